//! The reference of `populate.wgsl`: counts as `count_raster`'s reference gives them, an
//! exclusive prefix sum for the offsets, then each instance's froxels appended in
//! instance order (the GPU's order within a list is unspecified; compare as sets).

use meshlight_pass_count_raster::KINDS;
use meshlight_pass_count_raster::cpu::{CountResult, cpu_count};
use meshlight_pass_z_slice::SliceInstance;
use meshlight_shaders::cpu::layout::{ClusterGrid, ClusterableObject, View};

/// Every froxel's lists, in the contract's format.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ClusterLists {
    /// `[froxel × 4 + kind]`: where that list starts in `objects`.
    pub offsets: Vec<u32>,
    /// `[froxel × 4 + kind]`: the entries that list holds.
    pub counts: Vec<u32>,
    /// The lists back to back.
    pub objects: Vec<u32>,
    /// Entries all lists need; more than `objects.len()` when the capacity cut them.
    pub needed: u32,
}

impl ClusterLists {
    /// The objects of kind `kind` in froxel `froxel` (a `cluster_index`).
    pub fn list(&self, froxel: u32, kind: u32) -> &[u32] {
        let at = (froxel * KINDS + kind) as usize;
        // A list cut away entirely may start past the capacity.
        let start = (self.offsets[at] as usize).min(self.objects.len());
        &self.objects[start..start + self.counts[at] as usize]
    }

    /// Cuts the lists to `capacity` entries the way the GPU stage does: a list keeps the
    /// entries below the capacity.
    pub fn cut_to(&mut self, capacity: u32) {
        for (count, &offset) in self.counts.iter_mut().zip(&self.offsets) {
            *count = (*count).min(capacity - offset.min(capacity));
        }
        self.objects.truncate(capacity as usize);
    }
}

/// The lists from already counted instances.
pub fn lists_from_counts(
    objects: &[ClusterableObject],
    instances: &[SliceInstance],
    counted: &CountResult,
) -> ClusterLists {
    let mut offsets = Vec::with_capacity(counted.counts.len());
    let mut total = 0u32;
    for &c in &counted.counts {
        offsets.push(total);
        total += c;
    }
    let mut cursors = offsets.clone();
    let mut lists = vec![0u32; total as usize];
    for (pair, walked) in instances.iter().zip(&counted.instances) {
        let kind = objects[pair.object as usize].kind;
        for froxel in walked.touched() {
            let at = &mut cursors[(froxel * KINDS + kind) as usize];
            lists[*at as usize] = pair.object;
            *at += 1;
        }
    }
    ClusterLists {
        offsets,
        counts: counted.counts.clone(),
        objects: lists,
        needed: total,
    }
}

/// The lists of `instances` (z_slice's written list) over `grid`, cut to `capacity`.
pub fn cpu_populate(
    view: &View,
    grid: &ClusterGrid,
    objects: &[ClusterableObject],
    instances: &[SliceInstance],
    capacity: u32,
) -> (ClusterLists, CountResult) {
    let counted = cpu_count(view, grid, objects, instances);
    let mut lists = lists_from_counts(objects, instances, &counted);
    lists.cut_to(capacity);
    (lists, counted)
}
