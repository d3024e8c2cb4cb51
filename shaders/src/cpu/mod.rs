//! Rust references for the bit-exact encodings of the shared WGSL modules.
//!
//! The asset builder encodes with these functions and pass tests compare GPU output
//! against them, so each mirrors its WGSL counterpart operation for operation. [`rng`]
//! is the seeded generator the references and tests draw their inputs from.

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
