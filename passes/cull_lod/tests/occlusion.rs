//! Two-pass occlusion in `cull_lod` on the GPU against `cpu_cull_with`, with depth
//! pyramids made on the CPU (`DepthPyramid`, the rule the depth_pyramid stage builds
//! by) from hand-made walls, on seeded random views of spot.obj instances, one of them
//! moved since last frame and the camera moved too: the first pass against last frame's
//! pyramid (a history, filled by a copy pass the frame before), the second against this
//! frame's, chained as in the frame (the second takes the first's `occluded` list).
//! Also: with no valid history or on a camera cut the first pass culls nothing by
//! occlusion; the second pass considers only the first pass's candidates and fills only
//! the slots the first left free.

use glam::{Mat4, Quat, Vec3};
use meshlight_gpu_scene::gpu::elements;
use meshlight_gpu_scene::{Camera, GpuScene, Phase, SceneData};
use meshlight_graph::*;
use meshlight_pass_cull_lod::cpu::{self, HW_VERTICES, Occlusion};
use meshlight_pass_cull_lod::{
    CAMERA_CUT_INPUT, CullLod, CullResult, PER_INSTANCE_FIRST, PER_INSTANCE_SECOND, Thresholds,
};
use meshlight_shaders::cpu::layout::{Cluster, View};
use meshlight_shaders::cpu::occlusion::DepthPyramid;
use meshlight_testing::copy_pyramid::{pyramid_texture_desc, uploaded_history};
use meshlight_testing::{texture, write_pyramid};
use std::collections::BTreeSet;

mod common;
use common::*;

/// Decisions the GPU may take differently from the reference: within this relative
/// distance of a threshold, at most `MAX_NEAR_PER_VIEW` per view and pass.
const NEAR_THRESHOLD: f32 = 1e-5;
const MAX_NEAR_PER_VIEW: usize = 2;
const VIEWPORT: [u32; 2] = [320, 240];
const T: Thresholds = Thresholds {
    lod_threshold_px: 1.0,
    sw_threshold_px: 32.0,
    hardware: true,
};

/// The pyramid texture of the viewport.
fn pyramid_desc() -> TextureDesc {
    pyramid_texture_desc(&DepthPyramid::from_depth(
        VIEWPORT[0],
        VIEWPORT[1],
        &vec![0.0; pixels()],
    ))
}

fn pixels() -> usize {
    (VIEWPORT[0] * VIEWPORT[1]) as usize
}

/// The first and second pass chained as in the frame, over one imported candidate list,
/// with last frame's pyramid a history filled from `upload` and this frame's imported.
struct Harness {
    exec: Executor,
    compiled: CompiledGraph,
    scene: GpuScene,
    clusters: wgpu::Buffer,
    cluster_count: wgpu::Buffer,
    raster: wgpu::Buffer,
    upload: wgpu::Texture,
    now: wgpu::Texture,
    capacity: u32,
    per_instance_bound: bool,
}

/// What one frame left.
struct Frame {
    slots: Vec<Cluster>,
    first: [u32; 12],
    first_hw_args: [u32; 4],
    candidates: Vec<Cluster>,
    candidate_count: [u32; 2],
    second: [u32; 12],
    second_hw_args: [u32; 4],
    /// The per-instance counters after both passes.
    per_instance: Vec<u32>,
}

impl Harness {
    fn new(data: &mut SceneData, clusters: &[Cluster]) -> Self {
        Self::with(data, clusters, true)
    }

