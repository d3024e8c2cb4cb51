//! Rust mirrors of the shared WGSL modules: their struct layouts, encodings and tests.
//!
//! The GPU scene uploads through the layouts, and every pass's CPU reference is built on
//! the functions, which pass tests compare GPU output with; so each mirrors its WGSL
//! counterpart operation for operation, and each exists once. [`rng`] is the seeded
//! generator the references and tests draw their inputs from.

pub mod dispatch;
pub mod froxel;
pub mod layout;
pub mod light;
pub mod lod;
pub mod matrix;
pub mod occlusion;
pub mod octahedral;
pub mod rng;
pub mod visbuffer;
