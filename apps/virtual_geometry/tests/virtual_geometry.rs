//! The whole virtual-geometry frame on the GPU (lavapipe in CI), at small sizes: the
//! pipeline file against the graph built in code, growth after overflow, the software
//! rasteriser alone against the mixed split, cracks and LOD continuity, golden images,
//! and the bad inputs of a scene and a viewport.

mod common;

use common::asset;
use glam::{Mat4, Quat, Vec3};
use meshlight::gpu_scene::data::{InstanceId, Limits};
use meshlight::gpu_scene::{Camera, SceneData, SceneDataError};
use meshlight::graph::GraphError;
use meshlight::resolve::DebugView;
use meshlight_virtual_geometry::scenes::{self, Placed};
use meshlight_virtual_geometry::{FrameSettings, GraphSource, Renderer, Still};
use std::path::PathBuf;

const W: u32 = 192;
const H: u32 = 108;

fn field(instances: u32) -> Placed {
    scenes::field(SceneData::new(Limits::default()), asset(), instances).unwrap()
}

fn pipeline_file() -> GraphSource {
    shipped_file("virtual_geometry")
}

/// A shipped pipeline file, read from the repository as a user would pass it.
fn shipped_file(name: &str) -> GraphSource {
    GraphSource::File(
        PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/../.."))
            .join(format!("pipelines/{name}.toml")),
    )
}

fn render(placed: &Placed, settings: FrameSettings, source: &GraphSource) -> (Still, Renderer) {
    let mut r =
        Renderer::new(placed.data.clone(), settings, source).unwrap_or_else(|e| panic!("{e}"));
    let still = r
        .render_still(&placed.camera)
        .unwrap_or_else(|e| panic!("{e}"));
    (still, r)
}

fn settings(view: DebugView) -> FrameSettings {
    FrameSettings::new(W, H).with_view(view)
}

/// Whether the compiled frame runs the pass named `name`.
fn runs(r: &Renderer, name: &str) -> bool {
    let plan = &r.compiled.plan;
    plan.order.iter().any(|&i| plan.passes[i].name == name)
}

/// Pixels whose colour differs in any channel by more than `tolerance`.
fn differing(a: &[u8], b: &[u8], tolerance: u8) -> usize {
    assert_eq!(a.len(), b.len());
    a.chunks(4)
        .zip(b.chunks(4))
        .filter(|(p, q)| {
            p.iter()
                .zip(q.iter())
                .any(|(x, y)| x.abs_diff(*y) > tolerance)
        })
        .count()
}

/// Whether a pixel of the cluster view is background (black).
fn empty(rgba: &[u8], i: usize) -> bool {
    rgba[i * 4..i * 4 + 3] == [0, 0, 0]
}

/// The renderer's shipped frame is the shipped file: with occlusion it is
/// `pipelines/virtual_geometry.toml`, without it `virtual_geometry_one_pass.toml`, and
/// either, read from disk as a user passes it, draws the same image with the same plan.
#[test]
fn the_shipped_frame_and_the_shipped_files_give_identical_plans_and_images() {
    let placed = field(16);
    for (occlusion, file) in [
        (true, "virtual_geometry"),
        (false, "virtual_geometry_one_pass"),
    ] {
        for view in [
            DebugView::Shaded,
            DebugView::Clusters,
            DebugView::Lod,
            DebugView::Raster,
        ] {
            let s = FrameSettings {
                occlusion,
                ..settings(view)
            };
            let (shipped, a) = render(&placed, s.clone(), &GraphSource::Shipped);
            let (read, b) = render(&placed, s, &shipped_file(file));
            assert_eq!(shipped.counts, read.counts, "{file} {view:?}");
            assert!(
                shipped.counts.visible > 0 && shipped.counts.software > 0,
                "{:?}",
                shipped.counts
            );
            assert_eq!(
                differing(&shipped.rgba, &read.rgba, 0),
                0,
                "{file} {view:?}"
            );
            let (pa, pb) = (&a.compiled.plan, &b.compiled.plan);
            let passes = |p: &meshlight::graph::Plan| {
                p.passes
                    .iter()
                    .map(|x| (x.name.clone(), x.implementation, x.decision()))
                    .collect::<Vec<_>>()
            };
            assert_eq!(passes(pa), passes(pb), "{file}");
            assert_eq!(pa.batches, pb.batches, "{file}");
            assert!(runs(&a, "hw_raster"));
            assert_eq!(runs(&a, "cull_second"), occlusion, "{file}");
        }
    }
}

#[test]
fn a_slot_buffer_far_too_small_overflows_grows_and_then_renders_the_right_image() {
    // Shaded: hardware clusters' ids depend on the slot count, their colours do not.
    let placed = field(16);
    let (want, _) = render(&placed, settings(DebugView::Shaded), &GraphSource::Shipped);
    assert_eq!(want.frames, 1, "the default lists hold this scene");
    let small = FrameSettings {
        clusters: Some(64),
        slots: Some(8),
        ..settings(DebugView::Shaded)
    };
    let (got, r) = render(&placed, small, &GraphSource::Shipped);
    // The first frame dropped candidates and slots, and each grow is logged. The slots
    // can only count the clusters the candidate list let through, so they may grow
    // again on the second frame: within three frames the image is right.
    assert_eq!(r.growths[0].param, "clusters", "{:?}", r.growths);
    assert_eq!(r.growths[0].from, 64);
    let last = |param: &str| {
        r.growths
            .iter()
            .rev()
            .find(|g| g.param == param)
            .unwrap()
            .to
    };
    assert!(last("clusters") >= want.counts.clusters_requested as u64);
    assert!(
        last("slots") >= want.counts.visible as u64,
        "{:?}",
        r.growths
    );
    assert!((2..=3).contains(&got.frames), "{} frames", got.frames);
    assert!(!got.counts.overflowed());
    let mut want_counts = want.counts;
    want_counts.frame = got.counts.frame;
    want_counts.slots = got.counts.slots;
    // The later frames test occlusion against the frame before (the first cannot, and
    // so leaves its second pass out: no second walk either); the field hides nothing,
    // so every other counter is the same.
    if let Some(occlusion) = got.counts.occlusion {
        assert_eq!(occlusion.first_occluded, 0, "{occlusion:?}");
    }
    want_counts.occlusion = got.counts.occlusion;
    if let (Some(want), Some(got)) = (&mut want_counts.hierarchy, got.counts.hierarchy) {
        want.second = got.second;
    }
    assert_eq!(got.counts, want_counts);
    assert_eq!(differing(&got.rgba, &want.rgba, 0), 0);
}

