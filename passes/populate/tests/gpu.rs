//! `populate` on the GPU, both implementations, after z_slice, count_raster (the same
//! implementation) and scan_fan: every (froxel, kind) list equals the reference's as a
//! set, built from the list z_slice wrote on the GPU; a list may differ only by pairs
//! whose deciding value lies within `NEAR` of its threshold. A too-small capacity cuts
//! lists the way the reference does and writes nothing past it.

use glam::Vec3;
use meshlight_graph::*;
use meshlight_pass_count_raster::KINDS;
use meshlight_pass_populate::cpu::{ClusterLists, cpu_populate};
use meshlight_pass_scan_fan::ScanFan;
use meshlight_pass_z_slice::cpu::{WORD_CAPACITY, WORD_REQUESTED};
use meshlight_pass_z_slice::scenes::{Rng, orthographic, perspective, random_objects};
use meshlight_pass_z_slice::{
    CLUSTER_GRID, CLUSTERABLE_OBJECT, GridSettings, SLICE_INSTANCE, SliceInstance, ZSlice,
};
use meshlight_shaders::cpu::layout::{ClusterGrid, ClusterableObject, View};
use std::collections::BTreeSet;

const USAGE: wgpu::BufferUsages = wgpu::BufferUsages::STORAGE
    .union(wgpu::BufferUsages::COPY_DST)
    .union(wgpu::BufferUsages::COPY_SRC);
const NEAR: f32 = 1e-5;
/// What the GPU leaves in list entries nothing may write.
const SENTINEL: u32 = 0xdead_beef;
/// Entries after the capacity that must keep the sentinel.
const GUARD: u32 = 64;

#[derive(Clone, Copy, Debug, PartialEq)]
enum Implementation {
    Raster,
    Compute,
    /// `compute` with both walks dispatched with one workgroup: a round per 64 instances.
    ComputeRounds,
}

struct GpuLists {
    instances: Vec<SliceInstance>,
    lists: ClusterLists,
    /// `list_counts`: needed, capacity.
    list_counts: [u32; 2],
    /// The whole list buffer, guard included.
    raw: Vec<u32>,
    grid: ClusterGrid,
}

