//! The `hierarchy` implementation on the GPU: its list against `cpu_walk` (the set of
//! clusters, each once, and every count word) on seeded random views; `cull_lod` after it
//! against `cull_lod` after `workgroup_per_instance` (the same cut, exactly); a full
//! queue that emits whole subtrees and still gives the same cut; a small capacity counted
//! like the flat fill's; instances behind the camera costing one node each; the typed
//! error of a graph that leaves the hierarchy unbound; and one large terrain instance
//! seen from near (its walk handed on over the spreading steps) and far, and with lists
//! too short for what is handed on.

mod support;

use glam::{Mat4, Vec3};
use meshlight_gpu_scene::gpu::elements;
use meshlight_gpu_scene::{Camera, Material, SceneData, data::Limits};
use meshlight_graph::*;
use meshlight_pass_fill_clusters::{
    FillClusters, HierarchyFill, HierarchyWalk, WalkParams, cpu_walk, hierarchy::MAX_STEPS,
};
use meshlight_scene::MeshletAsset;
use meshlight_shaders::cpu::layout::View;
use std::sync::OnceLock;
use support::run::{Cull, Frame, run_fill};
use support::scenes::{Views, bake};
use support::*;

/// A node the GPU and the reference decide differently must have a deciding value
/// within this relative distance of its threshold (f32 rounding, fused multiply-adds).
const NEAR_THRESHOLD: f32 = 1e-5;

/// The bunny and spot on a 4 × 3 field ([`support::scenes::bunny_and_spot`]).
fn scene() -> SceneData {
    support::scenes::bunny_and_spot()
}

/// Random views of the field, from within it to 48 bunny radii away.
const VIEWS: Views = support::scenes::BUNNY_AND_SPOT_VIEWS;

enum Fill {
    Flat,
    Hierarchy(HierarchyFill),
}

/// The walk at `threshold` (cull's), otherwise as by default.
fn walk_at(threshold: f32) -> Fill {
    Fill::Hierarchy(HierarchyFill {
        lod_threshold_px: threshold,
        ..HierarchyFill::default()
    })
}

/// Runs `fill` with a capacity of `slots` (and `cull` after it, with a raster list as
/// long) over a sentinel-filled list of `slots` and the guard.
fn run(data: &mut SceneData, view: &View, fill: Fill, cull: Option<f32>, slots: u32) -> Frame {
    let pass: Box<dyn Pass> = match fill {
        Fill::Flat => Box::new(FillClusters {
            capacity: Some(slots),
            instance_count: None,
            ..FillClusters::default()
        }),
        Fill::Hierarchy(pass) => Box::new(HierarchyFill {
            capacity: Some(slots),
            ..pass
        }),
    };
    let cull = cull.map(|threshold| Cull { threshold, slots });
    run_fill(data, view, pass, slots + GUARD, cull)
}

/// The view from `eye` to `target` (in bunny radii), near plane at 0.02 radii.
fn view_over(data: &SceneData, eye: Vec3, target: Vec3, fov: f32, viewport: [u32; 2]) -> View {
    let radius = data.meshes[0].bounding_sphere[3];
    Camera::perspective(eye * radius, target * radius, fov, radius * 0.02).view(viewport, 0, None)
}

/// Where each meshlet stands in the shared hierarchy cluster list.
fn list_positions(data: &SceneData) -> Vec<usize> {
    let mut at = vec![usize::MAX; data.meshlets.len()];
    for (k, &m) in data.hierarchy_clusters.iter().enumerate() {
        at[m as usize] = k;
    }
    at
}

