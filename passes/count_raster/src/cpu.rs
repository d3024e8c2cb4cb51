//! The reference of `count.wgsl`: the same rectangles and froxel tests
//! (`meshlight_shaders::cpu::froxel`), one instance after another.

use meshlight_pass_z_slice::SliceInstance;
use meshlight_shaders::cpu::froxel::{InstanceFroxels, instance_froxels, view_object};
use meshlight_shaders::cpu::layout::{ClusterGrid, ClusterableObject, View};

use crate::KINDS;

/// What [`cpu_count`] found.
#[derive(Clone, Debug, PartialEq)]
pub struct CountResult {
    /// `[froxel × 4 + kind]`.
    pub counts: Vec<u32>,
    /// Per instance, the froxels it walked and their decisions (for comparing with the
    /// GPU, which may decide a near pair otherwise).
    pub instances: Vec<InstanceFroxels>,
}

/// Counts `instances` (z_slice's written list) over `grid`.
pub fn cpu_count(
    view: &View,
    grid: &ClusterGrid,
    objects: &[ClusterableObject],
    instances: &[SliceInstance],
) -> CountResult {
    let mut counts = vec![0u32; (grid.cluster_count * KINDS) as usize];
    let walked = instances
        .iter()
        .map(|pair| {
            let object = &objects[pair.object as usize];
            let o = view_object(view, object);
            let froxels = instance_froxels(view, grid, &o, pair.slice);
            for froxel in froxels.touched() {
                counts[(froxel * KINDS + object.kind) as usize] += 1;
            }
            froxels
        })
        .collect();
    CountResult {
        counts,
        instances: walked,
    }
}
