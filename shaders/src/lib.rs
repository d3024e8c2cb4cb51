//! The shared WGSL library of meshlight and the composer that assembles pass shaders.
//!
//! Every stage of the renderer is its own pass crate with its own WGSL entry points, but
//! the data those passes exchange (the view, meshlets, instances, the visibility buffer,
//! clusterable lights) must have exactly one layout. That layout lives here, as naga_oil
//! modules (`#import meshlight::view`, …), so a pass cannot drift from its neighbours.
//!
//! [`ShaderLibrary`] holds a naga_oil composer with every shared module added once;
//! [`ShaderLibrary::compose`] turns a [`PassShader`] plus typed [`ShaderDef`]s into a
//! validated `naga::Module` ready for `wgpu::ShaderSource::Naga`.
//!
//! [`cpu`] mirrors the shared WGSL in Rust (layouts, visibility packing, octahedral
//! normals, the LOD and occlusion tests, the depth pyramid), so every pass's CPU
//! reference builds on one copy of each.

#![warn(missing_docs)]

pub mod cpu;
mod defs;
mod error;
mod library;
mod modules;
mod uniform;

pub use defs::{ShaderDef, ShaderDefs};
pub use error::ShaderError;
pub use library::{LocalModule, PassShader, ShaderLibrary, validate};
pub use modules::{SharedModule, shared_modules};

/// Re-exported so callers name capabilities without depending on naga themselves.
pub use naga::valid::Capabilities;
