//! What the fill tests share: the sentinel guarding unwritten slots and cluster sets, the
//! scenes and views they draw, the graphs they run, with the common test helpers
//! (adapter, usage, baked meshes, seeded generator) re-exported.
#![allow(dead_code)]

pub mod graph;
pub mod lattice;
pub mod run;
pub mod scenes;

use meshlight_shaders::cpu::layout::Cluster;
use std::collections::BTreeSet;

/// What the GPU leaves in slots nothing may write.
pub const SENTINEL: Cluster = Cluster {
    instance: 0xdead_beef,
    meshlet: 0xfeed_f00d,
};

/// Slots after the capacity (or the list) that must keep the sentinel.
pub const GUARD: u32 = 64;

#[allow(unused_imports)] // not every test binary that includes this module uses each
pub use meshlight_testing::{
    Rng, USAGE, gpu,
    meshes::{bunny, spot},
};

pub fn set(clusters: &[Cluster]) -> BTreeSet<(u32, u32)> {
    clusters.iter().map(|c| (c.instance, c.meshlet)).collect()
}