/// The frame with `settings`, where both rasterisers draw, and the same frame with no
/// hardware rasteriser, which draws the same clusters in software.
fn with_and_without_hardware(placed: &Placed, settings: FrameSettings) -> (Still, Still) {
    let (mixed, r) = render(placed, settings.clone(), &GraphSource::Shipped);
    assert!(runs(&r, "hw_raster"));
    assert!(mixed.counts.hardware > 0, "{:?}", mixed.counts);
    let all_sw = FrameSettings {
        hardware: Some(false),
        ..settings
    };
    let (software, r) = render(placed, all_sw, &GraphSource::Shipped);
    assert!(!runs(&r, "hw_raster"));
    assert_eq!(software.counts.hardware, 0);
    assert_eq!(software.counts.visible, mixed.counts.visible);
    (mixed, software)
}

/// Asserts that at most one pixel in `one_in` of the `W` × `H` frame differs by more
/// than 2/255 between `software` and `mixed`; the count is logged as differing `how`.
fn assert_few_differ(software: &Still, mixed: &Still, one_in: usize, how: &str) {
    let pixels = (W * H) as usize;
    let diff = differing(&software.rgba, &mixed.rgba, 2);
    eprintln!("{diff} of {pixels} pixels differ {how}");
    assert!(diff * one_in <= pixels, "{diff} of {pixels} pixels differ");
}

/// The first instance's bounding-sphere centre, placed in the world, and its mesh's
/// radius as the mesh has it (the cameras below are set by it, not by the instance's scale).
fn first_instance_sphere(p: &Placed) -> (Vec3, f32) {
    let s = p.data.meshes[0].bounding_sphere;
    let centre = Mat4::from_cols_array_2d(&p.data.instances[0].world_from_local)
        .transform_point3(Vec3::new(s[0], s[1], s[2]));
    (centre, s[3])
}

#[test]
fn drawing_everything_in_software_changes_only_pixels_on_edges() {
    // The shaded view: the cluster and triangle views name slots, which differ when the
    // split differs.
    let placed = field(16);
    // A low software threshold, so that at this small size both rasterisers draw.
    let mixed_settings = FrameSettings {
        sw_threshold_px: Some(16.0),
        ..settings(DebugView::Shaded)
    };
    let (mixed, software) = with_and_without_hardware(&placed, mixed_settings);
    // The two rasterisers round edges differently (see hw_raster's docs): the stated
    // tolerance is 2% of the pixels differing by more than 2/255.
    assert_few_differ(&software, &mixed, 50, "between all-software and mixed");
}

#[test]
fn clusters_crossing_the_near_plane_clip_in_software_as_the_hardware_rasteriser_clips() {
    // The camera inside the first mesh's bounding sphere, close to its surface, with a
    // near plane that cuts clusters: on this adapter class they go to hw_raster.
    let placed = {
        let mut p = field(4);
        let (centre, radius) = first_instance_sphere(&p);
        let eye = centre + Vec3::new(0.55, 0.3, 0.2) * radius;
        p.camera = Camera::perspective(eye, centre, 1.3, radius * 0.12);
        p
    };
    let (mixed, software) = with_and_without_hardware(&placed, settings(DebugView::Shaded));
    // Only pixels on the edges of clipped triangles may differ, and few do: skipping
    // the triangles that cross the near plane (as before clipping) changed 1.7%.
    assert_few_differ(
        &software,
        &mixed,
        200,
        "with the near clusters clipped in software",
    );
}

#[test]
fn no_background_shows_through_a_closed_mesh_drawn_at_a_mixed_lod_cut() {
    // One mesh seen along its length: near clusters at LOD 0, far ones coarser.
    let placed = {
        let mut p = field(1);
        let (centre, radius) = first_instance_sphere(&p);
        p.camera = Camera::perspective(
            centre + Vec3::new(0.3, 0.25, 1.0) * radius * 1.6,
            centre,
            1.0,
            radius * 0.01,
        );
        p
    };
    let (w, h) = (384usize, 216usize);
    let cut_settings = FrameSettings {
        view: Some(DebugView::Lod),
        lod_threshold_px: Some(1.0),
        ..FrameSettings::new(w as u32, h as u32)
    };
    let (cut, _) = render(&placed, cut_settings.clone(), &GraphSource::Shipped);
    let levels: std::collections::HashSet<[u8; 3]> = cut
        .rgba
        .chunks(4)
        .filter(|p| p[..3] != [0, 0, 0])
        .map(|p| [p[0], p[1], p[2]])
        .collect();
    assert!(levels.len() >= 2, "the cut shows {} level(s)", levels.len());
    // The same view at LOD 0 (threshold 0 keeps only LOD-0 meshlets) is the mesh's true
    // coverage. Within a pixel of error the silhouettes may differ by a pixel, so only
    // pixels LOD 0 covers with their whole 5 × 5 neighbourhood are inside; any of them
    // left empty by the mixed cut is a crack between clusters.
    let (lod0, _) = render(
        &placed,
        FrameSettings {
            lod_threshold_px: Some(0.0),
            ..cut_settings
        },
        &GraphSource::Shipped,
    );
    let inside = |x: usize, y: usize| {
        (y - 2..=y + 2).all(|yy| (x - 2..=x + 2).all(|xx| !empty(&lod0.rgba, yy * w + xx)))
    };
    let mut cracks = Vec::new();
    let mut interior = 0;
    for y in 2..h - 2 {
        for x in 2..w - 2 {
            if inside(x, y) {
                interior += 1;
                if empty(&cut.rgba, y * w + x) {
                    cracks.push((x, y));
                }
            }
        }
    }
    assert!(interior > w * h / 20, "{interior} interior pixels");
    assert!(
        cracks.is_empty(),
        "background inside the silhouette at {cracks:?}"
    );
}

