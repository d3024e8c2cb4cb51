//! `z_slice` on the GPU against `cpu_z_slice`: seeded random scenes of every object kind
//! under perspective and orthographic views, compared as (object, slice) sets (list
//! order follows the atomics), with the count words, the draw and dispatch arguments, the
//! published grid, and a guard of sentinels past the list; lights that contain the camera,
//! straddle near and far, sit behind it, are huge, tiny, infinite or invalid; zero
//! objects; an overflowing list.

use glam::Vec3;
use meshlight_graph::*;
use meshlight_pass_z_slice::cpu::{
    self, Outcome, WORD_CAPACITY, WORD_CULLED, WORD_INVALID, WORD_REQUESTED, WORD_VISIBLE,
};
use meshlight_pass_z_slice::scenes::{
    Rng, object, orthographic, perspective, random_camera, random_objects, spot,
};
use meshlight_pass_z_slice::testbed::{Sliced, USAGE, WALK_INPUTS, read, run_frame};
use meshlight_pass_z_slice::{SLICE_INSTANCE, SliceInstance, ZSlice, cpu_z_slice};
use meshlight_shaders::cpu::layout::{ClusterGrid, ClusterableKind, ClusterableObject, View};
use std::collections::BTreeSet;

/// What the GPU leaves in entries nothing may write.
const SENTINEL: SliceInstance = SliceInstance {
    object: 0xdead_beef,
    slice: 0xfeed_f00d,
};
/// Entries after the list that must keep the sentinel.
const GUARD: u32 = 32;
/// Words of the `cluster_counts` buffer `prepare` must zero (filled with garbage first).
const FROXEL_COUNT_WORDS: u64 = 64 * 70 + 3;
/// A pair the GPU and the reference decide differently must belong to an object whose
/// deciding value lies within this relative distance of its threshold.
const NEAR_THRESHOLD: f32 = 1e-5;
/// At most this many such pairs per scene.
const MAX_NEAR_PER_SCENE: usize = 4;

use meshlight_testing::executor;

struct GpuSlices {
    /// The whole list: `capacity` entries, then the guard.
    list: Vec<SliceInstance>,
    counts: [u32; cpu::COUNT_WORDS],
    draw_args: [u32; 4],
    dispatch_args: [u32; 3],
    grid: ClusterGrid,
}

impl GpuSlices {
    fn written(&self) -> &[SliceInstance] {
        let n = self.counts[WORD_REQUESTED].min(self.counts[WORD_CAPACITY]);
        &self.list[..n as usize]
    }
}

/// Runs the pass once over `objects` (`count` of them valid) with a list of `entries`
/// sentinel entries.
fn run(
    objects: &[ClusterableObject],
    count: u32,
    view: &View,
    pass: ZSlice,
    entries: u32,
) -> GpuSlices {
    let mut g = GraphBuilder::new();
    let instances = g.import_buffer(
        "slice_instances",
        BufferDesc::array(SLICE_INSTANCE, entries as u64),
        USAGE,
    );
    // Not a multiple of the workgroup: every word, the last ones too, must be zeroed.
    let froxel_counts = g.import_buffer(
        "cluster_counts",
        BufferDesc::array(Element::U32, FROXEL_COUNT_WORDS),
        USAGE,
    );
    let sliced = Sliced::add(&mut g, pass, objects.len(), instances, froxel_counts).unwrap();
    sliced.export(&mut g, &WALK_INPUTS).unwrap();
    let mut exec = executor();
    let list_buffer = exec.gpu.buffer_with_data(
        "slice_instances",
        bytemuck::cast_slice(&vec![SENTINEL; entries as usize]),
        USAGE,
    );
    let froxel_count_buffer = exec.gpu.buffer_with_data(
        "cluster_counts",
        bytemuck::cast_slice(&vec![0xdead_beef_u32; FROXEL_COUNT_WORDS as usize]),
        USAGE,
    );
    let imports = Imports::new()
        .buffer("slice_instances", &list_buffer)
        .buffer("cluster_counts", &froxel_count_buffer);
    run_frame(&mut exec, g, objects, count, view, imports).unwrap();
    let counts: Vec<u32> = read(&mut exec, "slice_counts");
    let draw_args: Vec<u32> = read(&mut exec, "slice_draw_args");
    let dispatch_args: Vec<u32> = read(&mut exec, "slice_dispatch_args");
    let grid: Vec<ClusterGrid> = read(&mut exec, "cluster_grid");
    let whole = |buffer: &wgpu::Buffer| exec.gpu.read_buffer(buffer, 0, buffer.size()).unwrap();
    let list: Vec<SliceInstance> = bytemuck::pod_collect_to_vec(&whole(&list_buffer));
    let froxel_counts: Vec<u32> = bytemuck::pod_collect_to_vec(&whole(&froxel_count_buffer));
    assert!(
        froxel_counts.iter().all(|&w| w == 0),
        "prepare left words of cluster_counts unzeroed"
    );
    GpuSlices {
        list,
        counts: counts[..cpu::COUNT_WORDS].try_into().unwrap(),
        draw_args: draw_args[..4].try_into().unwrap(),
        dispatch_args: dispatch_args[..3].try_into().unwrap(),
        grid: grid[0],
    }
}

