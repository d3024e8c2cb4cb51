//! `cull_lod` on the GPU against `cpu_cull`, on seeded random views of several instances
//! of a real multi-level asset (spot.obj): the LOD cut and its software / hardware split
//! compared as sets (slot order follows the atomics), the count words and draw
//! arguments, untouched slots between the two sides and past the capacity; the DAG
//! property of the cut when every cluster is in view; overflow of a tiny slot buffer;
//! a cull dispatch folded into two dimensions.

use glam::{Mat4, Quat, Vec3};
use meshlight_gpu_scene::gpu::elements;
use meshlight_gpu_scene::{Camera, GpuScene, Projection, SceneData};
use meshlight_graph::*;
use meshlight_pass_cull_lod::cpu::{self, HW_VERTICES};
use meshlight_pass_cull_lod::{CullLod, CullResult, Thresholds, cpu_cull};
use meshlight_scene::asset::format::NO_GROUP;
use meshlight_shaders::cpu::layout::{Cluster, View};
use std::collections::{BTreeSet, HashMap, HashSet};

mod common;
use common::*;

/// What the GPU leaves in slots nothing may write.
/// Slots after the capacity that must keep the sentinel.
const GUARD: u32 = 32;

/// A cluster the GPU and the reference decide differently must have its deciding value
/// within this relative distance of the threshold (f32 rounding, fused multiply-adds).
const NEAR_THRESHOLD: f32 = 1e-5;
/// At most this many such clusters per view.
const MAX_NEAR_PER_VIEW: usize = 2;

struct GpuCull {
    /// The whole raster list: `capacity` slots, then the guard.
    slots: Vec<Cluster>,
    counts: [u32; 8],
    hw_args: [u32; 4],
}

impl GpuCull {
    fn capacity(&self) -> usize {
        self.counts[3] as usize
    }
    fn software(&self) -> &[Cluster] {
        &self.slots[..self.counts[0] as usize]
    }
    fn hardware(&self) -> &[Cluster] {
        &self.slots[self.capacity() - self.counts[1] as usize..self.capacity()]
    }
}

/// Runs the pass once over `clusters`, with a raster list of `slots` sentinel entries.
fn run(
    data: &mut SceneData,
    clusters: &[Cluster],
    view: &View,
    pass: CullLod,
    slots: u32,
) -> GpuCull {
    let gpu = gpu();
    let scene = GpuScene::new(&gpu, data);
    let mut g = GraphBuilder::new();
    let h = scene.import(&mut g);
    let n = clusters.len() as u64;
    let list = g.import_buffer("clusters", BufferDesc::array(elements::CLUSTER, n), USAGE);
    let count = g.import_buffer("cluster_count", BufferDesc::array(Element::U32, 2), USAGE);
    let raster = g.import_buffer(
        "raster_clusters",
        BufferDesc::array(elements::CLUSTER, slots as u64),
        USAGE,
    );
    let counts = g.create_buffer("raster_counts", BufferDesc::array(Element::U32, 8));
    let hw_args = g.create_buffer("hw_args", BufferDesc::array(Element::DRAW_ARGS, 1));
    let out = g
        .add_pass(
            "cull",
            pass,
            Bindings::new()
                .bind("clusters", list)
                .bind("cluster_count", count)
                .bind("meshlet_groups", h.groups)
                .bind("raster_clusters", raster)
                .bind("raster_counts", counts)
                .bind("hw_args", hw_args),
        )
        .unwrap();
    g.export(out.buffer("raster_clusters").unwrap());
    g.export(out.buffer("raster_counts").unwrap());
    g.export(out.buffer("hw_args").unwrap());
    let compiled = g.compile(&CompileOptions::for_gpu(&gpu)).unwrap();
    let [list_buffer, count_buffer, raster_buffer] = cull_buffers(&gpu, clusters, slots);
    let imports = scene
        .imports()
        .buffer("clusters", &list_buffer)
        .buffer("cluster_count", &count_buffer)
        .buffer("raster_clusters", &raster_buffer);
    let mut exec = Executor::new(gpu);
    let frame = FrameData::new().with("view", bytemuck::bytes_of(view));
    exec.execute_frame(&compiled, &imports, &frame).unwrap();
    let counts: Vec<u32> =
        bytemuck::pod_collect_to_vec(&exec.read_buffer("raster_counts").unwrap());
    let hw_args: Vec<u32> = bytemuck::pod_collect_to_vec(&exec.read_buffer("hw_args").unwrap());
    let raster = exec
        .gpu
        .read_buffer(&raster_buffer, 0, raster_buffer.size())
        .unwrap();
    GpuCull {
        slots: bytemuck::pod_collect_to_vec(&raster),
        counts: counts[..8].try_into().unwrap(),
        hw_args: hw_args[..4].try_into().unwrap(),
    }
}