#[test]
fn under_one_pixel_of_error_the_depth_agrees_with_lod_zero() {
    let placed = field(9);
    let depth_of = |threshold: f32| {
        let s = FrameSettings {
            lod_threshold_px: Some(threshold),
            depth: true,
            ..settings(DebugView::Shaded)
        };
        let (_, mut r) = render(&placed, s, &GraphSource::Shipped);
        let bytes = r.executor.read_texture("depth").unwrap();
        bytemuck::pod_collect_to_vec::<u8, f32>(&bytes)
    };
    let cut = depth_of(1.0);
    // A threshold of 0 keeps only LOD-0 meshlets (their own error is 0).
    let lod0 = depth_of(0.0);
    let covered = lod0.iter().filter(|d| **d > 0.0).count();
    assert!(covered > (W * H) as usize / 20, "{covered} pixels covered");
    let agree = cut
        .iter()
        .zip(&lod0)
        .filter(|(a, b)| (**a == 0.0) == (**b == 0.0) && (*a - *b).abs() <= 0.01 * b.abs())
        .count();
    let pixels = (W * H) as usize;
    assert!(
        agree * 100 >= pixels * 99,
        "{agree} of {pixels} pixels agree"
    );
}

/// Compares `still` with `tests/golden/{name}.png` (`UPDATE_SNAPSHOTS=1` rewrites it).
/// Tolerance: 2/255 per channel, on all but 0.5% of the pixels (float rounding of another
/// Vulkan driver may move an edge pixel).
fn check_golden(name: &str, still: &Still) {
    let (w, h) = (still.width, still.height);
    let path = PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/tests/golden"))
        .join(format!("{name}.png"));
    if std::env::var_os("UPDATE_SNAPSHOTS").is_some() {
        std::fs::create_dir_all(path.parent().unwrap()).unwrap();
        let mut enc = png::Encoder::new(std::fs::File::create(&path).unwrap(), w, h);
        enc.set_color(png::ColorType::Rgba);
        enc.write_header()
            .unwrap()
            .write_image_data(&still.rgba)
            .unwrap();
        return;
    }
    let decoder = png::Decoder::new(std::io::BufReader::new(
        std::fs::File::open(&path)
            .unwrap_or_else(|e| panic!("{}: {e}; UPDATE_SNAPSHOTS=1 writes it", path.display())),
    ));
    let mut reader = decoder.read_info().unwrap();
    assert_eq!(
        (reader.info().width, reader.info().height),
        (w, h),
        "{name}"
    );
    let mut golden = vec![0; reader.output_buffer_size().unwrap()];
    reader.next_frame(&mut golden).unwrap();
    let diff = differing(&still.rgba, &golden, 2);
    assert!(
        diff * 200 <= (w * h) as usize,
        "{name}: {diff} pixels differ from {}",
        path.display()
    );
}

#[test]
fn golden_images_of_the_shaded_and_cluster_views() {
    let placed = field(16);
    for (view, name) in [
        (DebugView::Shaded, "field_shaded"),
        (DebugView::Clusters, "field_clusters"),
    ] {
        let (still, _) = render(&placed, settings(view), &GraphSource::Shipped);
        check_golden(name, &still);
    }
}

/// A wall of three layers of 3 × 2 flattened knots at z = 0 and a 5 × 4 grid of knots
/// behind it, wider than the wall, one more knot behind the wall's middle and two
/// behind its edges.
fn walled_scene() -> SceneData {
    let (mut data, mesh, material) = common::grey_scene();
    let mut place = |m: Mat4| data.add_instance(mesh, m, material).unwrap().unwrap();
    // Three layers, turned differently, so the knots' holes do not line up.
    for i in 0..18 {
        let (x, y) = ((i % 3) as f32 * 1.2 - 1.2, (i / 3 % 2) as f32 * 1.2 - 0.4);
        place(Mat4::from_scale_rotation_translation(
            Vec3::new(1.0, 1.0, 0.3),
            Quat::from_rotation_z(i as f32 * 0.7),
            Vec3::new(x, y, -0.3 * (i / 6) as f32),
        ));
    }
    for i in 0..20 {
        let (x, z) = ((i % 5) as f32 * 4.0 - 8.0, -2.5 - (i / 5) as f32 * 2.0);
        place(Mat4::from_scale_rotation_translation(
            Vec3::splat(0.7),
            Quat::from_rotation_y(i as f32),
            Vec3::new(x, 0.3, z),
        ));
    }
    // The mover, behind the wall's middle until the test moves it out.
    place(mover_at(0.0));
    // Half behind the wall's edge: partly culled for good.
    for x in [-2.4, 2.4] {
        place(Mat4::from_scale_rotation_translation(
            Vec3::splat(0.9),
            Quat::from_rotation_x(x),
            Vec3::new(x, 0.2, -1.6),
        ));
    }
    data
}