    /// With `per_instance`, the per-instance counters are bound (the `occlusion` view's
    /// frame); without, a first pass that tests nothing runs its untested kernel.
    fn with(data: &mut SceneData, clusters: &[Cluster], per_instance_bound: bool) -> Self {
        let gpu = gpu();
        let scene = GpuScene::new(&gpu, data);
        let mut g = GraphBuilder::new();
        let h = scene.import(&mut g);
        let n = clusters.len() as u64;
        let capacity = n as u32;
        let list = g.import_buffer("clusters", BufferDesc::array(elements::CLUSTER, n), USAGE);
        let count = g.import_buffer("cluster_count", BufferDesc::array(Element::U32, 2), USAGE);
        let raster = g.import_buffer(
            "raster_clusters",
            BufferDesc::array(elements::CLUSTER, n),
            USAGE,
        );
        let words = BufferDesc::array(Element::U32, 12);
        let args = BufferDesc::array(Element::DRAW_ARGS, 1);
        let counts = g.create_buffer("raster_counts", words.clone());
        let hw_args = g.create_buffer("hw_args", args.clone());
        // Named unlike the slots, which the second pass would bind them to by name.
        let occluded = g.create_buffer("candidates", BufferDesc::array(elements::CLUSTER, n));
        let occluded_count = g.create_buffer("candidate_count", BufferDesc::array(Element::U32, 2));
        let counts2 = g.create_buffer("raster_counts_second", words);
        // Named unlike both of its slots, for the same reason.
        let per_instance = g.create_buffer(
            "instance_occlusion",
            BufferDesc::array(Element::U32, data.instances.len() as u64 * 2),
        );
        let hw_args2 = g.create_buffer("hw_args_second", args);
        let desc = pyramid_desc();
        let usage = wgpu::TextureUsages::TEXTURE_BINDING
            | wgpu::TextureUsages::COPY_SRC
            | wgpu::TextureUsages::COPY_DST;
        let history = uploaded_history(&mut g, "pyramid", "upload", &desc, usage).unwrap();
        let now_handle = g.import_texture("pyramid_now", desc.clone(), usage);
        let scene_bindings = || Bindings::new().bind("meshlet_groups", h.groups);
        let first = CullLod {
            thresholds: T,
            ..CullLod::default()
        };
        let mut bindings = scene_bindings()
            .bind("clusters", list)
            .bind("cluster_count", count)
            .bind("raster_clusters", raster)
            .bind("raster_counts", counts)
            .bind("hw_args", hw_args)
            .bind("pyramid", history.prev)
            .bind("occluded", occluded)
            .bind("occluded_count", occluded_count);
        if per_instance_bound {
            bindings = bindings.bind(PER_INSTANCE_FIRST, per_instance);
        }
        let out = g.add_pass("cull", first, bindings).unwrap();
        let second = CullLod {
            thresholds: T,
            phase: Phase::Second,
            ..CullLod::default()
        };
        let mut bindings = scene_bindings()
            .bind("clusters", out.buffer("occluded").unwrap())
            .bind("cluster_count", out.buffer("occluded_count").unwrap())
            .bind("raster_clusters", out.buffer("raster_clusters").unwrap())
            .bind("raster_counts", counts2)
            .bind("hw_args", hw_args2)
            .bind("pyramid", now_handle)
            .bind("first_counts", out.buffer("raster_counts").unwrap());
        if per_instance_bound {
            bindings = bindings.bind(PER_INSTANCE_SECOND, out.buffer(PER_INSTANCE_FIRST).unwrap());
        }
        let out2 = g.add_pass("cull_second", second, bindings).unwrap();
        for name in ["raster_counts", "hw_args", "occluded", "occluded_count"] {
            g.export(out.buffer(name).unwrap());
        }
        g.export(out2.buffer("raster_counts").unwrap());
        g.export(out2.buffer("hw_args").unwrap());
        g.export(out2.buffer("raster_clusters").unwrap());
        if per_instance_bound {
            g.export(out2.buffer(PER_INSTANCE_SECOND).unwrap());
        }
        let compiled = g.compile(&CompileOptions::for_gpu(&gpu)).unwrap();
        let [clusters_buffer, count_buffer, raster_buffer] = cull_buffers(&gpu, clusters, n as u32);
        let (upload, now) = (
            texture(&gpu, "upload", &desc, usage),
            texture(&gpu, "pyramid_now", &desc, usage),
        );
        Self {
            exec: Executor::new(gpu),
            compiled,
            scene,
            clusters: clusters_buffer,
            cluster_count: count_buffer,
            raster: raster_buffer,
            upload,
            now,
            capacity,
            per_instance_bound,
        }
    }

