//! No false culling: two-pass occlusion culling draws, on every frame of a scripted camera
//! path, the same visibility target as the frame without occlusion. The path orbits a
//! wall with instances behind it (three small ones wholly hidden), pans fast, teleports (with and without telling the
//! renderer it was a cut), moves an instance out from behind the wall, and changes the
//! viewport size. At every pixel the depth and the scene triangle (instance, meshlet,
//! triangle) must be the same; only pixels where two triangles tie exactly in depth may
//! show the other one (the tie goes to the larger slot id, and slots differ between the
//! two frames), and they are counted and bounded. Both culling passes split clusters
//! between the rasterisers by the current view alone, as the frame without occlusion
//! does, so each cluster is rasterised the same way in both frames: the comparison holds
//! with every cluster sent to the hardware rasteriser and with the shipped split.

mod common;

use glam::{Mat4, Quat, Vec2, Vec3};
use meshlight::gpu_scene::data::InstanceId;
use meshlight::gpu_scene::{Camera, SceneData};
use meshlight::scene::terrain::Terrain;
use meshlight::scene::{BuildOptions, MeshletAsset, build_asset};
use meshlight::shaders::cpu::layout::Cluster;
use meshlight::shaders::cpu::visbuffer;
use meshlight_virtual_geometry::adaptive_occlusion::{FramePlan, hidden_share};
use meshlight_virtual_geometry::counts::OcclusionCounts;
use meshlight_virtual_geometry::{FrameSettings, GraphSource, OcclusionPolicy, Renderer};
use std::sync::OnceLock;

/// A flat 4 × 4 square on the x–z plane, facing +y: a solid occluder.
fn panel_asset() -> &'static MeshletAsset {
    static ASSET: OnceLock<MeshletAsset> = OnceLock::new();
    ASSET.get_or_init(|| {
        let terrain = Terrain {
            origin: Vec2::splat(-2.0),
            size: 4.0,
            cells: 16,
            amplitude: 0.0,
            wavelength: 4.0,
            octaves: 1,
            seed: 7,
            uv_scale: 1.0,
            calm_centre: Vec2::ZERO,
            calm_radius: 0.0,
        };
        let mesh = terrain.mesh().unwrap();
        build_asset(&mesh, &BuildOptions::default(), &mut |_| {})
            .unwrap()
            .asset
    })
}

/// The instance that comes out from behind the wall.
const MOVER: InstanceId = InstanceId(1);

/// A wall (a flattened, widened mesh) at z = 0, the mover behind its middle, and a
/// 4 × 3 grid of instances behind it and beside it.
fn scene() -> SceneData {
    let (mut data, mesh, material) = common::grey_scene();
    let mut place = |m: Mat4| data.add_instance(mesh, m, material).unwrap().unwrap();
    place(Mat4::from_scale_rotation_translation(
        Vec3::new(5.0, 3.0, 0.4),
        Quat::IDENTITY,
        Vec3::ZERO,
    ));
    place(mover_at(0.0));
    for i in 0..12 {
        let (x, z) = ((i % 4) as f32 * 2.5 - 3.75, -3.0 - (i / 4) as f32 * 2.5);
        place(Mat4::from_scale_rotation_translation(
            Vec3::splat(0.8),
            Quat::from_rotation_y(i as f32),
            Vec3::new(x, (i % 3) as f32 * 0.6 - 0.6, z),
        ));
    }
    // A solid panel (the wall has holes: it is a flattened knot) standing behind the
    // wall, facing the orbit, and three small instances right behind it: whole
    // instances the pyramid hides, so the walk hides nodes, not only cull clusters.
    let panel = data.add_mesh("panel", panel_asset()).unwrap();
    data.add_instance(
        panel,
        Mat4::from_scale_rotation_translation(
            Vec3::new(2.0, 1.0, 1.5),
            Quat::from_rotation_x(std::f32::consts::FRAC_PI_2),
            Vec3::new(0.0, 0.5, -0.7),
        ),
        material,
    )
    .unwrap()
    .unwrap();
    let mut place = |m: Mat4| data.add_instance(mesh, m, material).unwrap().unwrap();
    for k in 0..3 {
        place(Mat4::from_scale_rotation_translation(
            Vec3::splat(0.08),
            Quat::from_rotation_y(k as f32),
            Vec3::new(k as f32 * 1.2 - 1.2, 0.5, -2.2),
        ));
    }
    data
}