/// The GPU's list against the reference: the same set, each cluster once, nothing past
/// it written; a cluster in one and not the other must lie below a node whose test was
/// within rounding of a threshold. Returns how many differed.
fn compare(data: &SceneData, reference: &HierarchyWalk, got: &Frame, label: &str) -> usize {
    let listed = got.listed();
    let gpu = set(listed);
    assert_eq!(gpu.len(), listed.len(), "{label}: a cluster written twice");
    assert!(
        got.list[listed.len()..].iter().all(|c| *c == SENTINEL),
        "{label}: a slot past the list was written"
    );
    let want = set(&reference.clusters);
    let positions = list_positions(data);
    let differing: Vec<(u32, u32)> = gpu.symmetric_difference(&want).copied().collect();
    for &(instance, meshlet) in &differing {
        let at = positions[meshlet as usize];
        let explained = reference.near_threshold.iter().any(|&(i, node)| {
            i == instance && data.hierarchy_nodes[node as usize].clusters().contains(&at)
        });
        assert!(
            explained,
            "{label}: cluster ({instance}, {meshlet}) listed differently, under no node near a threshold"
        );
    }
    if differing.is_empty() {
        assert_eq!(
            got.cluster_count,
            [reference.written, reference.requested],
            "{label}: count words"
        );
        assert_eq!(got.counts, reference.counts, "{label}: hierarchy counts");
    }
    differing.len()
}

#[test]
fn lists_equal_the_reference_on_random_views() {
    let mut data = scene();
    let (mut nodes, mut clusters, mut invisible) = (0, 0, 0);
    let mut differing = 0;
    for (v, view, threshold) in VIEWS.seeded(&data, 0x41e7_a7c4_0001, 12) {
        let params = WalkParams {
            lod_threshold_px: threshold,
            ..WalkParams::default()
        };
        let reference = cpu_walk(&data, &view, &params, NEAR_THRESHOLD);
        assert!(!reference.queue_full);
        let slots = reference.requested + 16;
        let got = run(&mut data, &view, walk_at(threshold), None, slots);
        let label = format!("view {v} (threshold {threshold})");
        differing += compare(&data, &reference, &got, &label);
        nodes += reference.counts[0];
        clusters += reference.requested;
        invisible += data.instances.len() - reference.visible_instances.len();
        eprintln!(
            "{label}: {} nodes tested, {} leaves, {} clusters listed, {} instances visible",
            got.counts[0],
            got.counts[1],
            got.cluster_count[1],
            reference.visible_instances.len()
        );
    }
    assert!(nodes > 0 && clusters > 0);
    assert!(invisible > 0, "no view culled an instance");
    assert!(differing <= 12, "{differing} clusters differed");
}

#[test]
fn after_cull_lod_the_cut_equals_the_flat_fills_cut() {
    let mut data = scene();
    let total: u32 = data.instances.iter().map(|i| i.meshlet_count).sum();
    let mut cut_sizes = Vec::new();
    for (v, view, threshold) in VIEWS.seeded(&data, 0x41e7_a7c4_0002, 8) {
        let flat = run(&mut data, &view, Fill::Flat, Some(threshold), total);
        let walk = run(&mut data, &view, walk_at(threshold), Some(threshold), total);
        let (want, got) = (flat.cut.unwrap(), walk.cut.unwrap());
        assert_eq!(
            got.len(),
            want.len(),
            "view {v}: cut of {} after the flat fill, {} after the walk",
            want.len(),
            got.len()
        );
        assert!(got == want, "view {v}: the cuts differ");
        assert!(walk.cluster_count[1] <= flat.cluster_count[1]);
        cut_sizes.push(want.len());
    }
    assert!(
        cut_sizes.iter().filter(|&&n| n > 0).count() >= 6,
        "{cut_sizes:?}"
    );
}

#[test]
fn a_full_queue_emits_whole_subtrees_and_keeps_the_cut() {
    let mut data = scene();
    // Close over the field: many leaves at several levels.
    let eye = Vec3::new(-1.0, 2.0, -1.0);
    let view = view_over(&data, eye, Vec3::new(5.0, 0.0, 4.0), 1.2, [1280, 720]);
    let threshold = 1.0;
    let total: u32 = data.instances.iter().map(|i| i.meshlet_count).sum();
    // No spreading step: every child that does not fit is emitted whole.
    let small = WalkParams {
        queue_capacity: 4,
        spread_steps: 0,
        ..WalkParams::default()
    };
    let pass = HierarchyFill {
        lod_threshold_px: threshold,
        queue_capacity: Some(4),
        spread_steps: 0,
        ..HierarchyFill::default()
    };
    whole_subtrees_keep_the_cut(&mut data, &view, &small, pass, total);
}