fn set(clusters: &[Cluster]) -> BTreeSet<(u32, u32)> {
    clusters.iter().map(|c| (c.instance, c.meshlet)).collect()
}

/// Compares the GPU's sets and words with the reference; a cluster decided differently
/// must lie within `NEAR_THRESHOLD` of a threshold. Returns how many did.
fn compare(
    data: &SceneData,
    view: &View,
    clusters: &[Cluster],
    t: &Thresholds,
    reference: &CullResult,
    got: &GpuCull,
    label: &str,
) -> usize {
    let capacity = got.capacity();
    assert_eq!(got.counts[3], reference.counts[3], "{label}: capacity word");
    assert_eq!(got.counts[7], 0, "{label}");
    assert_eq!(
        got.hw_args,
        [HW_VERTICES, got.counts[1], 0, 0],
        "{label}: draw arguments"
    );
    let (software, hardware) = (set(got.software()), set(got.hardware()));
    assert_eq!(
        software.len() + hardware.len(),
        got.counts[0] as usize + got.counts[1] as usize,
        "{label}: a cluster written twice"
    );
    assert!(
        !software.contains(&(SENTINEL.instance, SENTINEL.meshlet)),
        "{label}: a software slot left unwritten"
    );
    assert!(
        !hardware.contains(&(SENTINEL.instance, SENTINEL.meshlet)),
        "{label}: a hardware slot left unwritten"
    );
    let between = &got.slots[got.counts[0] as usize..capacity - got.counts[1] as usize];
    assert!(
        between.iter().all(|c| *c == SENTINEL),
        "{label}: a free slot was written"
    );
    assert!(
        got.slots[capacity..].iter().all(|c| *c == SENTINEL),
        "{label}: a slot past the capacity was written"
    );

    let want_sw = set(&reference.software);
    let want_hw = set(&reference.hardware);
    // Past the capacity the atomics choose which clusters got a slot: then only a
    // cluster the reference did not put on that side is a disagreement.
    let overflowed = got.counts[2] as usize > capacity;
    let differing: HashSet<(u32, u32)> = if overflowed {
        software
            .difference(&want_sw)
            .chain(hardware.difference(&want_hw))
            .copied()
            .collect()
    } else {
        software
            .symmetric_difference(&want_sw)
            .chain(hardware.symmetric_difference(&want_hw))
            .copied()
            .collect()
    };
    for &(instance, meshlet) in &differing {
        let d = cpu::classify(data, view, Cluster { instance, meshlet }, t);
        let closeness = d.closeness(t);
        assert!(
            closeness < NEAR_THRESHOLD,
            "{label}: cluster ({instance}, {meshlet}) decided differently, {closeness} from a threshold: {d:?}"
        );
    }
    // The frustum set is only counted on the GPU: clusters near a plane may move it.
    let near_planes = clusters
        .iter()
        .filter(|c| {
            let d = cpu::classify(data, view, **c, t);
            d.frustum_margin.abs() / d.radius < NEAR_THRESHOLD
        })
        .count();
    assert!(
        got.counts[4].abs_diff(reference.counts[4]) as usize <= near_planes,
        "{label}: {} clusters in the frustum, the reference has {}",
        got.counts[4],
        reference.counts[4]
    );
    if differing.is_empty() && !overflowed {
        assert_eq!(got.counts[..3], reference.counts[..3], "{label}: counts");
        assert_eq!(got.counts[5..], reference.counts[5..8], "{label}: counts");
    }
    differing.len()
}