    /// One frame: `last` becomes the next frame's history, `now` is this frame's
    /// pyramid for the second pass.
    fn frame(&mut self, view: &View, cut: bool, last: &DepthPyramid, now: &DepthPyramid) -> Frame {
        let queue = self.exec.gpu.queue.clone();
        write_pyramid(&queue, &self.upload, last);
        write_pyramid(&queue, &self.now, now);
        queue.write_buffer(
            &self.raster,
            0,
            bytemuck::cast_slice(&vec![SENTINEL; self.capacity as usize]),
        );
        let imports = self
            .scene
            .imports()
            .buffer("clusters", &self.clusters)
            .buffer("cluster_count", &self.cluster_count)
            .buffer("raster_clusters", &self.raster)
            .texture("upload", &self.upload)
            .texture("pyramid_now", &self.now);
        let frame = FrameData::new()
            .with("view", bytemuck::bytes_of(view))
            .with(CAMERA_CUT_INPUT, &u32::from(cut).to_le_bytes());
        self.exec
            .execute_frame(&self.compiled, &imports, &frame)
            .unwrap();
        let words = |exec: &mut Executor, name: &str| -> Vec<u32> {
            bytemuck::pod_collect_to_vec(&exec.read_buffer(name).unwrap())
        };
        let first = words(&mut self.exec, "raster_counts");
        let first_hw_args = words(&mut self.exec, "hw_args");
        let occluded = words(&mut self.exec, "candidates");
        let candidate_count = words(&mut self.exec, "candidate_count");
        let second = words(&mut self.exec, "raster_counts_second");
        let second_hw_args = words(&mut self.exec, "hw_args_second");
        let per_instance = match self.per_instance_bound {
            true => words(&mut self.exec, "instance_occlusion"),
            false => Vec::new(),
        };
        let raster = self
            .exec
            .gpu
            .read_buffer(&self.raster, 0, self.raster.size())
            .unwrap();
        let candidates: Vec<Cluster> =
            bytemuck::cast_slice(&occluded)[..candidate_count[0] as usize].to_vec();
        Frame {
            slots: bytemuck::pod_collect_to_vec(&raster),
            first: first[..12].try_into().unwrap(),
            first_hw_args: first_hw_args[..4].try_into().unwrap(),
            candidates,
            candidate_count: candidate_count[..2].try_into().unwrap(),
            second: second[..12].try_into().unwrap(),
            second_hw_args: second_hw_args[..4].try_into().unwrap(),
            per_instance,
        }
    }
}

fn set(clusters: &[Cluster]) -> BTreeSet<(u32, u32)> {
    clusters.iter().map(|c| (c.instance, c.meshlet)).collect()
}

/// A cluster decided differently must lie within `NEAR_THRESHOLD` of a threshold;
/// returns how many did.
fn differing(
    data: &SceneData,
    view: &View,
    occlusion: Occlusion,
    label: &str,
    pairs: [(&[Cluster], &[Cluster]); 3],
) -> usize {
    let mut n = 0;
    for (k, (got, want)) in pairs.into_iter().enumerate() {
        let extra = set(got).difference(&set(want)).count();
        for &(instance, meshlet) in set(got).symmetric_difference(&set(want)) {
            let c = Cluster { instance, meshlet };
            let d = cpu::classify_with(data, view, c, &T, occlusion);
            let closeness = d.closeness(&T);
            assert!(
                closeness < NEAR_THRESHOLD,
                "{label}: cluster ({instance}, {meshlet}) decided differently (list {k}, {extra} of {} more on the GPU, {} fewer), {closeness} from a threshold: {d:?}",
                got.len(),
                set(want).difference(&set(got)).count()
            );
            n += 1;
        }
    }
    n
}