/// Compares the GPU's outputs with the reference; a pair decided differently must belong
/// to an object within `NEAR_THRESHOLD` of a threshold. Returns how many pairs did.
fn compare(
    view: &View,
    pass: &ZSlice,
    objects: &[ClusterableObject],
    capacity: u32,
    got: &GpuSlices,
    label: &str,
) -> usize {
    let [w, h] = view.viewport_size;
    let grid = pass.grid([w as u32, h as u32]);
    assert_eq!(got.grid, grid, "{label}: the published grid");
    let limit = pass.max_per_dimension.unwrap_or(65535);
    let reference = cpu_z_slice(view, &grid, objects, capacity, pass.quad_vertices, limit);
    assert_eq!(
        got.counts[WORD_CAPACITY], capacity,
        "{label}: capacity word"
    );
    let written = got.counts[WORD_REQUESTED].min(capacity);
    assert_eq!(
        got.draw_args,
        [pass.quad_vertices, written, 0, 0],
        "{label}: draw arguments"
    );
    assert_eq!(
        got.dispatch_args,
        cpu::fold_dispatch(written.div_ceil(cpu::INSTANCES_PER_GROUP), limit),
        "{label}: dispatch arguments"
    );
    assert!(
        got.list[written as usize..].iter().all(|e| *e == SENTINEL),
        "{label}: an entry past the instances written (or past the capacity) was written"
    );
    let mine = got.written();
    assert!(
        !mine.contains(&SENTINEL),
        "{label}: an entry below the count left unwritten"
    );
    let gpu_set: BTreeSet<SliceInstance> = mine.iter().copied().collect();
    assert_eq!(gpu_set.len(), mine.len(), "{label}: a pair written twice");
    // Each object's slices are contiguous and ascending in the list.
    for pair in mine.windows(2) {
        if pair[0].object == pair[1].object {
            assert_eq!(pair[1].slice, pair[0].slice + 1, "{label}: {pair:?}");
        }
    }
    let want: BTreeSet<SliceInstance> = reference.pairs.iter().copied().collect();
    let overflowed = got.counts[WORD_REQUESTED] > capacity;
    let differing: Vec<SliceInstance> = if overflowed {
        // Past the capacity the atomics choose which objects got entries.
        gpu_set.difference(&want).copied().collect()
    } else {
        gpu_set.symmetric_difference(&want).copied().collect()
    };
    for pair in &differing {
        let e = cpu::object_extent(view, &grid, &objects[pair.object as usize]);
        let closeness = e.closeness(&grid);
        let on_gpu: Vec<u32> = mine
            .iter()
            .filter(|p| p.object == pair.object)
            .map(|p| p.slice)
            .collect();
        assert!(
            closeness < NEAR_THRESHOLD,
            "{label}: pair {pair:?} decided differently (GPU slices {on_gpu:?}), {closeness} from a threshold: {e:?}"
        );
    }
    if differing.is_empty() && !overflowed {
        assert_eq!(got.counts, reference.counts, "{label}: counts");
    } else {
        // Invalid objects are decided by bits alone.
        assert_eq!(got.counts[WORD_INVALID], reference.counts[WORD_INVALID]);
    }
    differing.len()
}