#[test]
fn random_views_match_the_reference() {
    let (mut rng, mut data, clusters) = seeded(0x5eed_cafe_f00d_0001, scene());
    let levels = data.meshes[0].level_count;
    assert!(levels >= 4, "spot has {levels} LOD levels");
    let mut totals = [0usize; 6];
    let mut near_total = 0;
    for v in 0..10 {
        let (target, direction) = random_aim(&mut rng, Vec3::new(4.0, 0.5, 3.0), [-0.3, 1.0]);
        let distance = 1.5 * (30.0f32 / 1.5).powf(rng.unit());
        let viewport = [[320, 240], [640, 360], [1280, 720]][rng.below(3) as usize];
        let fov = rng.range(0.5, 1.5);
        let mut camera = Camera::perspective(target + direction * distance, target, fov, 0.05);
        // Every third view orthographic (a shadow cascade's kind): its errors project
        // the same at every distance.
        if v % 3 == 2 {
            camera.projection = Projection::Orthographic {
                height: 2.0 * distance * (0.5 * fov).tan(),
                near: 0.05,
                far: distance * 4.0,
            };
        }
        let view = camera.view(viewport, v, None);
        assert_eq!(view.orthographic, u32::from(v % 3 == 2));
        // Every fourth view sends the whole cut to software (`hardware = false`).
        let t = Thresholds {
            lod_threshold_px: [0.5, 1.0, 2.0, 4.0][rng.below(4) as usize],
            sw_threshold_px: [8.0, 16.0, 32.0, 64.0][rng.below(4) as usize],
            hardware: v % 4 != 3,
        };
        let capacity = clusters.len() as u32;
        let pass = CullLod {
            thresholds: t,
            capacity: Some(capacity),
            ..CullLod::default()
        };
        let reference = cpu_cull(&data, &view, &clusters, &t, capacity);
        let got = run(&mut data, &clusters, &view, pass, capacity + GUARD);
        let label = format!("view {v} ({distance:.1} units, {viewport:?}, {t:?})");
        let near = compare(&data, &view, &clusters, &t, &reference, &got, &label);
        assert!(
            near <= MAX_NEAR_PER_VIEW,
            "{label}: {near} clusters near a threshold"
        );
        near_total += near;
        totals[0] += clusters.len() - reference.frustum.len();
        totals[1] += reference.frustum.len() - reference.cut.len();
        totals[2] += reference.software.len();
        totals[3] += reference.hardware.len();
        totals[4] += got.counts[4] as usize;
        eprintln!(
            "{label}: frustum {} cut {} sw {} hw {} near {near}",
            reference.frustum.len(),
            reference.cut.len(),
            reference.software.len(),
            reference.hardware.len()
        );
        if !t.hardware {
            assert_eq!(
                got.counts[1], 0,
                "{label}: a hardware cluster with hardware = false"
            );
            totals[5] += got.counts[0] as usize;
        }
    }
    // The views exercise every outcome.
    assert!(totals[0] > 0, "no view culled a cluster by the frustum");
    assert!(totals[1] > 0, "no view dropped a cluster from the LOD cut");
    assert!(
        totals[2] > 0 && totals[3] > 0,
        "software {} hardware {}",
        totals[2],
        totals[3]
    );
    assert!(totals[5] > 0, "no all-software view drew a cluster");
    eprintln!("clusters decided differently from the reference, near a threshold: {near_total}");
}

