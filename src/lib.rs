//! meshlight: a GPU render-graph framework on wgpu.
//!
//! - [`graph`]: declare resources and passes, compile without a device, run on wgpu, dump.
//! - [`shaders`]: the shared WGSL library and the composer.
//! - [`scene`]: mesh loading, the meshlet LOD DAG builder and the asset format.
//! - [`gpu_scene`]: assets packed into shared GPU buffers, instances, materials, the view.
//! - [`stream`]: geometry streaming's policy: pages, the cut over resident pages, the
//!   streamer and its reader threads.
//! - The virtual-geometry stages: [`fill_clusters`], [`cull_lod`], [`remap_dispatch`],
//!   [`sw_raster`], [`hw_raster`], [`depth_pyramid`], [`resolve`]; [`brute_force`] is the
//!   baseline they are measured against; [`present`] draws the image into a host's
//!   target.
//! - [`scan_fan`]: GPU prefix sum (stage `scan_fan`: `scan_fan`, `two_step`,
//!   `decoupled_lookback`).
//! - Light clustering: [`z_slice`], [`count_raster`], [`populate`] (with [`scan_fan`]
//!   between them).
//! - [`registry()`]: every shipped implementation of every stage, for pipeline files and
//!   for frames built in code.
//!
//! This crate is the library and nothing else. The renderers that wire the stages into
//! frames are crates of their own beside the applications, under `apps/`:
//! `meshlight-virtual-geometry` (the frame loop, its scenes and counters) and
//! `meshlight-light-clustering` (the clustering's graph, its overflow growth and the CPU
//! reference); `meshlight-cli` is the `meshlight` command, `meshlight-viewer` the live
//! window and `meshlight-bench` the benchmark scenarios.

#![warn(missing_docs)]

pub mod still;

pub use meshlight_gpu_scene as gpu_scene;
pub use meshlight_graph as graph;
pub use meshlight_pass_brute_force as brute_force;
pub use meshlight_pass_count_raster as count_raster;
pub use meshlight_pass_cull_lod as cull_lod;
pub use meshlight_pass_depth_pyramid as depth_pyramid;
pub use meshlight_pass_fill_clusters as fill_clusters;
pub use meshlight_pass_hw_raster as hw_raster;
pub use meshlight_pass_populate as populate;
pub use meshlight_pass_present as present;
pub use meshlight_pass_remap_dispatch as remap_dispatch;
pub use meshlight_pass_resolve as resolve;
pub use meshlight_pass_scan_fan as scan_fan;
pub use meshlight_pass_sw_raster as sw_raster;
pub use meshlight_pass_z_slice as z_slice;
pub use meshlight_scene as scene;
pub use meshlight_shaders as shaders;
pub use meshlight_stream as stream;
/// The crates meshlight's API speaks in, at the versions it was built with: a user needs
/// no dependency of their own on them (and cannot get a second, mismatched copy).
pub use {bytemuck, glam, wgpu};

/// Each stage crate's `register`, in the order their implementations enter the registry.
const REGISTERS: [fn(&mut graph::file::Registry); 13] = [
    scan_fan::register,
    remap_dispatch::register,
    fill_clusters::register,
    cull_lod::register,
    sw_raster::register,
    hw_raster::register,
    resolve::register,
    depth_pyramid::register,
    brute_force::register,
    z_slice::register,
    count_raster::register,
    populate::register,
    present::register,
];

/// Every stage implementation shipped with meshlight, for pipeline files.
pub fn registry() -> graph::file::Registry {
    let mut r = graph::file::Registry::new();
    for register in REGISTERS {
        register(&mut r);
    }
    r
}
