//! meshlight: a GPU render-graph framework on wgpu.
//!
//! - [`graph`]: declare resources and passes, compile without a device, run on wgpu, dump.
//! - [`shaders`]: the shared WGSL library and the composer.
//! - [`scene`]: mesh loading, the meshlet LOD DAG builder and the asset format.
//! - [`scan_fan`]: GPU prefix sum (stage `scan_fan`: `scan_fan` and `two_step`).
//! - [`remap_dispatch`]: a GPU workgroup count as a 2-D indirect dispatch under the limit.
//! - [`demo`]: the built-in default-scene renderer used by `meshlight render`.

pub mod bench;
pub mod demo;

pub use meshlight_graph as graph;
pub use meshlight_pass_remap_dispatch as remap_dispatch;
pub use meshlight_pass_scan_fan as scan_fan;
pub use meshlight_scene as scene;
pub use meshlight_shaders as shaders;

/// Every stage implementation shipped with meshlight, for pipeline files.
pub fn registry() -> graph::file::Registry {
    let mut r = graph::file::Registry::new();
    scan_fan::register(&mut r);
    remap_dispatch::register(&mut r);
    r
}
