//! The CPU reference of the whole assignment — z_slice, the froxel walk, the prefix sum
//! and the lists — built from each stage's reference, so it does the GPU's f32
//! arithmetic in the GPU's order. Tests compare the GPU's lists with it as sets; the
//! benchmark measures it, single-threaded and with rayon, as the baseline.

use super::frame_graph::ClusteringSettings;
use meshlight::count_raster::KINDS;
use meshlight::count_raster::cpu::{CountResult, cpu_count};
use meshlight::populate::cpu::{ClusterLists, lists_from_counts};
use meshlight::shaders::cpu::froxel::{instance_froxels, view_object};
use meshlight::shaders::cpu::layout::{ClusterGrid, ClusterableObject, View};
use meshlight::z_slice::cpu::{Outcome, object_extent};
use meshlight::z_slice::{SliceInstance, ZSlice};
use rayon::prelude::*;

/// What the reference assigned.
#[derive(Clone, Debug)]
pub struct Assignment {
    /// The froxel grid of the view.
    pub grid: ClusterGrid,
    /// z_slice's pairs, in object order.
    pub instances: Vec<SliceInstance>,
    /// Every instance's walk (with each decision's closeness, for comparisons).
    pub counted: CountResult,
    /// Per froxel and kind, the objects whose test passed.
    pub lists: ClusterLists,
}

/// The grid `settings` gives over its viewport.
pub fn grid_of(settings: &ClusteringSettings) -> ClusterGrid {
    ZSlice {
        grid: settings.grid,
        ..ZSlice::default()
    }
    .grid(settings.viewport)
}

fn slices_of(
    view: &View,
    grid: &ClusterGrid,
    index: usize,
    object: &ClusterableObject,
) -> Vec<SliceInstance> {
    match object_extent(view, grid, object).outcome {
        Outcome::Visible { first, last } => (first..=last)
            .map(|slice| SliceInstance {
                object: index as u32,
                slice,
            })
            .collect(),
        _ => Vec::new(),
    }
}

/// The assignment on one thread.
pub fn cpu_assign(
    view: &View,
    settings: &ClusteringSettings,
    objects: &[ClusterableObject],
) -> Assignment {
    assign(view, settings, objects, slices, cpu_count)
}

/// The same assignment with the objects and instances spread over rayon's threads; the
/// counting and the lists (linear in the pairs) stay serial.
pub fn cpu_assign_parallel(
    view: &View,
    settings: &ClusteringSettings,
    objects: &[ClusterableObject],
) -> Assignment {
    assign(view, settings, objects, slices_parallel, count_parallel)
}

/// The assignment's stages in the GPU's order, the slicing and the counting done by
/// `slice` and `count` (serial or parallel); the lists follow from the counts alike.
fn assign(
    view: &View,
    settings: &ClusteringSettings,
    objects: &[ClusterableObject],
    slice: fn(&View, &ClusterGrid, &[ClusterableObject]) -> Vec<SliceInstance>,
    count: fn(&View, &ClusterGrid, &[ClusterableObject], &[SliceInstance]) -> CountResult,
) -> Assignment {
    let grid = grid_of(settings);
    let instances = slice(view, &grid, objects);
    let counted = count(view, &grid, objects, &instances);
    let lists = lists_from_counts(objects, &instances, &counted);
    Assignment {
        grid,
        instances,
        counted,
        lists,
    }
}

/// z_slice's pairs of every object, in object order, on one thread.
fn slices(view: &View, grid: &ClusterGrid, objects: &[ClusterableObject]) -> Vec<SliceInstance> {
    objects
        .iter()
        .enumerate()
        .flat_map(|(i, o)| slices_of(view, grid, i, o))
        .collect()
}

/// [`slices`] over rayon's threads (still in object order).
fn slices_parallel(
    view: &View,
    grid: &ClusterGrid,
    objects: &[ClusterableObject],
) -> Vec<SliceInstance> {
    objects
        .par_iter()
        .enumerate()
        .flat_map_iter(|(i, o)| slices_of(view, grid, i, o))
        .collect()
}

/// `cpu_count` with the walks spread over rayon's threads; the tally stays serial.
fn count_parallel(
    view: &View,
    grid: &ClusterGrid,
    objects: &[ClusterableObject],
    instances: &[SliceInstance],
) -> CountResult {
    let walked: Vec<_> = instances
        .par_iter()
        .map(|pair| {
            let o = view_object(view, &objects[pair.object as usize]);
            instance_froxels(view, grid, &o, pair.slice)
        })
        .collect();
    let mut counts = vec![0u32; (grid.cluster_count * KINDS) as usize];
    for (pair, froxels) in instances.iter().zip(&walked) {
        let kind = objects[pair.object as usize].kind;
        for froxel in froxels.touched() {
            counts[(froxel * KINDS + kind) as usize] += 1;
        }
    }
    CountResult {
        counts,
        instances: walked,
    }
}