/// Runs `pass` over all of `objects` with a list of its capacity and the guard after it,
/// and compares the outputs with the reference: what every test of a whole scene does.
/// Returns the outputs and how many pairs were decided near a threshold.
fn run_compared(
    objects: &[ClusterableObject],
    view: &View,
    pass: ZSlice,
    label: &str,
) -> (GpuSlices, usize) {
    let capacity = pass
        .capacity
        .expect("a capacity param, for the guard to lie past it");
    let got = run(objects, objects.len() as u32, view, pass, capacity + GUARD);
    let near = compare(view, &pass, objects, capacity, &got, label);
    (got, near)
}

fn pass_with(capacity: u32) -> ZSlice {
    ZSlice {
        capacity: Some(capacity),
        ..ZSlice::default()
    }
}

/// [`pass_with`] under a per-dimension dispatch limit of `max_per_dimension`.
fn limited_pass(capacity: u32, max_per_dimension: u32) -> ZSlice {
    ZSlice {
        max_per_dimension: Some(max_per_dimension),
        ..pass_with(capacity)
    }
}

#[test]
fn random_scenes_of_every_kind_match_the_reference() {
    let mut rng = Rng(0x5eed_0123_4567_89ab);
    let mut near_total = 0;
    let mut visible_per_kind = [0u32; 4];
    let (mut culled, mut multi_slice, mut orthographic_scenes) = (0, 0, 0);
    for scene in 0..8 {
        let ortho = scene % 2 == 1;
        let (camera, target) = random_camera(&mut rng, ortho);
        let viewport = [[320, 180], [256, 256], [640, 360]][rng.below(3) as usize];
        let view = camera.view(viewport, scene, None);
        let objects = random_objects(&mut rng, 300, target, 80.0);
        let capacity = 300 * 40;
        let pass = ZSlice {
            grid: meshlight_pass_z_slice::GridSettings {
                dims: [16, 9, [24, 8, 32, 1][scene as usize % 4]],
                first_slice_end: [5.0, 1.0, 0.5][rng.below(3) as usize],
                far: [100.0, 1000.0][rng.below(2) as usize],
            },
            quad_vertices: [4, 6][rng.below(2) as usize],
            ..pass_with(capacity)
        };
        let label = format!(
            "scene {scene} ({}, {viewport:?}, {:?})",
            if ortho { "ortho" } else { "perspective" },
            pass.grid
        );
        let (got, near) = run_compared(&objects, &view, pass, &label);
        assert!(
            near <= MAX_NEAR_PER_SCENE,
            "{label}: {near} pairs near a threshold"
        );
        near_total += near;
        orthographic_scenes += ortho as u32;
        culled += got.counts[WORD_CULLED];
        for (k, v) in visible_per_kind.iter_mut().enumerate() {
            *v += got.counts[WORD_VISIBLE + k];
        }
        let [w, h] = view.viewport_size;
        let grid = pass.grid([w as u32, h as u32]);
        multi_slice += objects
            .iter()
            .filter(|o| {
                matches!(cpu::object_extent(&view, &grid, o).outcome, Outcome::Visible { first, last } if last > first)
            })
            .count();
        eprintln!("{label}: counts {:?} near {near}", got.counts);
    }
    // The scenes exercise every outcome.
    assert!(
        visible_per_kind.iter().all(|&v| v > 0),
        "{visible_per_kind:?}"
    );
    assert!(culled > 0 && multi_slice > 0 && orthographic_scenes > 0);
    eprintln!("pairs decided differently from the reference, near a threshold: {near_total}");
}

/// The first and last slice of an object, or none.
type Slices = Option<(u32, u32)>;