/// The walled scene's last instance, `t` of the way out from behind the wall.
const MOVER: InstanceId = InstanceId(38);
fn mover_at(t: f32) -> Mat4 {
    Mat4::from_scale_rotation_translation(
        Vec3::splat(0.8),
        Quat::from_rotation_y(t),
        Vec3::new(t * 7.0, 0.0, -1.5),
    )
}

#[test]
fn a_still_of_the_occlusion_view_culls_against_a_history() {
    let settings = FrameSettings {
        view: Some(DebugView::Occlusion),
        ..FrameSettings::new(320, 180)
    };
    let camera = Camera::perspective(
        Vec3::new(0.0, 1.5, 14.0),
        Vec3::new(0.0, 0.0, -3.0),
        0.9,
        0.05,
    );
    let mut r = Renderer::new(walled_scene(), settings.clone(), &GraphSource::Shipped)
        .unwrap_or_else(|e| panic!("{e}"));
    let still = r.render_still(&camera).unwrap_or_else(|e| panic!("{e}"));
    let counts = still.counts.occlusion.expect("both passes' counters");
    assert!(counts.first_occluded > 0, "{counts:?}");
    // Other views keep the first frame.
    let shaded = FrameSettings {
        view: Some(DebugView::Shaded),
        ..settings
    };
    let mut r = Renderer::new(walled_scene(), shaded, &GraphSource::Shipped)
        .unwrap_or_else(|e| panic!("{e}"));
    let still = r.render_still(&camera).unwrap_or_else(|e| panic!("{e}"));
    // A first frame tests nothing, so it hides nothing and leaves the second pass out.
    assert_eq!(still.counts.occlusion, None);
    assert!(!r.last_frame_plan().second);
}

#[test]
fn golden_image_of_the_occlusion_view() {
    let settings = FrameSettings {
        view: Some(DebugView::Occlusion),
        ..FrameSettings::new(320, 180)
    };
    // The frame built in code, and the shipped pipeline file with the view's records
    // added when it loads: the same two frames give the same image.
    let mut stills = [GraphSource::Shipped, pipeline_file()].map(|source| {
        let mut r = Renderer::new(walled_scene(), settings.clone(), &source)
            .unwrap_or_else(|e| panic!("{e}"));
        // Last frame the camera stood close to the wall (not told it was a cut) and the
        // mover was behind it: this frame the second pass draws what last frame's depth hid
        // and this frame's shows (the mover, out beside the wall, and the grid), and what
        // the wall hides stays culled.
        let look = |x: f32| {
            Camera::perspective(
                Vec3::new(x, 1.5, 14.0),
                Vec3::new(0.0, 0.0, -3.0),
                0.9,
                0.05,
            )
        };
        let near = Camera::perspective(
            Vec3::new(0.0, 0.3, 4.0),
            Vec3::new(0.0, 0.3, -3.0),
            0.9,
            0.05,
        );
        r.render_still(&near).unwrap_or_else(|e| panic!("{e}"));
        r.set_transform(MOVER, mover_at(1.0)).unwrap();
        r.render_still(&look(0.0)).unwrap_or_else(|e| panic!("{e}"))
    });
    let [still, file] = &mut stills;
    assert_eq!(still.counts, file.counts);
    assert_eq!(differing(&still.rgba, &file.rgba, 0), 0, "the file's image");
    let still = &*still;
    let counts = still.counts.occlusion.expect("both passes' counters");
    eprintln!("{counts:?}");
    assert!(
        counts.second_drawn > 0 && counts.second_occluded > 0,
        "{counts:?}"
    );
    check_golden("occlusion_view", still);
    // Covered pixels are first-pass green, second-pass blue or tinted towards red (red
    // above blue, which neither pass colour has): never the sky or the shaded colours.
    let covered: Vec<&[u8]> = still
        .rgba
        .chunks(4)
        .filter(|c| c[..3] != [0, 0, 0])
        .collect();
    let pass_coloured = covered
        .iter()
        .filter(|c| (c[1] > c[0] && c[1] > c[2]) || (c[2] > c[0] && c[2] > c[1]) || c[0] > c[2])
        .count();
    let second = covered
        .iter()
        .filter(|c| c[2] > c[0] && c[2] > c[1])
        .count();
    let tinted = covered.iter().filter(|c| c[0] > c[2]).count();
    eprintln!(
        "{pass_coloured} of {} covered pixels, {second} drawn by the second pass, {tinted} tinted",
        covered.len()
    );
    assert!(covered.len() > 1000 && pass_coloured == covered.len());
    // What moved out from behind the wall is the second pass's; the knots behind its
    // edges are partly culled and tinted.
    assert!(second > 50, "{second} second-pass pixels");
    assert!(tinted > 50, "{tinted} tinted pixels");
}

#[test]
fn golden_images_of_the_default_scene() {
    // The scene `meshlight render` draws: 1,024 copies of the 1,048,576-triangle mesh
    // (baked once, then read from the asset cache), at a small size. The candidate list
    // starts at its needed size; growth has its own test.
    let asset = scenes::load_asset(
        std::path::Path::new("procedural"),
        meshlight::scene::DEFAULT_SEGMENTS,
    )
    .unwrap_or_else(|e| panic!("{e}"));
    let placed = scenes::field(
        SceneData::new(Limits::default()),
        &asset,
        scenes::DEFAULT_INSTANCES,
    )
    .unwrap();
    assert!(placed.data.source_triangles() >= 1_000_000_000);
    for (view, name) in [
        (DebugView::Shaded, "default_shaded"),
        (DebugView::Clusters, "default_clusters"),
    ] {
        let s = FrameSettings {
            view: Some(view),
            clusters: Some(1 << 24),
            ..FrameSettings::new(256, 144)
        };
        let (still, _) = render(&placed, s, &GraphSource::Shipped);
        assert_eq!(still.frames, 1, "{:?}", still.counts);
        check_golden(name, &still);
    }
}

