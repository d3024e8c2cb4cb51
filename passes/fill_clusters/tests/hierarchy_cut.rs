//! The hierarchy walk on the CPU: `cull_lod`'s reference finds exactly the same LOD cut
//! after the walk's list as after the flat list, on seeded random views (near, far,
//! inside the field of instances, every threshold) of the Stanford bunny and of the
//! procedural mesh; the walk lists each cluster once and far fewer than the flat fill;
//! the comparison does notice a walk that drops clusters of the cut; and on the bunny
//! lattice of the benchmarks, clusters + nodes tested stay within 3× the cut.

mod support;

use glam::Vec3;
use meshlight_gpu_scene::SceneData;
use meshlight_pass_cull_lod::{Thresholds, cpu_cull};
use meshlight_pass_fill_clusters::{WalkParams, cpu_fill, cpu_walk};
use meshlight_scene::{MeshletAsset, procedural_mesh};
use std::collections::BTreeSet;
use std::sync::OnceLock;
use support::lattice::lattice;
use support::scenes::{Views, bake, field};
use support::*;

fn procedural() -> &'static MeshletAsset {
    static ASSET: OnceLock<MeshletAsset> = OnceLock::new();
    ASSET.get_or_init(|| bake(&procedural_mesh(40)))
}

/// A 4 × 4 field of `asset`, three mesh radii apart, turned, scaled (one unevenly) and
/// lifted differently, so instances are near and far from any camera among them.
fn field_of(asset: &MeshletAsset) -> SceneData {
    field(&[("mesh", asset)], 16, |i| {
        let scale = if i == 5 {
            Vec3::new(1.6, 0.6, 1.0)
        } else {
            Vec3::splat(0.6 + 0.1 * (i % 7) as f32)
        };
        let (x, z) = ((i % 4) as f32, (i / 4) as f32);
        let position = Vec3::new(x * 3.0, (i % 3) as f32 * 0.4, z * 3.0);
        (scale, i as f32 * 0.9, position)
    })
}

/// Random views of the field: from inside it to 60 mesh radii away, at every threshold.
const VIEWS: Views = Views {
    target: [Vec3::new(-1.0, -0.5, -1.0), Vec3::new(10.0, 1.5, 10.0)],
    lowest: -0.4,
    distance: [0.3, 200.0],
    viewports: &[[320, 240], [1280, 720], [2240, 1260]],
    fov: [0.4, 1.6],
    thresholds: &[0.5, 1.0, 2.0, 4.0],
};

/// Per view: the flat list and the walk's, each through `cpu_cull`; the cuts must be
/// equal. Returns (flat clusters, walk clusters + nodes, cut clusters) over all views.
fn compare_cuts(name: &str, data: &SceneData, seed: u64, views: u32) -> [usize; 3] {
    let mut totals = [0usize; 3];
    let mut levels_in_cuts = BTreeSet::new();
    for (v, view, threshold) in VIEWS.seeded(data, seed, views) {
        let t = Thresholds {
            lod_threshold_px: threshold,
            ..Thresholds::default()
        };
        let flat = cpu_fill(data, &view, u32::MAX);
        let want = cpu_cull(data, &view, &flat.clusters, &t, u32::MAX);
        let params = WalkParams {
            lod_threshold_px: threshold,
            ..WalkParams::default()
        };
        let walk = cpu_walk(data, &view, &params, 0.0);
        assert!(!walk.queue_full && walk.counts[3] == 0, "{name} view {v}");
        let listed = set(&walk.clusters);
        assert_eq!(
            listed.len(),
            walk.clusters.len(),
            "{name} view {v}: a cluster listed twice"
        );
        let got = cpu_cull(data, &view, &walk.clusters, &t, u32::MAX);
        let (want_cut, got_cut) = (set(&want.cut), set(&got.cut));
        let missing: Vec<_> = want_cut.difference(&got_cut).take(5).collect();
        assert!(
            want_cut == got_cut,
            "{name} view {v} (threshold {threshold}): cut of {} clusters, the walk's {}; missing {missing:?}",
            want_cut.len(),
            got_cut.len()
        );
        for c in &want.cut {
            levels_in_cuts.insert(data.meshlets[c.meshlet as usize].level());
        }
        totals[0] += flat.clusters.len();
        totals[1] += walk.clusters.len() + walk.counts[0] as usize;
        totals[2] += want.cut.len();
    }
    eprintln!(
        "{name}: {views} views, flat list {} clusters, walk {} clusters + nodes, cut {}; cut levels {levels_in_cuts:?}",
        totals[0], totals[1], totals[2]
    );
    assert!(
        levels_in_cuts.len() >= 4,
        "{name}: the views reach only levels {levels_in_cuts:?}"
    );
    totals
}

/// On 60 random views of a field of `asset`, the cuts are equal and the walk tests under a
/// third of what the flat fill lists.
fn same_cut_for_a_third_of_the_tests(name: &str, asset: &MeshletAsset, seed: u64) {
    let data = field_of(asset);
    let [flat, walk, cut] = compare_cuts(name, &data, seed, 60);
    assert!(cut > 0);
    assert!(
        walk * 3 < flat,
        "the walk tests {walk} clusters + nodes, the flat list {flat}"
    );
}