/// Hand-placed cases with known slices under a camera at the origin looking down −z.
#[test]
fn special_objects_get_the_slices_they_must() {
    let camera = perspective(Vec3::ZERO, Vec3::new(0.0, 0.0, -1.0), 1.2);
    let view = camera.view([320, 180], 0, None);
    let pass = ZSlice::default();
    let grid = pass.grid([320, 180]);
    let last = grid.dims[2] - 1;
    let at = |z: f32| Vec3::new(0.0, 0.0, -z);
    let p = ClusterableKind::PointLight;
    let mut nan_position = object(p, at(10.0), 1.0);
    nan_position.position_range[0] = f32::NAN;
    let mut unknown_kind = object(p, at(10.0), 1.0);
    unknown_kind.kind = 7;
    let cases: Vec<(&str, ClusterableObject, Slices)> = vec![
        (
            "containing the camera",
            object(p, at(0.0), 3.0),
            Some((0, 0)),
        ),
        (
            "containing the camera, reaching past 5 m",
            object(p, at(1.0), 20.0),
            Some((0, 7)),
        ),
        (
            "straddling near and far",
            object(p, at(500.0), 600.0),
            Some((0, last)),
        ),
        (
            "infinite",
            object(p, at(30.0), f32::INFINITY),
            Some((0, last)),
        ),
        ("huge", object(p, at(30.0), 1e35), Some((0, last))),
        (
            "beyond far",
            object(p, at(5000.0), 10.0),
            Some((last, last)),
        ),
        ("tiny", object(p, at(10.0), 1e-6), Some((4, 4))),
        ("behind the camera", object(p, at(-10.0), 3.0), None),
        (
            "off to the side",
            object(p, Vec3::new(100.0, 0.0, -10.0), 3.0),
            None,
        ),
        ("range 0", object(p, at(10.0), 0.0), None),
        ("range -0", object(p, at(10.0), -0.0), None),
        (
            "spot pointing away, behind",
            spot(at(-0.5), Vec3::Z, 50.0, 0.3),
            None,
        ),
        (
            "spot between the camera and the near plane, pointing back",
            spot(at(0.05), Vec3::Z, 5.0, 0.3),
            None,
        ),
        (
            "spot pointing forward from behind",
            spot(at(-0.5), -Vec3::Z, 50.0, 0.3),
            Some((0, 10)),
        ),
        (
            "probe straddling 5 m",
            object(ClusterableKind::Probe, at(5.0), 1.0),
            Some((0, 1)),
        ),
        (
            "decal facing the camera",
            {
                let mut o = object(ClusterableKind::Decal, at(10.0), 1.0);
                o.direction_cos_angle = [0.0, 0.0, 1.0, 1.0];
                o
            },
            Some((3, 4)),
        ),
        ("NaN position", nan_position, None),
        ("NaN range", object(p, at(10.0), f32::NAN), None),
        ("negative range", object(p, at(10.0), -1.0), None),
        ("unknown kind", unknown_kind, None),
        (
            "spot with no direction",
            spot(at(10.0), Vec3::ZERO, 5.0, 0.3),
            None,
        ),
    ];
    let invalid = 5;
    let objects: Vec<ClusterableObject> = cases.iter().map(|c| c.1).collect();
    // The expected slices, from the grid: checked against the reference first.
    for (i, (name, o, want)) in cases.iter().enumerate() {
        let outcome = cpu::object_extent(&view, &grid, o).outcome;
        match (want, outcome) {
            (Some((a, b)), Outcome::Visible { first, last }) => {
                assert_eq!((first, last), (*a, *b), "{name}")
            }
            (None, Outcome::Invalid) => assert!(i >= cases.len() - invalid, "{name}"),
            (None, Outcome::Culled) => assert!(i < cases.len() - invalid, "{name}"),
            _ => panic!("{name}: {outcome:?}, expected {want:?}"),
        }
    }
    let (got, near) = run_compared(&objects, &view, pass_with(1000), "special");
    assert_eq!(near, 0);
    assert_eq!(got.counts[WORD_INVALID], invalid as u32);
    assert_eq!(got.counts[WORD_CULLED], 6);
    let pairs: BTreeSet<SliceInstance> = got.written().iter().copied().collect();
    for (i, (name, _, want)) in cases.iter().enumerate() {
        let slices: Vec<u32> = pairs
            .iter()
            .filter(|p| p.object == i as u32)
            .map(|p| p.slice)
            .collect();
        let expected: Vec<u32> = want.map(|(a, b)| (a..=b).collect()).unwrap_or_default();
        assert_eq!(slices, expected, "{name}");
    }
}

