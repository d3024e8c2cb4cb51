//! Stage `resolve` (being built).