/// Runs `pass` (whose lists are as short as `short`'s) and checks what a full list
/// does: the reference fills it, subtrees that did not fit are emitted whole (counted,
/// each cluster once, a superset of the unlimited walk's list), nothing overflows, and
/// `cull_lod` after it finds the flat fill's cut exactly.
fn whole_subtrees_keep_the_cut(
    data: &mut SceneData,
    view: &View,
    short: &WalkParams,
    pass: HierarchyFill,
    total: u32,
) {
    let reference = cpu_walk(data, view, short, NEAR_THRESHOLD);
    assert!(reference.queue_full && reference.counts[2] > 0);
    let unlimited = cpu_walk(data, view, &WalkParams::default(), NEAR_THRESHOLD);
    let threshold = pass.lod_threshold_px;
    let got = run(data, view, Fill::Hierarchy(pass), Some(threshold), total);
    assert!(got.counts[2] > 0, "no subtree was emitted whole");
    assert_eq!(got.counts[3], 0);
    let listed = set(got.listed());
    assert_eq!(listed.len(), got.listed().len(), "a cluster written twice");
    // Emitting whole subtrees only adds: everything the unlimited walk lists is there.
    assert!(set(&unlimited.clusters).is_subset(&listed));
    assert!(listed.len() > unlimited.clusters.len());
    let flat = run(data, view, Fill::Flat, Some(threshold), total);
    assert!(got.cut.unwrap() == flat.cut.unwrap(), "the cuts differ");
}

#[test]
fn a_small_capacity_is_counted_like_the_flat_fill() {
    let mut data = scene();
    let eye = Vec3::new(-2.0, 3.0, -2.0);
    let view = view_over(&data, eye, Vec3::new(5.0, 0.0, 4.0), 1.0, [640, 360]);
    let reference = cpu_walk(&data, &view, &WalkParams::default(), NEAR_THRESHOLD);
    assert!(reference.near_threshold.is_empty());
    let capacity = reference.requested / 2 + 3;
    let got = run(
        &mut data,
        &view,
        Fill::Hierarchy(HierarchyFill::default()),
        None,
        capacity,
    );
    assert_eq!(got.cluster_count, [capacity, reference.requested]);
    let written = got.filled_to(capacity);
    assert_eq!(set(written).len(), written.len(), "a cluster written twice");
    assert!(set(written).is_subset(&set(&reference.clusters)));
    assert_eq!(got.counts, reference.counts);
}

#[test]
fn instances_behind_the_camera_cost_one_node_each() {
    let mut data = scene();
    // Looking away from the whole field.
    let eye = Vec3::new(-5.0, 1.0, -5.0);
    let view = view_over(&data, eye, Vec3::new(-20.0, 1.0, -20.0), 1.0, [640, 360]);
    let got = run(
        &mut data,
        &view,
        Fill::Hierarchy(HierarchyFill::default()),
        None,
        64,
    );
    assert_eq!(got.cluster_count, [0, 0]);
    assert_eq!(got.counts, [data.instances.len() as u32, 0, 0, 0]);
}

#[test]
fn a_graph_without_the_hierarchy_is_refused_naming_the_slot() {
    let data = scene();
    let Err(err) = compile_fill(&data, false, HierarchyFill::default()) else {
        panic!("a graph with the hierarchy unbound compiled");
    };
    let text = err.to_string();
    assert!(text.contains("hierarchy_nodes"), "{text}");
    // With them imported, the same graph compiles.
    compile_fill(&data, true, HierarchyFill::default()).unwrap();
    // A graph that imports them for other passes still compiles the flat fill, which
    // leaves the optional slots it does not read aside.
    compile_fill(&data, true, FillClusters::default()).unwrap();
}