/// The first pass's lists out of the shared slot buffer.
fn first_lists(f: &Frame) -> (Vec<Cluster>, Vec<Cluster>) {
    let c = f.first[3] as usize;
    let software = f.slots[..f.first[0] as usize].to_vec();
    let hardware = f.slots[c - f.first[1] as usize..c].to_vec();
    (software, hardware)
}

/// The second pass's lists: software from its first slot `second[7]`, hardware
/// `[C2 - hw2, C2)` with `C2 = second[3]`.
fn second_lists(f: &Frame) -> (Vec<Cluster>, Vec<Cluster>) {
    let base = f.second[7] as usize;
    let software = f.slots[base..base + f.second[0] as usize].to_vec();
    let top = f.second[3] as usize;
    let hardware = f.slots[top - f.second[1] as usize..top].to_vec();
    (software, hardware)
}

/// Both of the second pass's lists in one.
fn second_list(f: &Frame) -> Vec<Cluster> {
    let (software, hardware) = second_lists(f);
    [software, hardware].concat()
}

/// The per-instance counters against the reference over the lists the GPU wrote, and
/// their sums against the passes' totals: `[2i]` adds up to the first pass's cut,
/// `[2i + 1]` to what the second pass still found hidden.
fn check_per_instance(label: &str, f: &Frame, instances: usize) {
    let (software, hardware) = first_lists(f);
    let first = CullResult {
        cut: [software, hardware].concat(),
        occluded: f.candidates.clone(),
        ..CullResult::default()
    };
    let second = CullResult {
        cut: second_list(f),
        ..CullResult::default()
    };
    let want = cpu::occluded_per_instance(&first, Some(&second), instances);
    assert_eq!(f.per_instance, want, "{label}: per-instance counters");
    let sum = |word: usize| f.per_instance.iter().skip(word).step_by(2).sum::<u32>();
    assert_eq!(sum(0), f.first[8], "{label}: cut per instance");
    assert_eq!(sum(1), f.second[9], "{label}: culled per instance");
}

fn check_words(label: &str, got: &[u32; 12], want: &CullResult, near: usize) {
    if near == 0 {
        for w in [0, 1, 2, 3, 5, 6, 7, 8, 9, 10, 11] {
            assert_eq!(got[w], want.counts[w], "{label}: word {w} of {got:?}");
        }
    }
    assert_eq!(got[3], want.counts[3], "{label}: C");
    assert_eq!(got[10], want.counts[10], "{label}: slots of the pass");
}

/// One pass of frame `f` (the first or the second, as `occlusion` says) against the
/// reference's `want` for it: its lists, up to clusters decided differently near a
/// threshold (the first pass's candidates too), its count words and its hardware
/// arguments. Returns how many clusters lay near a threshold.
fn check_pass(
    data: &SceneData,
    view: &View,
    label: &str,
    f: &Frame,
    occlusion: Occlusion,
    want: &CullResult,
) -> usize {
    let second = matches!(occlusion, Occlusion::Second { .. });
    let (pass, words, hw_args) = if second {
        ("second", &f.second, f.second_hw_args)
    } else {
        ("first", &f.first, f.first_hw_args)
    };
    let (software, hardware) = if second {
        second_lists(f)
    } else {
        first_lists(f)
    };
    let lists: [(&[Cluster], &[Cluster]); 3] = if second {
        [
            (&hardware, &want.hardware),
            (&software, &want.software),
            (&[], &[]),
        ]
    } else {
        [
            (&software, &want.software),
            (&hardware, &want.hardware),
            (&f.candidates, &want.occluded),
        ]
    };
    let near = differing(data, view, occlusion, &format!("{label} {pass}"), lists);
    assert!(
        near <= MAX_NEAR_PER_VIEW,
        "{label}: {near} near a threshold"
    );
    check_words(&format!("{label} {pass}"), words, want, near);
    assert_eq!(hw_args, [HW_VERTICES, words[1], 0, 0]);
    near
}