/// The mover `t` of the way out from behind the wall (0: hidden, 1: beside it).
fn mover_at(t: f32) -> Mat4 {
    Mat4::from_scale_rotation_translation(
        Vec3::splat(0.9),
        Quat::from_rotation_y(t * 2.0),
        Vec3::new(t * 7.0, 0.0, -1.5),
    )
}

/// One step of the path: the camera, where the mover is, and whether the renderer is
/// told it is a cut.
struct Step {
    label: &'static str,
    camera: Camera,
    mover: f32,
    cut: bool,
}

fn look(from: Vec3, at: Vec3) -> Camera {
    Camera::perspective(from, at, 1.0, 0.05)
}

fn path() -> Vec<Step> {
    let mut steps = Vec::new();
    let orbit = |a: f32| look(Vec3::new(a.sin() * 11.0, 2.0, a.cos() * 11.0), Vec3::ZERO);
    for k in 0..4 {
        steps.push(Step {
            label: "orbit",
            camera: orbit(k as f32 * 0.08),
            mover: 0.0,
            cut: false,
        });
    }
    for k in 1..3 {
        steps.push(Step {
            label: "fast pan",
            camera: look(
                Vec3::new(0.0, 2.0, 11.0),
                Vec3::new((k as f32 * 0.6).sin() * 8.0, 0.0, 0.0),
            ),
            mover: 0.0,
            cut: false,
        });
    }
    steps.push(Step {
        label: "teleport behind, told",
        camera: look(Vec3::new(2.0, 3.0, -14.0), Vec3::new(0.0, 0.0, -2.0)),
        mover: 0.0,
        cut: true,
    });
    steps.push(Step {
        label: "teleport back, not told",
        camera: orbit(0.1),
        mover: 0.0,
        cut: false,
    });
    for k in 1..5 {
        steps.push(Step {
            label: "mover comes out",
            camera: orbit(0.1),
            mover: k as f32 * 0.25,
            cut: false,
        });
    }
    steps
}

fn renderer(occlusion: bool, split: Option<f32>, width: u32, height: u32) -> Renderer {
    renderer_with(OcclusionPolicy::ALWAYS, occlusion, split, width, height)
}

fn renderer_with(
    policy: OcclusionPolicy,
    occlusion: bool,
    split: Option<f32>,
    width: u32,
    height: u32,
) -> Renderer {
    let settings = FrameSettings {
        occlusion,
        occlusion_policy: policy,
        keep_visibility: true,
        // `Some(0.0)`: every cluster to the hardware rasteriser; `None`: the adapter
        // class's split.
        sw_threshold_px: split,
        depth: false,
        material_depth: false,
        ..FrameSettings::new(width, height)
    };
    Renderer::new(scene(), settings, &GraphSource::Shipped).unwrap_or_else(|e| panic!("{e}"))
}

/// The frame's visibility target as (depth bits, instance, meshlet, triangle) per pixel.
fn visibility(r: &mut Renderer) -> Vec<(u32, u32, u32, u32)> {
    let values: Vec<u64> =
        bytemuck::pod_collect_to_vec(&r.executor.read_buffer("visbuffer").unwrap());
    let slots: Vec<Cluster> =
        bytemuck::pod_collect_to_vec(&r.executor.read_buffer("raster_clusters").unwrap());
    values
        .iter()
        .map(|&v| {
            if v == visbuffer::EMPTY {
                return (0, u32::MAX, u32::MAX, u32::MAX);
            }
            let c = slots[visbuffer::cluster(v) as usize];
            (
                visbuffer::depth(v).to_bits(),
                c.instance,
                c.meshlet,
                visbuffer::triangle(v),
            )
        })
        .collect()
}

/// Renders `step` with both renderers and compares; returns the occlusion counters and
/// the pixels that differ only by an exact depth tie.
fn compare(
    with: &mut Renderer,
    without: &mut Renderer,
    step: &Step,
    frame: usize,
) -> (OcclusionCounts, usize) {
    let (counts, ties) = compare_images(with, without, step, frame);
    (
        counts.expect("the two-pass frame reads both counters back"),
        ties,
    )
}