#[test]
fn zero_objects_write_nothing_and_empty_arguments() {
    let camera = perspective(Vec3::new(0.0, 2.0, 10.0), Vec3::ZERO, 1.0);
    let view = camera.view([320, 180], 0, None);
    // One stored object, but a count of 0: nothing is read.
    let objects = vec![object(ClusterableKind::PointLight, Vec3::ZERO, 5.0)];
    let pass = ZSlice {
        quad_vertices: 6,
        ..pass_with(16)
    };
    let got = run(&objects, 0, &view, pass, 16 + GUARD);
    assert_eq!(got.counts, [0, 16, 0, 0, 0, 0, 0, 0]);
    assert_eq!(got.draw_args, [6, 0, 0, 0]);
    assert_eq!(got.dispatch_args, [0, 0, 1]);
    assert!(got.list.iter().all(|e| *e == SENTINEL));
    // The same object counted is drawn: the zero above came from the count.
    let got = run(&objects, 1, &view, pass, 16 + GUARD);
    assert_eq!(got.counts[WORD_VISIBLE], 1);
    assert!(got.draw_args[1] > 0);
}

#[test]
fn an_overflowing_list_counts_everything_and_writes_only_its_capacity() {
    let mut rng = Rng(0x0f10_2030);
    let camera = perspective(Vec3::new(0.0, 5.0, 30.0), Vec3::ZERO, 1.2);
    let view = camera.view([320, 180], 0, None);
    let objects = random_objects(&mut rng, 2000, Vec3::ZERO, 20.0);
    const C: u32 = 577;
    let pass = limited_pass(C, 8);
    let grid = pass.grid([320, 180]);
    let reference = cpu_z_slice(&view, &grid, &objects, C, 4, 8);
    assert!(
        reference.pairs.len() > 4 * C as usize,
        "{} pairs",
        reference.pairs.len()
    );
    // The list buffer is longer than the capacity param: the guard lies inside it.
    let (got, near) = run_compared(&objects, &view, pass, "overflow");
    assert!(near <= MAX_NEAR_PER_SCENE);
    assert!(got.counts[WORD_REQUESTED] > C);
    assert_eq!(got.draw_args[1], C);
    // 577 instances, 64 per workgroup: 10 workgroups under a limit of 8, 8 × 2.
    assert_eq!(got.dispatch_args, [8, 2, 1]);
    assert!(got.list[..C as usize].iter().all(|e| *e != SENTINEL));
    assert!(got.list[C as usize..].iter().all(|e| *e == SENTINEL));
    // Without the capacity param, the buffer's length is the capacity.
    let pass = ZSlice {
        capacity: None,
        ..pass
    };
    let got = run(&objects, objects.len() as u32, &view, pass, C);
    assert_eq!(got.counts[WORD_CAPACITY], C);
    assert_eq!(got.draw_args[1], C);
}

#[test]
fn more_objects_than_one_dispatch_row_are_all_sliced() {
    // 300 objects in 5 workgroups under a per-dimension limit of 3: a 3 × 2 dispatch.
    let mut rng = Rng(77);
    let camera = orthographic(Vec3::new(0.0, 0.0, 50.0), Vec3::ZERO, 60.0);
    let view = camera.view([256, 256], 0, None);
    let objects = random_objects(&mut rng, 300, Vec3::ZERO, 25.0);
    let pass = limited_pass(20_000, 3);
    let (got, near) = run_compared(&objects, &view, pass, "2-D dispatch");
    assert!(near <= MAX_NEAR_PER_SCENE);
    let seen: u32 = got.counts[WORD_INVALID..].iter().sum();
    assert_eq!(seen, 300, "every object decided once: {:?}", got.counts);
}
