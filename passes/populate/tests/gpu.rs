//! `populate` on the GPU, both implementations, after z_slice, count_raster (the same
//! implementation) and scan_fan: every (froxel, kind) list equals the reference's as a
//! set, built from the list z_slice wrote on the GPU; a list may differ only by pairs
//! whose deciding value lies within `NEAR` of its threshold. A too-small capacity cuts
//! lists the way the reference does and writes nothing past it.

use meshlight_graph::{Bindings, BufferDesc, Element, Imports};
use meshlight_pass_count_raster::KINDS;
use meshlight_pass_count_raster::testbed::{Counted, Implementation, Scene};
use meshlight_pass_populate::cpu::{ClusterLists, cpu_populate};
use meshlight_pass_scan_fan::ScanFan;
use meshlight_pass_z_slice::scenes::{Rng, random_camera, random_objects};
use meshlight_pass_z_slice::testbed::{USAGE, read};
use meshlight_pass_z_slice::{GridSettings, SliceInstance, ZSlice};
use meshlight_shaders::cpu::layout::{ClusterGrid, ClusterableObject, View};
use meshlight_testing::executor;
use std::collections::BTreeSet;

const NEAR: f32 = 1e-5;
/// What the GPU leaves in list entries nothing may write.
const SENTINEL: u32 = 0xdead_beef;
/// Entries after the capacity that must keep the sentinel.
const GUARD: u32 = 64;

struct GpuLists {
    instances: Vec<SliceInstance>,
    lists: ClusterLists,
    /// `list_counts`: needed, capacity.
    list_counts: [u32; 2],
    /// The whole list buffer, guard included.
    raw: Vec<u32>,
    grid: ClusterGrid,
}

fn run(scene: &Scene, implementation: Implementation, capacity: u32) -> GpuLists {
    let mut counted = Counted::add(scene, implementation).unwrap();
    let g = &mut counted.graph;
    let lists = counted.grid.cluster_count * KINDS;
    let list_buffer = g.import_buffer(
        "cluster_objects",
        BufferDesc::array(Element::U32, u64::from(capacity + GUARD)),
        USAGE,
    );
    let mut buffer = |name: &str, n: u64| g.create_buffer(name, BufferDesc::array(Element::U32, n));
    let offsets = buffer("cluster_offsets", u64::from(lists));
    let total = buffer("list_total", 1);
    let list_counts = buffer("list_counts", 2);
    let counts = counted.outputs.buffer("cluster_counts").unwrap();
    let scanned = g
        .add_pass(
            "scan",
            ScanFan::new(lists),
            Bindings::new()
                .bind("input", counts)
                .bind("output", offsets)
                .bind("total", total),
        )
        .unwrap();
    let populate_bindings = counted
        .sliced
        .bind_walk(
            Bindings::new()
                .bind("cluster_offsets", scanned.buffer("output").unwrap())
                .bind("list_total", scanned.buffer("total").unwrap())
                .bind("cluster_counts", counts)
                .bind("cluster_objects", list_buffer)
                .bind("list_counts", list_counts),
        )
        .unwrap();
    let populated = g
        .add_boxed_pass(
            "populate",
            meshlight_pass_populate::pass(counted.walk, Some(capacity)),
            populate_bindings,
        )
        .unwrap();
    g.export(scanned.buffer("output").unwrap());
    for name in ["cluster_counts", "cluster_objects", "list_counts"] {
        g.export(populated.buffer(name).unwrap());
    }
    let mut exec = executor();
    let sentinels = vec![SENTINEL; (capacity + GUARD) as usize];
    let lists_buffer =
        exec.gpu
            .buffer_with_data("cluster_objects", bytemuck::cast_slice(&sentinels), USAGE);
    let imports = Imports::new().buffer("cluster_objects", &lists_buffer);
    let (instances, grid) = counted.run(&mut exec, imports).unwrap();
    let raw: Vec<u32> = bytemuck::pod_collect_to_vec(
        &exec
            .gpu
            .read_buffer(&lists_buffer, 0, lists_buffer.size())
            .unwrap(),
    );
    let list_counts: Vec<u32> = read(&mut exec, "list_counts");
    GpuLists {
        instances,
        lists: ClusterLists {
            offsets: read(&mut exec, "cluster_offsets"),
            counts: read(&mut exec, "cluster_counts"),
            objects: raw[..capacity as usize].to_vec(),
            needed: list_counts[0],
        },
        list_counts: [list_counts[0], list_counts[1]],
        raw,
        grid,
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

fn scene(rng: &mut Rng, index: u32) -> Scene {
    let (camera, target) = random_camera(rng, index % 2 == 1);
    let viewport = [[320, 180], [256, 256]][rng.below(2) as usize];
    let z_slice = ZSlice {
        grid: GridSettings {
            dims: [[16, 9, 24], [8, 8, 16], [12, 7, 3]][index as usize % 3],
            first_slice_end: [5.0, 1.0][rng.below(2) as usize],
            far: 1000.0,
        },
        ..ZSlice::default()
    };
    Scene {
        view: camera.view(viewport, index, None),
        objects: random_objects(rng, 150, target, 60.0),
        z_slice,
    }
}

#[test]
fn lists_equal_the_reference_as_sets_in_both_implementations() {
    let mut rng = Rng(0x0bad_cafe_f00d_0001);
    let mut differing = 0;
    for index in 0..4 {
        let scene = scene(&mut rng, index);
        for implementation in Implementation::ALL {
            let got = run(&scene, implementation, 1 << 18);
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
            differing += compare(&scene.view, &scene.objects, &got, 1 << 18, &label);
        }
    }
    assert!(differing <= 8, "{differing} pairs decided otherwise");
}

#[test]
fn a_small_capacity_cuts_lists_and_writes_nothing_past_it() {
    let mut rng = Rng(0x0bad_cafe_f00d_0002);
    let scene = scene(&mut rng, 0);
    for implementation in Implementation::ALL {
        let got = run(&scene, implementation, 100);
        let label = format!("{implementation:?} at capacity 100");
        assert!(got.list_counts[0] > 100, "{label}: no overflow to test");
        assert!(got.lists.counts.iter().sum::<u32>() <= 100, "{label}");
        compare(&scene.view, &scene.objects, &got, 100, &label);
    }
}
