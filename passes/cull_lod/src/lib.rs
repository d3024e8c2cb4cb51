//! Stage `cull_lod` (being built).