fn run(
    objects: &[ClusterableObject],
    view: &View,
    z_slice: ZSlice,
    implementation: Implementation,
    capacity: u32,
) -> GpuLists {
    let gpu = GpuContext::with_available(wgpu::Features::all()).unwrap_or_else(|e| panic!("{e}"));
    let [w, h] = view.viewport_size.map(|v| v as u32);
    let grid = z_slice.grid([w, h]);
    let lists = grid.cluster_count * KINDS;
    let mut g = GraphBuilder::new();
    let stored = objects.len().max(1) as u64;
    let object_list = g.import_buffer(
        "objects",
        BufferDesc::array(CLUSTERABLE_OBJECT, stored),
        USAGE,
    );
    let object_count = g.import_buffer("object_count", BufferDesc::array(Element::U32, 1), USAGE);
    let list_buffer = g.import_buffer(
        "cluster_objects",
        BufferDesc::array(Element::U32, u64::from(capacity + GUARD)),
        USAGE,
    );
    let buffer = |g: &mut GraphBuilder, name: &str, element: Element, n: u64| {
        g.create_buffer(name, BufferDesc::array(element, n))
    };
    let slice_capacity = (objects.len() as u64 * u64::from(grid.dims[2])).max(1);
    let walk_groups = match implementation {
        Implementation::ComputeRounds => 1,
        _ => meshlight_pass_count_raster::WALK_GROUPS,
    };
    let instances = buffer(&mut g, "slice_instances", SLICE_INSTANCE, slice_capacity);
    let slice_counts = buffer(&mut g, "slice_counts", Element::U32, 8);
    let draw = buffer(&mut g, "slice_draw_args", Element::DRAW_ARGS, 1);
    let dispatch = buffer(&mut g, "slice_dispatch_args", Element::DISPATCH_ARGS, 1);
    let grid_buffer = buffer(&mut g, "cluster_grid", CLUSTER_GRID, 1);
    let counts = buffer(&mut g, "cluster_counts", Element::U32, u64::from(lists));
    let offsets = buffer(&mut g, "cluster_offsets", Element::U32, u64::from(lists));
    let total = buffer(&mut g, "list_total", Element::U32, 1);
    let list_counts = buffer(&mut g, "list_counts", Element::U32, 2);
    let sliced = g
        .add_pass(
            "z_slice",
            z_slice,
            Bindings::new()
                .bind("objects", object_list)
                .bind("object_count", object_count)
                .bind("slice_instances", instances)
                .bind("slice_counts", slice_counts)
                .bind("slice_draw_args", draw)
                .bind("slice_dispatch_args", dispatch)
                .bind("cluster_grid", grid_buffer)
                .bind("cluster_counts", counts),
        )
        .unwrap();
    let from_slices = |b: Bindings| {
        let mut b = b.bind("objects", object_list);
        for name in [
            "slice_instances",
            "slice_counts",
            "slice_draw_args",
            "slice_dispatch_args",
            "cluster_grid",
        ] {
            b = b.bind(name, sliced.buffer(name).unwrap());
        }
        b
    };
    let count_bindings = from_slices(
        Bindings::new().bind("cluster_counts", sliced.buffer("cluster_counts").unwrap()),
    );
    let counted = match implementation {
        Implementation::Raster => g.add_pass(
            "count",
            meshlight_pass_count_raster::Raster {
                width: grid.dims[0],
                height: grid.dims[1],
            },
            count_bindings,
        ),
        Implementation::Compute | Implementation::ComputeRounds => g.add_pass(
            "count",
            meshlight_pass_count_raster::Compute { walk_groups },
            count_bindings,
        ),
    }
    .unwrap();
    let scanned = g
        .add_pass(
            "scan",
            ScanFan::new(lists),
            Bindings::new()
                .bind("input", counted.buffer("cluster_counts").unwrap())
                .bind("output", offsets)
                .bind("total", total),
        )
        .unwrap();
    let populate_bindings = from_slices(
        Bindings::new()
            .bind("cluster_offsets", scanned.buffer("output").unwrap())
            .bind("list_total", scanned.buffer("total").unwrap())
            .bind("cluster_counts", counted.buffer("cluster_counts").unwrap())
            .bind("cluster_objects", list_buffer)
            .bind("list_counts", list_counts),
    );
    let populated = match implementation {
        Implementation::Raster => g.add_pass(
            "populate",
            meshlight_pass_populate::Raster {
                width: grid.dims[0],
                height: grid.dims[1],
                capacity: Some(capacity),
            },
            populate_bindings,
        ),
        Implementation::Compute | Implementation::ComputeRounds => g.add_pass(
            "populate",
            meshlight_pass_populate::Compute {
                capacity: Some(capacity),
                walk_groups,
            },
            populate_bindings,
        ),
    }
    .unwrap();
    g.export(sliced.buffer("slice_instances").unwrap());
    g.export(sliced.buffer("slice_counts").unwrap());
    g.export(sliced.buffer("cluster_grid").unwrap());
    g.export(scanned.buffer("output").unwrap());
    for name in ["cluster_counts", "cluster_objects", "list_counts"] {
        g.export(populated.buffer(name).unwrap());
    }
    let compiled = g.compile(&CompileOptions::for_gpu(&gpu)).unwrap();
    let mut padded = objects.to_vec();
    padded.resize(stored as usize, ClusterableObject::default());
    let object_buffer = gpu.buffer_with_data("objects", bytemuck::cast_slice(&padded), USAGE);
    let n = objects.len() as u32;
    let count_buffer = gpu.buffer_with_data("object_count", bytemuck::bytes_of(&n), USAGE);
    let sentinels = vec![SENTINEL; (capacity + GUARD) as usize];
    let lists_buffer =
        gpu.buffer_with_data("cluster_objects", bytemuck::cast_slice(&sentinels), USAGE);
    let imports = Imports::new()
        .buffer("objects", &object_buffer)
        .buffer("object_count", &count_buffer)
        .buffer("cluster_objects", &lists_buffer);
    let mut exec = Executor::new(gpu);
    let frame = FrameData::new().with("view", bytemuck::bytes_of(view));
    exec.execute_frame(&compiled, &imports, &frame).unwrap();
    let words = |exec: &mut Executor, name: &str| -> Vec<u32> {
        bytemuck::pod_collect_to_vec(&exec.read_buffer(name).unwrap())
    };
    let slice_words = words(&mut exec, "slice_counts");
    let written = slice_words[WORD_REQUESTED].min(slice_words[WORD_CAPACITY]) as usize;
    let mut instances: Vec<SliceInstance> =
        bytemuck::pod_collect_to_vec(&exec.read_buffer("slice_instances").unwrap());
    instances.truncate(written);
    let grid: Vec<ClusterGrid> =
        bytemuck::pod_collect_to_vec(&exec.read_buffer("cluster_grid").unwrap());
    let raw: Vec<u32> = bytemuck::pod_collect_to_vec(
        &exec
            .gpu
            .read_buffer(&lists_buffer, 0, lists_buffer.size())
            .unwrap(),
    );
    let list_counts = words(&mut exec, "list_counts");
    GpuLists {
        instances,
        lists: ClusterLists {
            offsets: words(&mut exec, "cluster_offsets"),
            counts: words(&mut exec, "cluster_counts"),
            objects: raw[..capacity as usize].to_vec(),
            needed: list_counts[0],
        },
        list_counts: [list_counts[0], list_counts[1]],
        raw,
        grid: grid[0],
    }
}