/// For each LOD-0 meshlet of `instance`, the number of cut clusters on every path to a
/// root (meshlet → its parent group → any meshlet that group produced → …), as a bit
/// set of counts: the DAG property holds when it is exactly {1} for every LOD-0 meshlet.
fn cut_counts_on_paths(data: &SceneData, instance: u32, cut: &HashSet<u32>) -> Vec<(u32, u64)> {
    let inst = &data.instances[instance as usize];
    let range = inst.first_meshlet..inst.first_meshlet + inst.meshlet_count;
    let mut produced: HashMap<u32, Vec<u32>> = HashMap::new();
    for m in range.clone() {
        let source = data.meshlets[m as usize].source_group;
        if source != NO_GROUP {
            produced.entry(source).or_default().push(m);
        }
    }
    fn paths(
        m: u32,
        data: &SceneData,
        produced: &HashMap<u32, Vec<u32>>,
        cut: &HashSet<u32>,
        memo: &mut HashMap<u32, u64>,
    ) -> u64 {
        if let Some(&p) = memo.get(&m) {
            return p;
        }
        let own = u32::from(cut.contains(&m));
        let parent = data.meshlets[m as usize].parent_group;
        let above = if parent == NO_GROUP {
            1
        } else {
            let children = produced.get(&parent).map(Vec::as_slice).unwrap_or(&[]);
            assert!(!children.is_empty(), "group {parent} produced no meshlet");
            children
                .iter()
                .fold(0, |acc, &c| acc | paths(c, data, produced, cut, memo))
        };
        let p = above << own;
        memo.insert(m, p);
        p
    }
    let mut memo = HashMap::new();
    range
        .filter(|&m| data.meshlets[m as usize].level() == 0)
        .map(|m| (m, paths(m, data, &produced, cut, &mut memo)))
        .collect()
}

#[test]
fn with_every_cluster_in_view_the_cut_covers_each_lod0_meshlet_exactly_once() {
    // A row of instances receding from the camera: near ones fine, far ones coarse.
    let placements: Vec<Mat4> = (0..6)
        .map(|i| {
            Mat4::from_rotation_translation(
                Quat::from_rotation_y(i as f32),
                Vec3::new(0.0, 0.0, -2.0 - 9.0 * i as f32),
            )
        })
        .collect();
    let (_, mut data, clusters) = seeded(7, scene_with(&placements));
    let camera = Camera::perspective(
        Vec3::new(0.0, 1.5, 2.0),
        Vec3::new(0.0, 0.0, -20.0),
        1.3,
        0.05,
    );
    let view = camera.view([640, 480], 0, None);
    let t = Thresholds {
        lod_threshold_px: 1.0,
        sw_threshold_px: 32.0,
        ..Thresholds::default()
    };
    let reference = cpu_cull(&data, &view, &clusters, &t, clusters.len() as u32);
    assert_eq!(
        reference.frustum.len(),
        clusters.len(),
        "every cluster in view"
    );
    let pass = CullLod {
        thresholds: t,
        ..CullLod::default()
    };
    let got = run(&mut data, &clusters, &view, pass, clusters.len() as u32);
    assert_eq!(got.counts[4] as usize, clusters.len());
    let near = compare(&data, &view, &clusters, &t, &reference, &got, "row");
    assert!(near <= MAX_NEAR_PER_VIEW);
    let cut: Vec<Cluster> = got
        .software()
        .iter()
        .chain(got.hardware())
        .copied()
        .collect();
    let levels: BTreeSet<u32> = cut
        .iter()
        .map(|c| data.meshlets[c.meshlet as usize].level())
        .collect();
    assert!(levels.len() >= 3, "the cut spans levels {levels:?}");
    for instance in 0..data.instances.len() as u32 {
        let mine: HashSet<u32> = cut
            .iter()
            .filter(|c| c.instance == instance)
            .map(|c| c.meshlet)
            .collect();
        for (m, counts) in cut_counts_on_paths(&data, instance, &mine) {
            assert_eq!(
                counts, 0b10,
                "instance {instance}: paths from LOD-0 meshlet {m} hold these numbers of cut clusters: {counts:#b}"
            );
        }
        // The check itself fails on a broken cut: drop one cluster and a path loses it.
        if let Some(&dropped) = mine.iter().next() {
            let mut broken = mine.clone();
            broken.remove(&dropped);
            assert!(
                cut_counts_on_paths(&data, instance, &broken)
                    .iter()
                    .any(|(_, c)| *c != 0b10),
                "a cut missing meshlet {dropped} passed the check"
            );
        }
    }
}