/// Six spot instances; instance 2 was elsewhere last frame.
fn moved_scene() -> SceneData {
    let mut data = scene();
    let id = meshlight_gpu_scene::data::InstanceId(2);
    let m = Mat4::from_scale_rotation_translation(
        Vec3::splat(1.0),
        Quat::from_rotation_y(0.4),
        Vec3::new(0.5, 0.3, 2.0),
    );
    assert!(data.set_transform(id, m).unwrap());
    data
}

/// A random camera, and the one it was last frame (a little orbit and dolly).
fn random_views(rng: &mut Rng, v: u32) -> View {
    let (target, direction) = random_aim(rng, Vec3::new(2.0, 0.3, 1.5), [0.0, 0.8]);
    let distance = rng.range(4.0, 14.0);
    let fov = rng.range(0.7, 1.2);
    let camera = Camera::perspective(target + direction * distance, target, fov, 0.05);
    let turn = Quat::from_rotation_y(rng.range(-0.15, 0.15));
    let last = Camera::perspective(
        target + turn * direction * distance * rng.range(0.9, 1.1),
        target,
        fov,
        0.05,
    );
    let previous = last.view(VIEWPORT, v, None).view_projection;
    camera.view(VIEWPORT, v + 1, Some(Mat4::from_cols_array_2d(&previous)))
}

/// A depth image of a few walls (axis-aligned screen rectangles at one depth each),
/// placed at depths between the camera and the instances so that they hide some
/// clusters and not others; the rest of the image is empty (depth 0).
fn walls(rng: &mut Rng, data: &SceneData, view: &View, count: u32) -> DepthPyramid {
    let [w, h] = VIEWPORT;
    let mut depth = vec![0.0f32; pixels()];
    let eye = Vec3::from(view.camera_position);
    for _ in 0..count {
        let instance = &data.instances[rng.below(data.instances.len() as u32) as usize];
        let at = Vec3::from_slice(&instance.world_from_local[3][..3]);
        let distance = (at - eye).length() * rng.range(0.4, 0.95);
        let d = view.near / distance;
        let (x0, y0) = (rng.below(w * 3 / 4), rng.below(h * 3 / 4));
        let (x1, y1) = (
            (x0 + w / 8 + rng.below(w * 3 / 4)).min(w),
            (y0 + h / 8 + rng.below(h * 3 / 4)).min(h),
        );
        for y in y0..y1 {
            for x in x0..x1 {
                let p = &mut depth[(y * w + x) as usize];
                *p = p.max(d);
            }
        }
    }
    DepthPyramid::from_depth(w, h, &depth)
}