#[test]
fn the_walk_and_the_flat_list_give_the_same_cut_on_random_views_of_the_bunny() {
    same_cut_for_a_third_of_the_tests("bunny", bunny(), 0xb0_0b1e5);
}

#[test]
fn the_walk_and_the_flat_list_give_the_same_cut_on_random_views_of_the_procedural_mesh() {
    same_cut_for_a_third_of_the_tests("procedural", procedural(), 0x9e0_3e7c);
}

/// The comparison above notices a walk that loses clusters of the cut: with a threshold
/// other than cull's, the walk prunes what cull would keep, and the cuts differ.
#[test]
fn a_walk_with_another_threshold_than_cull_loses_clusters_of_the_cut() {
    let data = field_of(bunny());
    let mut differing = 0;
    for (_, view, threshold) in VIEWS.seeded(&data, 0x5eed_0002, 20) {
        let t = Thresholds {
            lod_threshold_px: threshold,
            ..Thresholds::default()
        };
        let want = set(&cpu_cull(
            &data,
            &view,
            &cpu_fill(&data, &view, u32::MAX).clusters,
            &t,
            u32::MAX,
        )
        .cut);
        for factor in [0.5, 2.0] {
            let params = WalkParams {
                lod_threshold_px: threshold * factor,
                ..WalkParams::default()
            };
            let walk = cpu_walk(&data, &view, &params, 0.0);
            let got = set(&cpu_cull(&data, &view, &walk.clusters, &t, u32::MAX).cut);
            assert!(got.is_subset(&want));
            differing += usize::from(got != want);
        }
    }
    assert!(
        differing >= 10,
        "only {differing} of 40 walks lost clusters"
    );
}

/// The virtual-geometry benchmark's scene: 15³ bunnies in a lattice 2.5 mesh radii
/// apart, seen from outside one corner at 2240×1260 (`scenes::lattice`), threshold 1 px.
#[test]
fn on_the_bunny_lattice_clusters_and_nodes_tested_stay_within_three_times_the_cut() {
    let (data, view) = lattice(bunny(), 15);
    let t = Thresholds::default();
    let flat = cpu_fill(&data, &view, u32::MAX);
    let want = cpu_cull(&data, &view, &flat.clusters, &t, u32::MAX);
    let walk = cpu_walk(&data, &view, &WalkParams::default(), 0.0);
    let got = cpu_cull(&data, &view, &walk.clusters, &t, u32::MAX);
    assert_eq!(set(&want.cut), set(&got.cut));
    let tested = walk.clusters.len() + walk.counts[0] as usize;
    let cut = want.cut.len();
    eprintln!(
        "bunny lattice 15³ at 2240x1260: cut {cut} clusters; flat fill lists {} (cull tests {}); \
         the walk tests {} nodes and lists {} clusters ({} leaves), {tested} in all = {:.2}x the cut; \
         rounds per step {:?}, subtrees handed on per step {:?}",
        flat.clusters.len(),
        flat.clusters.len(),
        walk.counts[0],
        walk.clusters.len(),
        walk.counts[1],
        tested as f64 / cut as f64,
        walk.rounds,
        walk.handed_on
    );
    assert!(!walk.queue_full);
    assert!(
        tested <= 3 * cut,
        "{tested} clusters + nodes tested for a cut of {cut}"
    );
}

/// How the walk is split does not change what it tests or lists: with no spreading
/// step, the default one, or every step with narrow frontiers (so subtrees are handed on
/// from step to step), the counts and the clusters are the same, while the narrow split
/// really hands subtrees on.
#[test]
fn the_walk_tests_and_lists_the_same_however_it_is_spread() {
    let data = field_of(bunny());
    let mut handed_on = 0;
    for (v, view, threshold) in VIEWS.seeded(&data, 0x5b1e_ad00, 24) {
        let walk = |spread_steps: u32, queue_capacity: u32| {
            let params = WalkParams {
                lod_threshold_px: threshold,
                spread_steps,
                queue_capacity,
                ..WalkParams::default()
            };
            cpu_walk(&data, &view, &params, 0.0)
        };
        let alone = walk(0, 1024);
        let default = walk(WalkParams::default().spread_steps, 1024);
        let narrow = walk(4, 16);
        for (label, w) in [("default", &default), ("narrow", &narrow)] {
            assert!(!w.queue_full, "view {v} {label}");
            assert_eq!(w.counts, alone.counts, "view {v} {label}");
            assert_eq!(set(&w.clusters), set(&alone.clusters), "view {v} {label}");
            assert_eq!(w.clusters.len(), alone.clusters.len(), "view {v} {label}");
        }
        handed_on += narrow.handed_on.iter().sum::<u32>();
    }
    assert!(handed_on > 0, "no view handed a subtree on");
}