/// [`compare`], for a frame that may have left its second pass out (`None`).
fn compare_images(
    with: &mut Renderer,
    without: &mut Renderer,
    step: &Step,
    frame: usize,
) -> (Option<OcclusionCounts>, usize) {
    for r in [&mut *with, &mut *without] {
        r.set_transform(MOVER, mover_at(step.mover)).unwrap();
    }
    if step.cut {
        with.camera_cut();
    }
    let a = with
        .render_still(&step.camera)
        .unwrap_or_else(|e| panic!("{e}"));
    let b = without
        .render_still(&step.camera)
        .unwrap_or_else(|e| panic!("{e}"));
    assert_eq!((a.frames, b.frames), (1, 1), "no list overflowed");
    let (va, vb) = (visibility(with), visibility(without));
    let mut ties = 0;
    let mut lost = Vec::new();
    for (i, (p, q)) in va.iter().zip(&vb).enumerate() {
        if p == q {
            continue;
        }
        if p.0 == q.0 {
            ties += 1;
        } else {
            lost.push((i, *p, *q));
        }
    }
    let counts = a.counts.occlusion;
    assert!(
        lost.is_empty(),
        "frame {frame} ({}): {} pixels differ in depth from the frame without occlusion, e.g. pixel {} has {:?}, should have {:?}; counters {counts:?}",
        step.label,
        lost.len(),
        lost[0].0,
        lost[0].1,
        lost[0].2
    );
    match counts {
        Some(c) => eprintln!(
            "frame {frame} ({}): drawn {} clusters ({} in the second pass), first pass tested {} occluded {}, second pass considered {} occluded {}, ties {ties}",
            step.label,
            a.counts.visible,
            c.second_drawn,
            c.first_tested,
            c.first_occluded,
            c.second_considered,
            c.second_occluded
        ),
        None => eprintln!(
            "frame {frame} ({}): drawn {} clusters in one pass ({:?}), ties {ties}",
            step.label,
            a.counts.visible,
            with.last_frame_plan()
        ),
    }
    (counts, ties)
}

#[test]
fn two_pass_occlusion_never_culls_what_the_frame_without_it_draws_all_in_hardware() {
    no_false_culling(Some(0.0));
}

#[test]
fn two_pass_occlusion_never_culls_what_the_frame_without_it_draws_with_the_default_split() {
    no_false_culling(None);
}