#[test]
fn both_passes_match_the_reference_on_random_views_and_walls() {
    let (mut rng, mut data, clusters) = seeded(0x0cc1_0de5_0000_0001, moved_scene());
    let mut harness = Harness::new(&mut data, &clusters);
    let empty = DepthPyramid::from_depth(VIEWPORT[0], VIEWPORT[1], &vec![0.0; pixels()]);
    let mut totals = [0u32; 4];
    for v in 0..8 {
        let view = random_views(&mut rng, v * 2);
        let count = 3 + rng.below(4);
        let last = walls(&mut rng, &data, &view, count);
        // Every other view, this frame's walls are last frame's: most candidates stay
        // hidden; else new walls: most come back.
        let now = if v % 2 == 0 {
            last.clone()
        } else {
            let count = 3 + rng.below(4);
            walls(&mut rng, &data, &view, count)
        };
        // The frame before puts `last` in the history; its own results do not matter.
        harness.frame(&view, true, &last, &empty);
        let f = harness.frame(&view, false, &empty, &now);
        let label = format!("view {v}");

        let first = Occlusion::First(&last);
        let want = cpu::cpu_cull_with(&data, &view, &clusters, &T, harness.capacity, first);
        let near = check_pass(&data, &view, &label, &f, first, &want);
        assert_eq!(f.candidate_count, [f.first[9]; 2], "{label}: candidates");

        // The second pass, on the candidates the GPU's first pass found.
        let second = Occlusion::Second {
            pyramid: &now,
            first_counts: f.first,
        };
        let want2 = cpu::cpu_cull_with(&data, &view, &f.candidates, &T, harness.capacity, second);
        let near2 = check_pass(&data, &view, &label, &f, second, &want2);
        assert_eq!(
            f.second[7], f.first[0],
            "{label}: second software slots start"
        );
        check_per_instance(&label, &f, data.instances.len());
        if near == 0 && near2 == 0 {
            let want_words = cpu::occluded_per_instance(&want, Some(&want2), data.instances.len());
            assert_eq!(f.per_instance, want_words, "{label}: per instance");
        }
        eprintln!(
            "{label}: first cut {} occluded {} tested {}; second considered {} drawn {} + {} occluded {}",
            f.first[8], f.first[9], f.first[11], f.second[4], f.second[0], f.second[1], f.second[9]
        );
        totals[0] += f.first[9];
        totals[1] += f.first[2];
        totals[2] += f.second[0] + f.second[1];
        totals[3] += f.second[9];
    }
    // The views and walls exercise every outcome of both passes.
    assert!(
        totals.iter().all(|&t| t > 0),
        "first occluded / drawn, second drawn / occluded: {totals:?}"
    );
}

#[test]
fn the_second_pass_tests_only_the_first_passs_candidates_in_the_free_slots() {
    let (_, mut data, clusters) = seeded(0x5ec0_4d00_0000_0002, moved_scene());
    let mut harness = Harness::new(&mut data, &clusters);
    let view = Camera::perspective(Vec3::new(1.0, 2.5, 9.0), Vec3::ZERO, 1.0, 0.05)
        .view(VIEWPORT, 1, None);
    // Last frame: a wall over the left half in front of everything. This frame: nothing
    // hides anything, so every candidate comes back.
    let (w, h) = (VIEWPORT[0], VIEWPORT[1]);
    let mut depth = vec![0.0f32; pixels()];
    for y in 0..h {
        for x in 0..w / 2 {
            depth[(y * w + x) as usize] = view.near / 2.0;
        }
    }
    let last = DepthPyramid::from_depth(w, h, &depth);
    let empty = DepthPyramid::from_depth(w, h, &vec![0.0; pixels()]);
    harness.frame(&view, true, &last, &empty);
    let f = harness.frame(&view, false, &empty, &empty);
    let candidates = f.first[9];
    assert!(candidates > 20, "the wall hides {candidates} clusters");
    // The second pass considered exactly the candidates, and all of them were in the
    // frustum and the cut already.
    assert_eq!(f.candidate_count, [candidates; 2]);
    assert_eq!(
        f.second[4], candidates,
        "clusters the second pass considered"
    );
    assert_eq!(f.second[8], candidates, "of them in the LOD cut");
    assert_eq!(f.second[9], 0, "nothing hides them this frame");
    assert_eq!(
        f.second[0] + f.second[1],
        candidates,
        "every candidate drawn"
    );
    assert!(
        f.second[0] > 0 && f.second[1] > 0,
        "the second pass splits like the first: {} software, {} hardware",
        f.second[0],
        f.second[1]
    );
    assert_eq!(set(&second_list(&f)), set(&f.candidates));
    // Disjoint slots: first software, second software, free, second hardware (from the
    // right of the free range), first hardware; the sentinel in between.
    let c = f.first[3];
    let (sw1, hw1) = (f.first[0], f.first[1]);
    assert_eq!(f.second[3], c - hw1);
    assert_eq!(f.second[7], sw1);
    assert_eq!(f.second[10], c - hw1 - sw1);
    let (software, hardware) = first_lists(&f);
    let all: Vec<Cluster> = [software, hardware, second_list(&f)].concat();
    assert_eq!(set(&all).len(), all.len(), "a cluster drawn twice");
    assert!(all.iter().all(|c| *c != SENTINEL));
    let free = &f.slots[(sw1 + f.second[0]) as usize..(c - hw1 - f.second[1]) as usize];
    assert!(
        free.iter().all(|c| *c == SENTINEL),
        "a free slot was written"
    );
    // Both passes together draw what one pass without occlusion draws.
    let plain = cpu::cpu_cull(&data, &view, &clusters, &T, harness.capacity);
    assert_eq!(set(&all), set(&plain.cut));
    // Every candidate came back: the counters of every instance say nothing was culled.
    check_per_instance("wall", &f, data.instances.len());
    assert!(f.per_instance.iter().skip(1).step_by(2).all(|&w| w == 0));
}