#[test]
fn a_tiny_slot_buffer_overflows_into_exactly_its_capacity() {
    let (_, mut data, clusters) = seeded(0x0f10_2030, scene());
    // A view with both software and hardware clusters.
    let camera = Camera::perspective(Vec3::new(2.0, 6.0, 14.0), Vec3::ZERO, 1.0, 0.05);
    let view = camera.view([1280, 720], 0, None);
    let t = Thresholds {
        lod_threshold_px: 0.5,
        sw_threshold_px: 64.0,
        ..Thresholds::default()
    };
    const C: u32 = 10;
    let reference = cpu_cull(&data, &view, &clusters, &t, C);
    assert!(
        reference.cut.len() > 5 * C as usize,
        "{} cut",
        reference.cut.len()
    );
    assert!(!reference.software.is_empty() && !reference.hardware.is_empty());
    let pass = CullLod {
        thresholds: t,
        capacity: Some(C),
        ..CullLod::default()
    };
    let got = run(&mut data, &clusters, &view, pass, C + GUARD);
    let near = compare(&data, &view, &clusters, &t, &reference, &got, "overflow");
    assert_eq!(near, 0, "the overflow view has no cluster near a threshold");
    assert_eq!(got.counts[2] as usize, reference.cut.len());
    assert!(got.counts[2] > got.counts[3]);
    assert_eq!(got.counts[3], C);
    assert_eq!(got.counts[0] + got.counts[1], C, "exactly C slots used");
    assert_eq!(got.hw_args, [HW_VERTICES, got.counts[1], 0, 0]);
    let written = &got.slots[..C as usize];
    assert!(
        written.iter().all(|c| *c != SENTINEL),
        "a slot left unwritten"
    );
    assert_eq!(set(written).len(), C as usize, "a cluster written twice");
    // Each side holds clusters of its kind, and its triangle word counts them.
    let (want_sw, want_hw) = (set(&reference.software), set(&reference.hardware));
    let triangles = |side: &[Cluster]| -> u32 {
        side.iter()
            .map(|c| data.meshlets[c.meshlet as usize].triangle_count())
            .sum()
    };
    assert!(set(got.software()).is_subset(&want_sw));
    assert!(set(got.hardware()).is_subset(&want_hw));
    assert_eq!(got.counts[5], triangles(got.software()));
    assert_eq!(got.counts[6], triangles(got.hardware()));
}

#[test]
fn a_cull_dispatch_folded_into_two_dimensions_visits_every_cluster() {
    let (_, mut data, clusters) = seeded(0xd15_a7c4, scene());
    let groups = (clusters.len() as u32).div_ceil(meshlight_pass_cull_lod::WORKGROUP_SIZE);
    // The smallest limit whose square still covers the workgroups: several rows.
    let limit = (1..).find(|m| m * m >= groups).unwrap();
    assert!(
        limit < groups,
        "{groups} workgroups need two dimensions under {limit}"
    );
    let camera = Camera::perspective(Vec3::new(0.0, 4.0, 12.0), Vec3::ZERO, 1.2, 0.05);
    let view = camera.view([640, 360], 0, None);
    let t = Thresholds::default();
    let reference = cpu_cull(&data, &view, &clusters, &t, clusters.len() as u32);
    let pass = CullLod {
        max_per_dimension: Some(limit),
        ..CullLod::default()
    };
    let got = run(&mut data, &clusters, &view, pass, clusters.len() as u32);
    let near = compare(
        &data,
        &view,
        &clusters,
        &t,
        &reference,
        &got,
        "2-D dispatch",
    );
    assert!(near <= MAX_NEAR_PER_VIEW);
    assert_eq!(got.counts[4] as usize, reference.frustum.len());
}