fn no_false_culling(split: Option<f32>) {
    let (w, h) = (160, 96);
    let mut with = renderer(true, split, w, h);
    let mut without = renderer(false, split, w, h);
    let mut rasterisers = [0u32; 2];
    let mut second_software = 0;
    let mut totals = OcclusionCounts::default();
    let mut ties = 0;
    // The walks' node-level occlusion: nodes handed to the second walk, those it found
    // still hidden, and the clusters it listed below the others.
    let mut walk = [0u32; 3];
    let mut instances_culled = 0;
    let steps = path();
    for (frame, step) in steps.iter().enumerate() {
        let (c, t) = compare(&mut with, &mut without, step, frame);
        let counts = with.latest_counts().expect("counters read back");
        rasterisers[0] += counts.software;
        rasterisers[1] += counts.hardware;
        let h = counts
            .hierarchy
            .expect("the default frame walks the hierarchy");
        let second_walk = h.second.expect("a two-pass frame walks twice");
        // Every instance's root is tested once, before any of its clusters; those out
        // of view or hidden by last frame's depth go no further.
        let instances = h.instances.expect("room for the instance counters");
        assert_eq!(instances.tested as usize, with.data.instances.len());
        assert!(instances.visible <= instances.tested, "{instances:?}");
        instances_culled += instances.tested - instances.visible;
        walk[0] += h.hidden_nodes;
        walk[1] += second_walk.still_hidden;
        walk[2] += second_walk.clusters_listed;
        if frame == 0 || step.cut {
            assert_eq!(
                h.hidden_nodes, 0,
                "frame {frame} hid nodes without a history"
            );
        }
        let second: Vec<u32> = bytemuck::pod_collect_to_vec(
            &with.executor.read_buffer("raster_counts_second").unwrap(),
        );
        second_software += second[0];
        // No history on the first frame; a cut says the history is no use.
        if frame == 0 || step.cut {
            assert_eq!(
                (c.first_tested, c.first_occluded),
                (0, 0),
                "frame {frame} ({}) tested against last frame's depth",
                step.label
            );
        }
        totals.first_occluded += c.first_occluded;
        totals.second_drawn += c.second_drawn;
        totals.second_occluded += c.second_occluded;
        ties += t;
    }
    // The mover's last move was drawn: its previous transform is now that one.
    let mover = &with.data.instances[MOVER.0 as usize];
    assert_eq!(mover.previous_world_from_local, mover.world_from_local);
    // A resize: new targets, a new history; its first frame tests nothing.
    let (w2, h2) = (128, 120);
    let mut with = renderer(true, split, w2, h2);
    let mut without = renderer(false, split, w2, h2);
    for (k, step) in steps[..3].iter().enumerate() {
        let (c, t) = compare(&mut with, &mut without, step, steps.len() + k);
        if k == 0 {
            assert_eq!(c.first_tested, 0, "the first frame at the new size tested");
        }
        ties += t;
    }
    // The path exercised both passes: clusters hidden by last frame's depth, some of
    // them drawn by the second pass (the mover, the teleport), others culled for good.
    assert!(totals.first_occluded > 0, "{totals:?}");
    assert!(totals.second_drawn > 0, "{totals:?}");
    assert!(totals.second_occluded > 0, "{totals:?}");
    // The same at the node level: whole subtrees (instances) hidden by last frame's
    // depth, some still hidden in this frame's, some listed again for the second cull.
    assert!(
        walk.iter().all(|&n| n > 0),
        "hidden, still hidden, listed: {walk:?}"
    );
    assert!(instances_culled > 0, "no instance culled at its root");
    // The split under test: all hardware, or both rasterisers drawing.
    if split == Some(0.0) {
        assert_eq!(
            rasterisers[0], 0,
            "software clusters with every one to hardware"
        );
    } else {
        assert!(rasterisers.iter().all(|&n| n > 0), "{rasterisers:?}");
        assert!(
            second_software > 0,
            "the second pass drew nothing in software"
        );
    }
    let pixels = (steps.len() as u32 * w * h + 3 * w2 * h2) as usize;
    eprintln!("exact depth ties that went the other way: {ties} of {pixels} pixels");
    assert!(ties * 200 <= pixels, "{ties} ties in {pixels} pixels");
}

fn pipeline(name: &str) -> GraphSource {
    GraphSource::File(std::path::PathBuf::from(format!(
        "{}/pipelines/{name}",
        concat!(env!("CARGO_MANIFEST_DIR"), "/../..")
    )))
}

#[test]
fn the_pipeline_files_run_the_frames_built_in_code() {
    let (w, h) = (160, 96);
    let steps = path();
    for (file, occlusion) in [
        ("virtual_geometry.toml", true),
        ("virtual_geometry_one_pass.toml", false),
    ] {
        let settings = FrameSettings {
            occlusion,
            occlusion_policy: OcclusionPolicy::ALWAYS,
            ..FrameSettings::new(w, h)
        };
        let mut code = Renderer::new(scene(), settings.clone(), &GraphSource::Shipped).unwrap();
        let mut loaded = Renderer::new(scene(), settings, &pipeline(file)).unwrap();
        // Moving frames, so the two-pass frame has history to test against.
        for step in &steps[..5] {
            let a = code.render_still(&step.camera).unwrap();
            let b = loaded.render_still(&step.camera).unwrap();
            assert_eq!(a.counts, b.counts, "{file}, {}", step.label);
            assert_eq!(a.counts.occlusion.is_some(), occlusion, "{file}");
            // Slots are handed out by atomics, so where two triangles tie exactly in depth
            // the one with the larger slot wins, and the order can change between runs:
            // a few pixels may show the other triangle.
            let differ = a
                .rgba
                .chunks(4)
                .zip(b.rgba.chunks(4))
                .filter(|(p, q)| p != q)
                .count();
            assert!(
                differ * 1000 <= (w * h) as usize,
                "{file}, {}: the images differ in {differ} pixels",
                step.label
            );
        }
        let tested = code
            .latest_counts()
            .unwrap()
            .occlusion
            .map(|o| o.first_tested);
        assert!(!occlusion || tested > Some(0), "{file}: {tested:?}");
    }
}