#[test]
fn zero_instances_draw_the_sky_alone() {
    let placed = field(0);
    let (still, _) = render(&placed, settings(DebugView::Shaded), &GraphSource::Shipped);
    assert_eq!(still.counts.clusters_requested, 0);
    let row = |y: u32| &still.rgba[(y * W * 4) as usize..((y + 1) * W * 4) as usize];
    for y in 0..H {
        let r = row(y);
        assert!(
            r.chunks(4).all(|p| p == &r[..4]),
            "row {y} is not one colour"
        );
    }
    assert_ne!(row(0), row(H - 1), "no gradient");
}

#[test]
fn singular_and_nan_instances_are_skipped_and_counted_not_drawn() {
    let placed = field(4);
    let mut broken = placed.data.clone();
    assert_eq!(
        broken
            .add_instance(meshlight::gpu_scene::MeshId(0), Mat4::ZERO, 0)
            .unwrap(),
        None
    );
    assert_eq!(
        broken
            .add_instance(
                meshlight::gpu_scene::MeshId(0),
                Mat4::from_translation(Vec3::NAN),
                0
            )
            .unwrap(),
        None
    );
    assert_eq!(broken.skipped_instances(), 2);
    let with_broken = Placed {
        data: broken,
        camera: placed.camera,
        sources: Vec::new(),
    };
    let (a, _) = render(&placed, settings(DebugView::Shaded), &GraphSource::Shipped);
    let (b, _) = render(
        &with_broken,
        settings(DebugView::Shaded),
        &GraphSource::Shipped,
    );
    assert_eq!(differing(&a.rgba, &b.rgba, 0), 0);
}

#[test]
fn more_instances_than_the_buffer_holds_is_an_error_naming_the_limit() {
    let limits = Limits {
        max_instances: 10,
        ..Limits::default()
    };
    match scenes::field(SceneData::new(limits), asset(), 11) {
        Err(e @ SceneDataError::Limit { .. }) => {
            let text = e.to_string();
            assert!(text.contains("10") && text.contains("instances"), "{text}");
        }
        other => panic!("{:?}", other.map(|p| p.data.instances.len())),
    }
}

/// A field of `instances` in a scene whose bindings hold `per_binding` instances each,
/// `max_instances` in all.
fn split_field(per_binding: u32, max_instances: u32, instances: u32) -> Placed {
    let limits = Limits {
        instances_per_binding: per_binding,
        max_instances,
        ..Limits::default()
    };
    scenes::field(SceneData::new(limits), asset(), instances).unwrap()
}

/// Instances past what one binding holds continue in `instances_high`: with a binding
/// of 7 instances, a field of 13 (and its ground) takes both, and every pass that reads instances (both
/// fills and culls, both rasterisers, resolve) draws what one binding draws.
#[test]
fn instances_past_one_binding_take_a_second_and_draw_the_same_frame() {
    let split = split_field(7, 14, 13);
    assert!(split.data.instances_split());
    assert_eq!(split.data.instance_split(), 7);
    let whole = field(13);
    assert!(!whole.data.instances_split());
    assert_eq!(whole.data.instances.len(), split.data.instances.len());
    // Shaded (colours) and clusters (which cluster and triangle each pixel holds); the
    // second with both rasterisers drawing.
    let cases = [
        settings(DebugView::Shaded),
        FrameSettings {
            sw_threshold_px: Some(16.0),
            ..settings(DebugView::Clusters)
        },
    ];
    for source in [GraphSource::Shipped, pipeline_file()] {
        for s in &cases {
            let (want, _) = render(&whole, s.clone(), &source);
            let (got, r) = render(&split, s.clone(), &source);
            let binds_high = r
                .compiled
                .plan
                .resources
                .iter()
                .any(|res| res.info.name == "instances_high");
            assert!(
                binds_high,
                "{source:?}: the split frame imports no `instances_high`"
            );
            let split_passes: Vec<&str> = r
                .compiled
                .plan
                .passes
                .iter()
                .filter(|p| p.shader_defs.iter().any(|(d, _)| d == "INSTANCES_HIGH"))
                .map(|p| p.name.as_str())
                .collect();
            for stage in ["fill", "cull", "sw_raster", "resolve"] {
                assert!(
                    split_passes.iter().any(|p| p.contains(stage)),
                    "{source:?}: no `{stage}` pass reads the second binding: {split_passes:?}"
                );
            }
            assert_eq!(got.counts, want.counts, "{source:?} {:?}", s.view);
            assert!(got.counts.visible > 0, "{:?}", got.counts);
            assert_eq!(
                differing(&got.rgba, &want.rgba, 0),
                0,
                "{source:?} {:?}",
                s.view
            );
        }
    }
}