/// Compiles `fill` alone over `data`'s imports, with the hierarchy's when `hierarchy`.
fn compile_fill(
    data: &SceneData,
    hierarchy: bool,
    fill: impl Pass + 'static,
) -> Result<CompiledGraph> {
    let mut g = GraphBuilder::new();
    meshlight_gpu_scene::gpu::import_for(data, &mut g);
    if hierarchy {
        meshlight_gpu_scene::gpu::import_hierarchy_for(data, &mut g);
    }
    g.create_buffer("clusters", BufferDesc::array(elements::CLUSTER, 64));
    g.create_buffer("cluster_count", BufferDesc::array(Element::U32, 2));
    let out = g.add_pass("fill", fill, Bindings::new())?;
    g.export(out.buffer("clusters")?);
    g.compile(&CompileOptions::new(wgpu::Features::empty()))
}

/// A terrain of 524,288 triangles: one instance whose walk, seen from nearby, is far
/// wider than one workgroup's chunk.
fn terrain() -> &'static MeshletAsset {
    static ASSET: OnceLock<MeshletAsset> = OnceLock::new();
    ASSET.get_or_init(|| {
        let terrain = meshlight_scene::Terrain {
            origin: glam::Vec2::splat(-50.0),
            size: 100.0,
            cells: 512,
            amplitude: 4.0,
            wavelength: 30.0,
            octaves: 4,
            seed: 7,
            uv_scale: 0.1,
            calm_centre: glam::Vec2::ZERO,
            calm_radius: 0.0,
        };
        bake(&terrain.mesh().unwrap())
    })
}

/// Just above the terrain's ground, looking along it: a wide walk.
fn terrain_near_view() -> View {
    Camera::perspective(
        Vec3::new(0.0, 1.5, -48.0),
        Vec3::new(0.0, 0.0, 20.0),
        1.0,
        0.05,
    )
    .view([1280, 720], 0, None)
}

fn terrain_scene() -> SceneData {
    let mut data = SceneData::new(Limits::default());
    let material = data
        .add_material(Material {
            base_color: [1.0; 3],
            ..Material::default()
        })
        .unwrap();
    let mesh = data.add_mesh("terrain", terrain()).unwrap();
    data.add_instance(mesh, Mat4::IDENTITY, material)
        .unwrap()
        .expect("an invertible transform");
    data
}