/// Occlusion tested only while it pays: where the view hides little, a two-pass frame
/// stops testing and leaves its second pass and pyramid out; where a wall hides much, it
/// tests again within a probe. Every frame's visibility target equals the frame without
/// occlusion's, through both switches, a cut told and untold, and the mover coming out.
#[test]
fn adaptive_occlusion_stops_and_resumes_testing_and_draws_what_the_frame_without_it_does() {
    let (w, h) = (160, 96);
    // Above the scene, looking down: the instances stand side by side, little is hidden.
    let open = look(Vec3::new(0.5, 16.0, -2.0), Vec3::new(0.0, 0.0, -2.5));
    // Facing the wall: the three small instances and the panel's neighbours are hidden.
    let walled = look(Vec3::new(0.0, 2.0, 11.0), Vec3::ZERO);
    // The share each view hides, from frames that test every time.
    let share = |camera: &Camera| {
        let mut r = renderer(true, None, w, h);
        r.render_still(camera).unwrap();
        let c = r.render_still(camera).unwrap().counts;
        hidden_share(&c).expect("the second frame tested")
    };
    let (little, much) = (share(&open), share(&walled));
    eprintln!("hidden share: {little} looking down, {much} facing the wall");
    assert!(much > 2.0 * little + 0.02, "{little} against {much}");
    let policy = OcclusionPolicy {
        min_hidden: (little + much) / 2.0,
        probe_every: 4,
    };
    let mut with = renderer_with(policy, true, None, w, h);
    let mut without = renderer(false, None, w, h);
    assert!(with.culls_in_two_passes() && !without.culls_in_two_passes());
    let step = |label, camera, cut| Step {
        label,
        camera,
        mover: 0.0,
        cut,
    };
    let mut steps: Vec<Step> = (0..12).map(|_| step("looking down", open, false)).collect();
    steps.push(step("to the wall, told", walled, true));
    steps.extend((0..8).map(|_| step("facing the wall", walled, false)));
    steps.push(step("looking down, not told", open, false));
    steps.extend((0..8).map(|k| Step {
        mover: 0.125 * k as f32,
        ..step("looking down, mover out", open, false)
    }));
    let mut plans = Vec::new();
    for (frame, s) in steps.iter().enumerate() {
        let (counts, ties) = compare_images(&mut with, &mut without, s, frame);
        let plan = with.last_frame_plan();
        assert_eq!(
            counts.is_some(),
            plan.second,
            "frame {frame}: the counters of the second pass come back exactly when it runs"
        );
        assert!(ties * 100 <= (w * h) as usize, "{ties} ties");
        plans.push((s.label, plan, with.tests_occlusion()));
    }
    let off = |range: std::ops::Range<usize>| {
        plans[range]
            .iter()
            .filter(|(_, p, _)| !p.pyramid && !p.second)
            .count()
    };
    // Looking down: testing stops after three tested frames; frames without a pyramid
    // outnumber the probes' (a pyramid frame, then a tested one).
    assert!(off(0..12) >= 6, "{plans:?}");
    assert!(plans[4..8].iter().all(|(_, p, _)| !p.pyramid), "{plans:?}");
    // Facing the wall: within a probe, the frames test again and go on testing.
    let back = (12..21)
        .find(|&f| plans[f].1.test)
        .expect("a probe facing the wall");
    assert!(
        back <= 12 + 4 + 2,
        "testing resumed at frame {back}: {plans:?}"
    );
    assert!(
        plans[back..21]
            .iter()
            .all(|(_, p, t)| *p == FramePlan::FULL && *t),
        "{plans:?}"
    );
    // Looking down again (a move the renderer was not told of, drawn by the second
    // pass): testing stops again.
    assert_eq!(plans[21].1, FramePlan::FULL);
    assert!(off(22..30) >= 4, "{plans:?}");
}