#[test]
fn with_no_valid_history_or_on_a_camera_cut_the_first_pass_culls_nothing_by_occlusion() {
    // With the per-instance counters bound, and without (the untested kernel).
    for per_instance in [true, false] {
        no_test_culls_nothing(per_instance);
    }
}

fn no_test_culls_nothing(per_instance: bool) {
    let (_, mut data, clusters) = seeded(0x1157_0e41_0000_0003, moved_scene());
    let mut harness = Harness::with(&mut data, &clusters, per_instance);
    let view = Camera::perspective(Vec3::new(-2.0, 3.0, 10.0), Vec3::ZERO, 1.1, 0.05)
        .view(VIEWPORT, 1, None);
    // A wall over the whole screen, nearer than everything: with a valid history it
    // hides nearly every cluster (checked below, so the test can fail).
    let wall = DepthPyramid::from_depth(VIEWPORT[0], VIEWPORT[1], &vec![view.near / 1.0; pixels()]);
    let plain = cpu::cpu_cull_with(
        &data,
        &view,
        &clusters,
        &T,
        harness.capacity,
        Occlusion::Skipped,
    );
    let check = |f: &Frame, label: &str| {
        assert_eq!(f.first[9], 0, "{label}: occluded");
        assert_eq!(f.first[11], 0, "{label}: tested");
        assert_eq!(f.candidate_count, [0, 0], "{label}: candidates");
        assert_eq!(
            f.second[4], 0,
            "{label}: the second pass considered clusters"
        );
        let (software, hardware) = first_lists(f);
        let near = differing(
            &data,
            &view,
            Occlusion::Skipped,
            label,
            [
                (&software, &plain.software),
                (&hardware, &plain.hardware),
                (&[], &[]),
            ],
        );
        check_words(label, &f.first, &plain, near);
    };
    // Frame 0: the history was just made.
    let f = harness.frame(&view, false, &wall, &wall);
    check(&f, "first frame");
    // Frame 1 with a camera cut: the history is valid but says nothing.
    let f = harness.frame(&view, true, &wall, &wall);
    check(&f, "camera cut");
    // Frame 2: valid and no cut; the same wall now hides clusters.
    let f = harness.frame(&view, false, &wall, &wall);
    let hidden = cpu::cpu_cull_with(
        &data,
        &view,
        &clusters,
        &T,
        harness.capacity,
        Occlusion::First(&wall),
    );
    assert!(
        hidden.occluded.len() * 2 > plain.cut.len(),
        "{} of {}",
        hidden.occluded.len(),
        plain.cut.len()
    );
    assert!(
        f.first[9] as usize * 2 > plain.cut.len(),
        "the valid history hid only {}",
        f.first[9]
    );
    // Frame 3, a cut after a frame that listed candidates: none is left for the second
    // pass.
    let f = harness.frame(&view, true, &wall, &wall);
    check(&f, "camera cut after a tested frame");
}
