//! meshlight
