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
    pub grid: ClusterGrid,
    /// z_slice's pairs, in object order.
    pub instances: Vec<SliceInstance>,
    /// Every instance's walk (with each decision's closeness, for comparisons).
    pub counted: CountResult,
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
    let grid = grid_of(settings);
    let instances: Vec<SliceInstance> = objects
        .iter()
        .enumerate()
        .flat_map(|(i, o)| slices_of(view, &grid, i, o))
        .collect();
    let counted = cpu_count(view, &grid, objects, &instances);
    let lists = lists_from_counts(objects, &instances, &counted);
    Assignment {
        grid,
        instances,
        counted,
        lists,
    }
}

/// The same assignment with the objects and instances spread over rayon's threads; the
/// counting and the lists (linear in the pairs) stay serial.
pub fn cpu_assign_parallel(
    view: &View,
    settings: &ClusteringSettings,
    objects: &[ClusterableObject],
) -> Assignment {
    let grid = grid_of(settings);
    let instances: Vec<SliceInstance> = objects
        .par_iter()
        .enumerate()
        .flat_map_iter(|(i, o)| slices_of(view, &grid, i, o))
        .collect();
    let walked: Vec<_> = instances
        .par_iter()
        .map(|pair| {
            let o = view_object(view, &objects[pair.object as usize]);
            instance_froxels(view, &grid, &o, pair.slice)
        })
        .collect();
    let mut counts = vec![0u32; (grid.cluster_count * KINDS) as usize];
    for (pair, froxels) in instances.iter().zip(&walked) {
        let kind = objects[pair.object as usize].kind;
        for froxel in froxels.touched() {
            counts[(froxel * KINDS + kind) as usize] += 1;
        }
    }
    let counted = CountResult {
        counts,
        instances: walked,
    };
    let lists = lists_from_counts(objects, &instances, &counted);
    Assignment {
        grid,
        instances,
        counted,
        lists,
    }
}