/// A pipeline file that does not import the scene's instances as `instances` cannot
/// take a split table: refused, naming the counts and what to import.
#[test]
fn a_split_instance_table_and_a_file_without_the_instances_import_is_an_error() {
    let split = split_field(2, 4, 3);
    let GraphSource::File(shipped) = pipeline_file() else {
        unreachable!()
    };
    let text = std::fs::read_to_string(shipped).unwrap();
    let imported = "name = \"instances\"\nkind = \"imported\"";
    assert!(text.contains(imported));
    let dir = std::env::temp_dir().join(format!("meshlight-split-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("transient_instances.toml");
    std::fs::write(
        &path,
        text.replace(imported, "name = \"instances\"\nkind = \"transient\""),
    )
    .unwrap();
    match Renderer::new(
        split.data.clone(),
        settings(DebugView::Shaded),
        &GraphSource::File(path),
    ) {
        Err(GraphError::PipelineFile { message, .. }) => assert!(
            message.contains("4 instances")
                && message.contains("one holds 2")
                && message.contains("import the scene's instances as `instances`"),
            "{message}"
        ),
        Err(e) => panic!("{e}"),
        Ok(_) => panic!("a split table ran without its import"),
    }
}

#[test]
fn an_asset_of_an_older_format_names_the_version_and_the_bake_command() {
    let dir = std::env::temp_dir().join(format!("meshlight-vg-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("old.mlasset");
    asset().save(&path).unwrap();
    let mut bytes = std::fs::read(&path).unwrap();
    bytes[8..12].copy_from_slice(&1u32.to_le_bytes());
    std::fs::write(&path, bytes).unwrap();
    let text = match scenes::load_asset(&path, 0) {
        Err(e) => e.to_string(),
        Ok(_) => panic!("an asset of format version 1 loaded"),
    };
    assert!(
        text.contains("version 1") && text.contains("meshlight bake"),
        "{text}"
    );
}

#[test]
fn a_viewport_of_zero_or_past_the_texture_limit_is_an_error_saying_what_to_change() {
    let placed = field(1);
    for (w, h) in [(0, 64), (64, 0), (1 << 20, 64)] {
        match Renderer::new(
            placed.data.clone(),
            FrameSettings::new(w, h),
            &GraphSource::Shipped,
        ) {
            Err(GraphError::Setting { setting, message }) => {
                assert_eq!(setting, "the viewport");
                assert!(message.contains("--width/--height"), "{message}")
            }
            Err(e) => panic!("{w} × {h}: {e}"),
            Ok(_) => panic!("{w} × {h} was accepted"),
        }
    }
}

#[test]
fn the_default_frame_has_no_depth_targets_and_turning_them_on_keeps_the_image() {
    // The depth targets are optional slots of `resolve`, off by default: the default
    // frame declares neither and runs no fragment pass in resolve; a frame that asks for
    // them gets them readable, and the colour does not depend on them.
    let placed = field(16);
    let (bare, mut r) = render(&placed, settings(DebugView::Shaded), &GraphSource::Shipped);
    let plan = &r.compiled.plan;
    assert!(
        plan.resources
            .iter()
            .all(|res| res.info.name != "depth" && res.info.name != "material_depth"),
        "the default frame declared a depth target"
    );
    let resolve = plan
        .passes
        .iter()
        .find(|p| p.stage == "resolve")
        .expect("a resolve pass");
    assert!(
        resolve.programs.iter().all(|p| p.kind == "compute"),
        "resolve declares a render program by default: {:?}",
        resolve.programs
    );
    assert!(r.executor.read_texture("depth").is_err());
    let with_targets = FrameSettings {
        depth: true,
        material_depth: true,
        ..settings(DebugView::Shaded)
    };
    let (full, mut r) = render(&placed, with_targets, &GraphSource::Shipped);
    assert_eq!(differing(&full.rgba, &bare.rgba, 0), 0);
    assert!(r.executor.read_texture("depth").is_ok());
    assert!(r.executor.read_texture("material_depth").is_ok());
}

#[test]
fn clustered_lights_shade_the_field_and_the_light_count_view_shows_them() {
    let placed = field(64);
    let lights = scenes::field_lights(&placed, 48);
    assert_eq!(lights.len(), 48);
    let lit_settings = |view| FrameSettings {
        clustering: Some(meshlight_light_clustering::ClusteringSettings {
            // Small lists, so the frame also shows the clustering's lists growing.
            slice_instances: 8,
            entries: 8,
            ..meshlight_light_clustering::ClusteringSettings::new([W, H], 64)
        }),
        ..settings(view)
    };
    let (unlit, _) = render(&placed, settings(DebugView::Shaded), &GraphSource::Shipped);
    let still = |view| {
        let mut r = Renderer::new(
            placed.data.clone(),
            lit_settings(view),
            &GraphSource::Shipped,
        )
        .unwrap_or_else(|e| panic!("{e}"));
        r.lights = lights.clone();
        let s = r
            .render_still(&placed.camera)
            .unwrap_or_else(|e| panic!("{e}"));
        (s, r)
    };
    let (lit, r) = still(DebugView::Shaded);
    assert!(runs(&r, "z_slice") && runs(&r, "populate"));
    let grown: Vec<&str> = r.clustering.growths.iter().map(|g| g.param).collect();
    assert!(grown.contains(&"cluster_entries"), "{grown:?}");
    let latest = r
        .clustering
        .latest
        .expect("the clustering's counters came back");
    assert!(
        !latest.overflowed() && latest.entries_needed > 8,
        "{latest:?}"
    );
    let changed = differing(&lit.rgba, &unlit.rgba, 4);
    let pixels = (W * H) as usize;
    assert!(
        changed * 20 > pixels,
        "the lights changed only {changed} of {pixels} pixels"
    );
    // Light only adds: no channel of a lit pixel is darker than unlit.
    let darker = lit
        .rgba
        .iter()
        .zip(&unlit.rgba)
        .filter(|(l, u)| u16::from(**l) + 1 < u16::from(**u))
        .count();
    assert_eq!(darker, 0);
    let (count_view, _) = still(DebugView::LightCount);
    let colours: std::collections::BTreeSet<&[u8]> = count_view.rgba.chunks(4).collect();
    assert!(
        colours.len() >= 3,
        "{} colours in the light-count view",
        colours.len()
    );
    // Without lights in the frame the view is an error naming what to add.
    match Renderer::new(
        placed.data.clone(),
        settings(DebugView::LightCount),
        &GraphSource::Shipped,
    ) {
        Err(GraphError::Parameter { message, .. }) => {
            assert!(message.contains("light_clustering.toml"), "{message}")
        }
        other => panic!("{:?}", other.err().map(|e| e.to_string())),
    }
}

/// The same lit frame gives the same bytes: twice in a row, and again after the frame is
/// rebuilt at another size and back. Populate fills each froxel's list in whatever order
/// its atomics fall; the resolve sums the lights in fixed point, which no order rounds
/// differently.
#[test]
fn the_lit_frame_renders_the_same_bytes_every_time() {
    let placed = field(64);
    let lit = |width: u32, height: u32| FrameSettings {
        width,
        height,
        clustering: Some(meshlight_light_clustering::ClusteringSettings::new(
            [width, height],
            64,
        )),
        ..settings(DebugView::Shaded)
    };
    let mut r = Renderer::new(placed.data.clone(), lit(W, H), &GraphSource::Shipped)
        .unwrap_or_else(|e| panic!("{e}"));
    r.lights = scenes::field_lights(&placed, 48);
    let still = |r: &mut Renderer| {
        r.render_still(&placed.camera)
            .unwrap_or_else(|e| panic!("{e}"))
            .rgba
    };
    let first = still(&mut r);
    let (unlit, _) = render(&placed, settings(DebugView::Shaded), &GraphSource::Shipped);
    assert!(
        differing(&first, &unlit.rgba, 4) * 20 > (W * H) as usize,
        "the lights should light the frame"
    );
    assert_eq!(differing(&first, &still(&mut r), 0), 0, "the second frame");
    let keep = |_: &mut meshlight::graph::GraphBuilder, _: &FrameSettings| Ok(());
    r.rebuild(&GraphSource::Shipped, lit(2 * W, 2 * H), &keep)
        .unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(still(&mut r).len(), (16 * W * H) as usize);
    r.rebuild(&GraphSource::Shipped, lit(W, H), &keep)
        .unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(
        differing(&first, &still(&mut r), 0),
        0,
        "after a resize and back"
    );
}

#[test]
fn the_hierarchy_walk_draws_the_flat_fills_image_from_fewer_candidates() {
    let placed = field(16);
    let flat_fill = FrameSettings {
        hierarchy: false,
        ..settings(DebugView::Shaded)
    };
    let (flat, _) = render(&placed, flat_fill, &GraphSource::Shipped);
    // The shipped file walks the hierarchy, as the frame built in code does by default.
    let (walk, r) = render(&placed, settings(DebugView::Shaded), &pipeline_file());
    assert!(runs(&r, "fill"));
    let (code, _) = render(&placed, settings(DebugView::Shaded), &GraphSource::Shipped);
    assert_eq!(code.counts, walk.counts);
    let h = walk
        .counts
        .hierarchy
        .expect("the walk's counters read back");
    assert!(h.nodes_tested > 0 && h.leaves_accepted > 0, "{h:?}");
    assert!(flat.counts.hierarchy.is_none());
    // The same cut, from a shorter candidate list.
    assert_eq!(walk.counts.visible, flat.counts.visible);
    assert_eq!(walk.counts.software, flat.counts.software);
    assert_eq!(walk.counts.hardware, flat.counts.hardware);
    assert_eq!(
        walk.counts.software_triangles + walk.counts.hardware_triangles,
        flat.counts.software_triangles + flat.counts.hardware_triangles
    );
    assert!(
        walk.counts.clusters_requested * 2 < flat.counts.clusters_requested,
        "{} candidates from the walk, {} flat",
        walk.counts.clusters_requested,
        flat.counts.clusters_requested
    );
    // The same triangles drawn: pixels differ only where two triangles tie in depth and
    // the tie is broken by the cluster's place in the list, which the walk changes.
    let changed = differing(&flat.rgba, &walk.rgba, 0);
    eprintln!(
        "cut {} clusters; candidates {} flat, {} from the walk; {changed} pixels differ",
        flat.counts.visible, flat.counts.clusters_requested, walk.counts.clusters_requested
    );
    assert!(changed <= (W * H / 500) as usize, "{changed} pixels differ");
}

/// A copy of Spot in a scratch folder with its own material: `spot.obj` names no
/// `.mtl`, so the copy starts with `mtllib spot.mtl` and `usemtl spot`, beside the
/// repository's `spot.mtl` and `spot_texture.png`.
fn textured_spot() -> PathBuf {
    let meshes = PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/../../assets/meshes"));
    let dir = std::env::temp_dir().join(format!("meshlight-vg-spot-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let mut obj = b"mtllib spot.mtl\nusemtl spot\n".to_vec();
    obj.extend(std::fs::read(meshes.join("spot.obj")).unwrap());
    std::fs::write(dir.join("spot.obj"), obj).unwrap();
    for file in ["spot.mtl", "spot_texture.png"] {
        std::fs::copy(meshes.join(file), dir.join(file)).unwrap();
    }
    dir.join("spot.obj")
}

#[test]
fn golden_images_of_textured_spot() {
    let path = textured_spot();
    let (asset, materials) = scenes::load_obj_with_materials(&path)
        .unwrap_or_else(|e| panic!("{e}"))
        .expect("spot.mtl gives Spot its texture");
    assert_eq!(materials.len(), 1);
    assert!(materials[0].diffuse_texture.is_some());
    let mut data = SceneData::new(Limits::default());
    let first = scenes::add_obj_materials(&mut data, &materials).unwrap();
    let placed = scenes::single_painted(data, &asset, scenes::Paint::Own(vec![first])).unwrap();
    assert_eq!(placed.data.texture_refs.len(), 1);
    assert_eq!(placed.data.texture_refs[0].size(), 1024);
    for (view, name) in [
        (DebugView::Shaded, "spot_shaded"),
        (DebugView::BaseColor, "spot_base_color"),
        (DebugView::Mip, "spot_mip"),
    ] {
        let (still, _) = render(&placed, settings(view), &GraphSource::Shipped);
        check_golden(name, &still);
    }
}

/// A generated glTF scene of several materials: a strip of five quads, one mesh of five
/// primitives each in its own colour, a checker-textured quad above it whose texture
/// repeats, and a metal and an emissive sphere; the shaded and material views.
#[test]
fn golden_images_of_a_multi_material_scene() {
    use meshlight_testing::gltf_writer::{GltfWriter, Node, Primitive, json, png_bytes};
    let mut w = GltfWriter::new();
    let quad = |x: f32, y: f32, size: f32, tiles: f32, material| Primitive {
        positions: vec![
            [x, y, 0.0],
            [x + size, y, 0.0],
            [x + size, y + size, 0.0],
            [x, y + size, 0.0],
        ],
        normals: Some(vec![[0.0, 0.0, 1.0]; 4]),
        colors: None,
        uvs: Some(vec![[0.0, tiles], [tiles, tiles], [tiles, 0.0], [0.0, 0.0]]),
        indices: vec![0, 1, 2, 0, 2, 3],
        material: Some(material),
    };
    let strip: Vec<Primitive> = (0..5)
        .map(|k| {
            let x = k as f32;
            let m = w.material(json!({"name": format!("m{k}"), "pbrMetallicRoughness": {
                "baseColorFactor": [0.2 * x + 0.1, 0.5, 0.9 - 0.2 * x, 1.0],
                "metallicFactor": 0.0, "roughnessFactor": 0.3 + 0.15 * x}}));
            quad(x, 0.0, 1.0, 1.0, m)
        })
        .collect();
    let mut rgba = Vec::new();
    for y in 0..16u32 {
        for x in 0..16u32 {
            let light = (x / 4 + y / 4).is_multiple_of(2);
            rgba.extend(if light {
                [230, 220, 200, 255]
            } else {
                [60, 90, 40, 255]
            });
        }
    }
    let image = w.image_bytes(&png_bytes(16, 16, &rgba), "image/png");
    let texture = w.texture(image, None);
    let textured = w.material(json!({"name": "checker", "pbrMetallicRoughness": {
        "baseColorTexture": {"index": texture}, "metallicFactor": 0.0}}));
    let metal = w.material(json!({"name": "metal", "pbrMetallicRoughness": {
        "baseColorFactor": [0.95, 0.75, 0.4, 1.0], "metallicFactor": 1.0, "roughnessFactor": 0.35}}));
    let glow = w.material(json!({"name": "glow", "emissiveFactor": [0.9, 0.3, 0.1],
        "pbrMetallicRoughness": {"baseColorFactor": [0.2, 0.2, 0.2, 1.0], "metallicFactor": 0.0}}));
    let strip = w.mesh("strip", &strip);
    let board = w.mesh("board", &[quad(0.0, 1.2, 2.0, 3.0, textured)]);
    let ball = |w: &mut GltfWriter, material| {
        let (rings, segments) = (16u32, 24u32);
        let mut positions = Vec::new();
        for r in 0..=rings {
            for s in 0..=segments {
                let (t, p) = (
                    std::f32::consts::PI * r as f32 / rings as f32,
                    std::f32::consts::TAU * s as f32 / segments as f32,
                );
                positions.push([t.sin() * p.cos(), t.cos(), t.sin() * p.sin()]);
            }
        }
        let mut indices = Vec::new();
        for r in 0..rings {
            for s in 0..segments {
                let a = r * (segments + 1) + s;
                let b = a + segments + 1;
                indices.extend([a, a + 1, b, a + 1, b + 1, b]);
            }
        }
        let normals = Some(positions.clone());
        w.mesh(
            "ball",
            &[Primitive {
                positions,
                normals,
                colors: None,
                uvs: None,
                indices,
                material: Some(material),
            }],
        )
    };
    let metal_ball = ball(&mut w, metal);
    let glow_ball = ball(&mut w, glow);
    let nodes = [
        (strip, [0.0, 0.0, 0.0], 1.0),
        (board, [0.0, 0.0, 0.0], 1.0),
        (metal_ball, [3.2, 1.9, 0.3], 0.5),
        (glow_ball, [4.4, 1.9, 0.3], 0.5),
    ]
    .map(|(mesh, translation, s)| {
        w.node(Node {
            mesh: Some(mesh),
            translation: Some(translation),
            scale: Some([s; 3]),
            ..Node::default()
        })
    });
    w.scene(&nodes);
    let dir = std::env::temp_dir().join(format!("meshlight-vg-materials-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("materials.glb");
    std::fs::write(&path, w.glb()).unwrap();
    let mut placed = meshlight_virtual_geometry::gltf_scene::gltf_scene(
        SceneData::new(Limits::default()),
        &path,
        None,
    )
    .unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(placed.data.materials.len(), 8);
    assert_eq!(placed.data.texture_refs.len(), 1);
    placed.camera =
        Camera::perspective(Vec3::new(2.5, 1.4, 4.6), Vec3::new(2.5, 1.2, 0.0), 0.9, 0.1);
    for (view, name) in [
        (DebugView::Shaded, "materials_shaded"),
        (DebugView::Material, "materials_material"),
    ] {
        let (still, _) = render(&placed, settings(view), &GraphSource::Shipped);
        check_golden(name, &still);
    }
}