/// One large instance seen from just above its ground (its walk is wide: handed on over
/// the spreading steps) and from far away (a few nodes): the list and every counter equal
/// the reference's, equal those of the unspread walk (one workgroup), and `cull_lod`
/// after it finds the flat fill's cut exactly.
#[test]
fn one_large_instance_near_and_far_spreads_its_walk_and_keeps_the_cut() {
    let mut data = terrain_scene();
    let total = data.instances[0].meshlet_count;
    let threshold = 1.0;
    let views = [
        (
            "near",
            Vec3::new(0.0, 1.5, -48.0),
            Vec3::new(0.0, 0.0, 20.0),
        ),
        ("far", Vec3::new(0.0, 900.0, -900.0), Vec3::ZERO),
    ];
    let mut tested = Vec::new();
    for (label, eye, target) in views {
        let camera = Camera::perspective(eye, target, 1.0, 0.05);
        let view = camera.view([1280, 720], 0, None);
        let reference = cpu_walk(&data, &view, &WalkParams::default(), NEAR_THRESHOLD);
        assert!(!reference.queue_full, "{label}");
        let unspread = WalkParams {
            spread_steps: 0,
            ..WalkParams::default()
        };
        let single = cpu_walk(&data, &view, &unspread, NEAR_THRESHOLD);
        assert_eq!(
            single.counts, reference.counts,
            "{label}: counts depend on the split"
        );
        assert_eq!(set(&single.clusters), set(&reference.clusters), "{label}");
        eprintln!(
            "{label}: counts {:?}, handed on per step {:?}, rounds per step {:?} ({:?} without spreading), {} clusters listed",
            reference.counts,
            reference.handed_on,
            reference.rounds,
            single.rounds,
            reference.requested
        );
        let got = run(&mut data, &view, walk_at(threshold), Some(threshold), total);
        assert_eq!(compare(&data, &reference, &got, label), 0, "{label}");
        let one_group = HierarchyFill {
            lod_threshold_px: threshold,
            spread_steps: 0,
            ..HierarchyFill::default()
        };
        let alone = run(&mut data, &view, Fill::Hierarchy(one_group), None, total);
        assert_eq!(
            alone.counts, got.counts,
            "{label}: spread and unspread counts"
        );
        assert_eq!(set(alone.listed()), set(got.listed()), "{label}: lists");
        let flat = run(&mut data, &view, Fill::Flat, Some(threshold), total);
        let (want, cut) = (flat.cut.unwrap(), got.cut.unwrap());
        assert!(!want.is_empty(), "{label}: nothing in the cut");
        assert!(cut == want, "{label}: the cuts differ");
        tested.push((reference.counts[0], reference.handed_on.clone()));
    }
    let (near, far) = (&tested[0], &tested[1]);
    // Seen from nearby a frontier outgrows one chunk: the first step hands subtrees on.
    assert!(near.1[0] > 0, "near: {near:?}");
    // From afar it stays within one workgroup's chunk and costs a few nodes.
    assert!(far.1.iter().all(|&n| n == 0), "far: {far:?}");
    assert!(far.0 * 10 < near.0, "near {near:?}, far {far:?}");
}

/// Lists too short for what is handed on: the rest is emitted whole (counted), the
/// walk still ends, and the cut is the flat fill's.
#[test]
fn a_full_subtree_list_emits_whole_subtrees_and_keeps_the_cut() {
    let mut data = terrain_scene();
    let total = data.instances[0].meshlet_count;
    let short = WalkParams {
        subtree_capacity: 1,
        ..WalkParams::default()
    };
    let pass = HierarchyFill {
        lod_threshold_px: 1.0,
        subtree_capacity: Some(1),
        ..HierarchyFill::default()
    };
    whole_subtrees_keep_the_cut(&mut data, &terrain_near_view(), &short, pass, total);
}

/// Narrow frontiers and every spreading step: the near terrain's walk is handed on from
/// step to step (each step reading the list the one before wrote), and the list, the
/// counters and the cut are still the reference's and the flat fill's.
#[test]
fn a_walk_handed_on_over_every_step_keeps_the_reference_and_the_cut() {
    let mut data = terrain_scene();
    let total = data.instances[0].meshlet_count;
    let threshold = 1.0;
    let view = terrain_near_view();
    let params = WalkParams {
        queue_capacity: 16,
        spread_steps: MAX_STEPS,
        ..WalkParams::default()
    };
    let reference = cpu_walk(&data, &view, &params, NEAR_THRESHOLD);
    eprintln!(
        "narrow: counts {:?}, handed on per step {:?}, rounds per step {:?}",
        reference.counts, reference.handed_on, reference.rounds
    );
    assert!(!reference.queue_full);
    assert!(
        reference.handed_on.iter().filter(|&&n| n > 0).count() >= 2,
        "{:?}",
        reference.handed_on
    );
    let pass = HierarchyFill {
        lod_threshold_px: threshold,
        queue_capacity: Some(16),
        spread_steps: MAX_STEPS,
        ..HierarchyFill::default()
    };
    let got = run(
        &mut data,
        &view,
        Fill::Hierarchy(pass),
        Some(threshold),
        total,
    );
    assert_eq!(compare(&data, &reference, &got, "narrow"), 0);
    let flat = run(&mut data, &view, Fill::Flat, Some(threshold), total);
    assert!(got.cut.unwrap() == flat.cut.unwrap(), "the cuts differ");
}
