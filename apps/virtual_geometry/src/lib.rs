//! The virtual-geometry renderer: a GPU scene, the frame graph that draws it (the
//! shipped pipeline file `pipelines/virtual_geometry.toml`, embedded, or a caller's file,
//! with the settings applied by [`frame_graph::frame`]), and the frame loop that reads the
//! GPU's counters back and grows the cluster lists when a frame overflowed them.
//!
//! ```text
//! fill_clusters → cull_lod (first) → remap_dispatch → sw_raster → hw_raster
//!   → depth_pyramid (also next frame's history) → fill_clusters (second)
//!   → cull_lod (second) → remap_dispatch → sw_raster → hw_raster
//!   → the shadow cascades → light clustering → resolve
//! ```
//!
//! Two culling passes (occlusion, [`FrameSettings::occlusion`], on by default): the
//! first against last frame's depth pyramid, the second, over what the first found
//! hidden, against this frame's; see [`frame_graph`]. Off, one pass draws the LOD cut.
//! While occlusion culls too little to pay, frames leave the second pass out
//! ([`adaptive_occlusion`]).
//!
//! Nothing here decides what a pass does; the passes are the crates under `passes/`.
//! This crate only wires them, sizes what they share, and turns the counters into
//! numbers a person reads.

#![warn(missing_docs)]

pub mod adaptive_occlusion;
pub mod counts;
pub mod frame_graph;
pub mod gltf_scene;
pub mod renderer;
pub mod scenes;
pub mod settings;
pub mod setup;
pub mod shadows;
pub mod streaming;

pub use adaptive_occlusion::OcclusionPolicy;
pub use counts::FrameCounts;
pub use frame_graph::GraphSource;
pub use renderer::{Renderer, Still};
pub use settings::{FrameSettings, HostTargets, ShadowSettings};
pub use setup::{SceneOptions, SceneSetup, SetupError, setup};