/// Compares every list as a set with the reference; returns the pairs that differed.
fn compare(
    view: &View,
    objects: &[ClusterableObject],
    got: &GpuLists,
    capacity: u32,
    label: &str,
) -> usize {
    let (want, counted) = cpu_populate(view, &got.grid, objects, &got.instances, capacity);
    let (whole, _) = cpu_populate(view, &got.grid, objects, &got.instances, u32::MAX);
    assert_eq!(
        got.list_counts,
        [want.needed, capacity],
        "{label}: list_counts"
    );
    assert!(
        got.raw[capacity as usize..].iter().all(|&e| e == SENTINEL),
        "{label}: an entry past the capacity was written"
    );
    // Pairs the GPU may decide otherwise, per list.
    let mut near: Vec<BTreeSet<u32>> = vec![BTreeSet::new(); want.counts.len()];
    for (pair, walked) in got.instances.iter().zip(&counted.instances) {
        let kind = objects[pair.object as usize].kind;
        for (froxel, d) in &walked.tested {
            if d.closeness < NEAR || walked.rect_closeness < NEAR {
                near[(froxel * KINDS + kind) as usize].insert(pair.object);
            }
        }
    }
    let mut differing = 0;
    let froxels = got.grid.cluster_count;
    for froxel in 0..froxels {
        for kind in 0..KINDS {
            let mine = got.lists.list(froxel, kind);
            let set: BTreeSet<u32> = mine.iter().copied().collect();
            assert_eq!(
                set.len(),
                mine.len(),
                "{label}: an object twice in froxel {froxel} kind {kind}"
            );
            let at = (froxel * KINDS + kind) as usize;
            let theirs: BTreeSet<u32> = whole.list(froxel, kind).iter().copied().collect();
            // A list the capacity cut keeps as many entries as the reference's, any of
            // the whole list's (the atomics choose which).
            let cut = want.counts[at] < counted.counts[at];
            if cut {
                assert_eq!(
                    mine.len() as u32,
                    want.counts[at],
                    "{label}: cut list {froxel}/{kind}"
                );
            }
            for object in set.symmetric_difference(&theirs) {
                let allowed = near[at].contains(object) || (cut && !set.contains(object));
                assert!(
                    allowed,
                    "{label}: froxel {froxel} kind {kind}: object {object} {} (GPU {mine:?}, reference {theirs:?})",
                    if set.contains(object) {
                        "only on the GPU"
                    } else {
                        "missing on the GPU"
                    }
                );
                differing += 1;
            }
        }
    }
    differing
}

fn scene(rng: &mut Rng, index: u32) -> (View, Vec<ClusterableObject>, ZSlice) {
    let target = Vec3::new(rng.range(-5.0, 5.0), 0.0, rng.range(-5.0, 5.0));
    let eye = target + rng.direction() * rng.range(5.0, 60.0);
    let viewport = [[320, 180], [256, 256]][rng.below(2) as usize];
    let camera = if index % 2 == 1 {
        orthographic(eye, target, rng.range(10.0, 80.0))
    } else {
        perspective(eye, target, rng.range(0.5, 1.5))
    };
    let z_slice = ZSlice {
        grid: GridSettings {
            dims: [[16, 9, 24], [8, 8, 16], [12, 7, 3]][index as usize % 3],
            first_slice_end: [5.0, 1.0][rng.below(2) as usize],
            far: 1000.0,
        },
        ..ZSlice::default()
    };
    (
        camera.view(viewport, index, None),
        random_objects(rng, 150, target, 60.0),
        z_slice,
    )
}

#[test]
fn lists_equal_the_reference_as_sets_in_both_implementations() {
    let mut rng = Rng(0x0bad_cafe_f00d_0001);
    let mut differing = 0;
    for index in 0..4 {
        let (view, objects, z_slice) = scene(&mut rng, index);
        for implementation in [
            Implementation::Raster,
            Implementation::Compute,
            Implementation::ComputeRounds,
        ] {
            let got = run(&objects, &view, z_slice, implementation, 1 << 18);
            let label = format!("scene {index} {implementation:?}");
            assert!(
                got.list_counts[0] > 200,
                "{label}: only {} entries",
                got.list_counts[0]
            );
            assert!(
                got.list_counts[0] <= 1 << 18,
                "{label}: the lists overflowed"
            );
            differing += compare(&view, &objects, &got, 1 << 18, &label);
        }
    }
    assert!(differing <= 8, "{differing} pairs decided otherwise");
}

#[test]
fn a_small_capacity_cuts_lists_and_writes_nothing_past_it() {
    let mut rng = Rng(0x0bad_cafe_f00d_0002);
    let (view, objects, z_slice) = scene(&mut rng, 0);
    for implementation in [
        Implementation::Raster,
        Implementation::Compute,
        Implementation::ComputeRounds,
    ] {
        let got = run(&objects, &view, z_slice, implementation, 100);
        let label = format!("{implementation:?} at capacity 100");
        assert!(got.list_counts[0] > 100, "{label}: no overflow to test");
        assert!(got.lists.counts.iter().sum::<u32>() <= 100, "{label}");
        compare(&view, &objects, &got, 100, &label);
    }
}
