//! `sw_raster` on the GPU (lavapipe in CI) against `cpu::rasterize`, bit for bit on every
//! pixel: seeded views of three instances of the procedural mesh at several LOD levels,
//! a 1-D and a 2-D dispatch with ids past the count, both loop shapes, a flat
//! tessellated quad whose shared edges must cover every pixel once, the per-frame clear
//! and the errors.

use glam::{Mat4, Quat, Vec2, Vec3};
use meshlight_gpu_scene::data::Limits;
use meshlight_gpu_scene::{Camera, GpuScene, Material, Projection, SceneData};
use meshlight_graph::*;
use meshlight_pass_sw_raster::{BIG_COUNT_SLOT, SwRaster, cpu};
use meshlight_scene::{Mesh, procedural_mesh};
use meshlight_shaders::cpu::layout::{Cluster, MATERIAL_FLAG_DOUBLE_SIDED, View};
use meshlight_shaders::cpu::visbuffer;

const W: u32 = 96;
const H: u32 = 64;
/// Below every triangle box: every workgroup loops per scanline.
const SCANLINES: u32 = 1;
/// Above every triangle box: every workgroup loops over its whole box.
const BOXES: u32 = 1 << 20;

use meshlight_gpu_scene::gpu::elements;
use meshlight_testing::features::where_supported;
use meshlight_testing::frames::{Imported, filled, import_filled, run_per_view};
use meshlight_testing::{Rng, gpu};

#[path = "support/scenes.rs"]
mod scenes;
use scenes::{MASK_CUTOFF, add_mesh, flat_quad, masked_scene, with_cutoff};

// ---------------------------------------------------------------------------------------
// Scenes and views

/// Three instances of the torus knot (one at its place, two moved, scaled and turned).
fn knot_scene() -> SceneData {
    let third = Mat4::from_scale_rotation_translation(
        Vec3::new(0.5, 0.7, 0.6),
        Quat::from_rotation_x(-1.1),
        Vec3::new(-2.0, -1.5, 1.0),
    );
    scenes::knot_scene(&procedural_mesh(12), &[third])
}

/// The white `meshes`, then one instance of each at its place, numbered in order.
fn flat_scene(meshes: &[(&str, Mesh)]) -> SceneData {
    let mut scene = SceneData::new(Limits::default());
    let material = scene
        .add_material(Material {
            base_color: [1.0; 3],
            ..Material::default()
        })
        .unwrap();
    let ids: Vec<_> = meshes
        .iter()
        .map(|(name, mesh)| add_mesh(&mut scene, name, mesh))
        .collect();
    for id in ids {
        scene
            .add_instance(id, Mat4::IDENTITY, material)
            .unwrap()
            .unwrap();
    }
    scene
}

/// The meshlets of `instance` for which `pick` holds, as clusters.
fn clusters_of(scene: &SceneData, instance: u32, pick: impl Fn(u32) -> bool) -> Vec<Cluster> {
    let i = &scene.instances[instance as usize];
    (i.first_meshlet..i.first_meshlet + i.meshlet_count)
        .filter(|&m| pick(scene.meshlets[m as usize].level()))
        .map(|meshlet| Cluster { instance, meshlet })
        .collect()
}

/// `n` perspective views from seeded points around the knot scene.
fn seeded_views(seed: u64, n: usize) -> Vec<View> {
    let mut rng = Rng(seed);
    (0..n)
        .map(|_| {
            let yaw = rng.range(0.0, std::f32::consts::TAU);
            let pitch = rng.range(-0.9, 0.9);
            let distance = rng.range(7.0, 12.0);
            let dir = Vec3::new(
                pitch.cos() * yaw.cos(),
                pitch.sin(),
                pitch.cos() * yaw.sin(),
            );
            let target = Vec3::new(rng.range(-1.0, 1.0), rng.range(-1.0, 1.0), 0.5);
            Camera::perspective(target + dir * distance, target, 0.8, 0.5).view([W, H], 0, None)
        })
        .collect()
}

// ---------------------------------------------------------------------------------------
// Running the pass

/// What the pass is given: the slot buffer (clusters past `count` must not be drawn) and
/// the dispatch shape.
struct Input {
    slots: Vec<Cluster>,
    count: u32,
    args: [u32; 3],
}

impl Input {
    /// The first `count` slots drawn; `x` workgroups per row, enough rows for `count`.
    fn new(slots: Vec<Cluster>, count: u32, x: u32) -> Self {
        assert!(count as usize <= slots.len());
        Self {
            args: [x, count.div_ceil(x), 1],
            slots,
            count,
        }
    }

    /// Every slot drawn, `x` workgroups per row.
    fn every(slots: Vec<Cluster>, x: u32) -> Self {
        let count = slots.len() as u32;
        Self::new(slots, count, x)
    }

    /// Every slot drawn, a workgroup each in one row.
    fn every_in_one_row(slots: Vec<Cluster>) -> Self {
        let count = slots.len() as u32;
        Self::new(slots, count, count)
    }

    fn reference(&self, scene: &SceneData, view: &View) -> Vec<u64> {
        cpu::rasterize(scene, view, &self.slots[..self.count as usize], W, H)
    }
}

/// Values the visibility buffer holds before the first frame: the nearest depth, so any
/// of them left by a missing clear would win every atomicMax.
fn stale_contents() -> Vec<u64> {
    (0..W * H)
        .map(|i| visbuffer::pack(1.0, i % 4096, i % 128))
        .collect()
}

/// Runs one frame per view through one graph and executor, and reads the visibility
/// buffer back after each.
fn run(
    scene: &mut SceneData,
    input: &Input,
    views: &[View],
    pass: SwRaster,
) -> Result<Vec<Vec<u64>>> {
    let gpu = gpu();
    let gpu_scene = GpuScene::new(&gpu, scene);
    let counts = [input.count, 0, 0, 0];
    let stale = stale_contents();
    let mut g = GraphBuilder::new();
    gpu_scene.import(&mut g);
    // Each buffer is imported under its slot's name, which binds it.
    let Imported {
        handles: [.., out],
        buffers: [.., visbuffer],
        imports,
    } = import_filled(
        &mut g,
        &gpu,
        [
            filled("raster_clusters", elements::CLUSTER, &input.slots),
            filled("raster_counts", Element::U32, &counts),
            filled("sw_args", Element::DISPATCH_ARGS, &input.args),
            filled("visbuffer", Element::U64, &stale),
        ],
        gpu_scene.imports(),
    );
    // The `texture` target is a transient R64Uint texture, copied out after the raster.
    let texture = pass.target == Visibility64::Texture;
    let mut bindings = Bindings::new();
    if texture {
        let vis = g.create_visibility64("visbuffer_texture", W, H);
        bindings = bindings.bind("visbuffer", vis);
    }
    let tiled = pass.big_triangle_px > 0;
    if tiled {
        g.create_buffer(BIG_COUNT_SLOT, BufferDesc::array(Element::U32, 2));
    }
    let drawn = g.add_pass("sw_raster", pass, bindings)?;
    if tiled {
        g.export(drawn.buffer(BIG_COUNT_SLOT)?);
    }
    if texture {
        let copy = Bindings::new()
            .bind("texture", drawn.texture("visbuffer")?)
            .bind("buffer", out);
        let copy_out = synthetic::CopyTextureToBuffer {
            format: wgpu::TextureFormat::R64Uint,
            width: W,
            height: H,
        };
        g.add_pass("copy_out", copy_out, copy)?;
    }
    let compiled = g.compile(&CompileOptions::for_gpu(&gpu))?;
    let mut exec = Executor::new(gpu);
    run_per_view(&mut exec, &compiled, &imports, views, |exec| {
        let bytes = exec.gpu.read_buffer(&visbuffer, 0, (W * H) as u64 * 8)?;
        if tiled {
            // Big triangles were tiled, and every tile found room in the list.
            let c: Vec<u32> = bytemuck::pod_collect_to_vec(&exec.read_buffer(BIG_COUNT_SLOT)?);
            assert!(
                c[0] > 0 && c[0] == c[1],
                "big-triangle tiles listed, asked for: {c:?}"
            );
        }
        Ok(bytemuck::pod_collect_to_vec(&bytes))
    })
}

/// The pass with exact division, so that every driver matches the reference bit for bit
/// (lavapipe divides exactly either way; NVIDIA's division moves some depths by an ulp).
fn pass(scanline_width: u32) -> SwRaster {
    SwRaster {
        width: W,
        height: H,
        target: Visibility64::Buffer,
        scanline_width,
        exact_division: true,
        accumulate: false,
        big_triangle_px: 0,
        small_triangle_px: meshlight_pass_sw_raster::SMALL_TRIANGLE_PX,
        two_sided: false,
        alpha_mask: false,
        depth_only: false,
        layer: 0,
    }
}

/// `pass(scanline_width)` with the small-triangle path for corners within
/// `small_triangle_px` only (0: none).
fn small_below(scanline_width: u32, small_triangle_px: u32) -> SwRaster {
    SwRaster {
        small_triangle_px,
        ..pass(scanline_width)
    }
}

// ---------------------------------------------------------------------------------------
// Comparing

fn covered(v: &[u64]) -> usize {
    v.iter().filter(|&&p| p != visbuffer::EMPTY).count()
}

fn describe(v: u64) -> String {
    if v == visbuffer::EMPTY {
        "empty".into()
    } else {
        format!(
            "depth {:e} ({:#010x}) cluster {} triangle {}",
            visbuffer::depth(v),
            v >> 32,
            visbuffer::cluster(v),
            visbuffer::triangle(v)
        )
    }
}

/// Every pixel identical; the first differences are named by pixel.
fn assert_identical(name: &str, got: &[u64], want: &[u64]) {
    assert_eq!(got.len(), want.len());
    let diffs: Vec<usize> = (0..got.len()).filter(|&i| got[i] != want[i]).collect();
    let shown: Vec<String> = diffs
        .iter()
        .take(8)
        .map(|&i| {
            format!(
                "({}, {}): GPU {} / CPU {}",
                i as u32 % W,
                i as u32 / W,
                describe(got[i]),
                describe(want[i])
            )
        })
        .collect();
    assert!(
        diffs.is_empty(),
        "{name}: {} of {} pixels differ ({} covered by the reference):\n{}",
        diffs.len(),
        got.len(),
        covered(want),
        shown.join("\n")
    );
}

// ---------------------------------------------------------------------------------------
// Tests

#[test]
fn matches_the_reference_bit_for_bit_in_both_loop_shapes_and_dispatch_shapes() {
    let mut scene = knot_scene();
    // LOD 0 of the first instance, levels 1 and 2 of the second, level 3 and up of the
    // third: overlapping surfaces of several levels.
    let mut slots: Vec<Cluster> = [
        clusters_of(&scene, 0, |l| l == 0),
        clusters_of(&scene, 1, |l| l == 1 || l == 2),
        clusters_of(&scene, 2, |l| l >= 3),
    ]
    .concat();
    let levels: std::collections::BTreeSet<u32> = slots
        .iter()
        .map(|c| scene.meshlets[c.meshlet as usize].level())
        .collect();
    assert!(levels.len() >= 4, "levels {levels:?}");
    let count = slots.len() as u32;
    // Real clusters past the count: drawing any of them would show.
    slots.extend(clusters_of(&scene, 0, |l| l == 0).into_iter().take(8));
    let views = seeded_views(7, 4);

    let linear = Input::new(slots.clone(), count, count);
    // A few workgroups per row: ids `y * x_count + x`, the last row partly past the count.
    let x_count = (7..).find(|x| !count.is_multiple_of(*x)).unwrap();
    let folded = Input::new(slots, count, x_count);
    assert!(folded.args[0] * folded.args[1] > count && folded.args[1] > 1);

    let want: Vec<Vec<u64>> = views.iter().map(|v| linear.reference(&scene, v)).collect();
    for (k, w) in want.iter().enumerate() {
        assert!(
            covered(w) > 600,
            "view {k} covers only {} pixels",
            covered(w)
        );
        // Every drawn slot is below the count, and every instance appears in some view.
        assert!(w.iter().all(|&p| visbuffer::cluster(p) < count));
    }
    let seen: std::collections::BTreeSet<u32> = want
        .iter()
        .flatten()
        .filter(|&&p| p != visbuffer::EMPTY)
        .map(|&p| linear.slots[visbuffer::cluster(p) as usize].instance)
        .collect();
    assert_eq!(seen.len(), 3, "instances seen: {seen:?}");

    for (shape, input) in [("1-D", &linear), ("2-D", &folded)] {
        let mut results = Vec::new();
        // Tiled: nearly every triangle (boxes of 3 pixels or more) covered a tile per
        // workgroup.
        let tiled = SwRaster {
            big_triangle_px: 3,
            ..pass(SCANLINES)
        };
        // Every triangle by 64-bit edge functions in each loop shape, every one the
        // small path takes by 32-bit ones, and a mix.
        for (loop_name, raster) in [
            ("scanline", small_below(SCANLINES, 0)),
            ("box", small_below(BOXES, 0)),
            ("tiled", tiled),
            ("small-triangle", pass(SCANLINES)),
            (
                "small-triangle below 3 px, scanline",
                small_below(SCANLINES, 3),
            ),
            ("small-triangle below 3 px, box", small_below(BOXES, 3)),
        ] {
            let got = run(&mut scene, input, &views, raster).unwrap_or_else(|e| panic!("{e}"));
            for (k, (g, w)) in got.iter().zip(&want).enumerate() {
                assert_identical(
                    &format!("{shape} dispatch, {loop_name} loop, view {k}"),
                    g,
                    w,
                );
            }
            results.push(got);
        }
        for (k, r) in results.iter().enumerate().skip(1) {
            assert_eq!(&results[0], r, "{shape}: loop shape {k} disagrees");
        }
        // The driver's division: exact on lavapipe, within an ulp or so elsewhere.
        let driver = SwRaster {
            exact_division: false,
            ..pass(SCANLINES)
        };
        let got = run(&mut scene, input, &views, driver).unwrap_or_else(|e| panic!("{e}"));
        for (k, (g, w)) in got.iter().zip(&want).enumerate() {
            let name = format!("{shape} dispatch, driver division, view {k}");
            if exact_divider() {
                assert_identical(&name, g, w);
            } else {
                assert_near(&name, g, w);
            }
        }
    }
}

/// True where the driver divides as IEEE 754 does (lavapipe, a CPU adapter).
fn exact_divider() -> bool {
    gpu().adapter.get_info().device_type == wgpu::DeviceType::Cpu
}

/// The driver's division against the reference: coverage identical, every depth within
/// 1e-5 (an ulp of a quotient moves a depth by about that much at most), and where two
/// surfaces are that close the winner may change: ids differ on at most 2% of the
/// covered pixels.
fn assert_near(name: &str, got: &[u64], want: &[u64]) {
    let mut covered = 0;
    let mut other_id = 0;
    let mut depths_moved = 0;
    for (i, (&g, &w)) in got.iter().zip(want).enumerate() {
        assert_eq!(
            g == visbuffer::EMPTY,
            w == visbuffer::EMPTY,
            "{name}: pixel {i} coverage"
        );
        if w == visbuffer::EMPTY {
            continue;
        }
        covered += 1;
        other_id += (g as u32 != w as u32) as usize;
        depths_moved += (g >> 32 != w >> 32) as usize;
        let d = (visbuffer::depth(g) - visbuffer::depth(w)).abs();
        assert!(
            d <= 1e-5,
            "{name}: pixel {i}: {} against {}",
            describe(g),
            describe(w)
        );
    }
    eprintln!(
        "{name}: of {covered} covered pixels, {depths_moved} with a moved depth, {other_id} with another id"
    );
    assert!(
        other_id * 50 <= covered,
        "{name}: {other_id} of {covered} pixels with another id"
    );
}

/// The `texture` implementation writes the same values as the reference (and so as
/// `buffer`) where the adapter has 64-bit texture atomics (NVIDIA through Vulkan); where
/// it has not (lavapipe), compiling it is the typed error naming the feature.
#[test]
fn the_texture_target_holds_the_reference_values_or_names_the_missing_feature() {
    let mut scene = knot_scene();
    let slots: Vec<Cluster> = [
        clusters_of(&scene, 0, |l| l == 0),
        clusters_of(&scene, 1, |l| l >= 1),
    ]
    .concat();
    let input = Input::every(slots, 7);
    let views = seeded_views(5, 3);
    // `pass` divides exactly: bit for bit on every driver, so the reference is the
    // yardstick on NVIDIA too.
    let exact = pass(SCANLINES);
    let textured = SwRaster {
        target: Visibility64::Texture,
        ..exact
    };
    let Some(got) = where_supported(
        run(&mut scene, &input, &views, textured),
        meshlight_pass_sw_raster::TEXTURE_FEATURES,
        "sw_raster",
        "TEXTURE_INT64_ATOMIC",
        "64-bit texture atomics",
    ) else {
        return;
    };
    let buffer = run(&mut scene, &input, &views, exact).unwrap_or_else(|e| panic!("{e}"));
    for (k, view) in views.iter().enumerate() {
        let want = input.reference(&scene, view);
        assert!(covered(&want) > 600, "view {k}");
        assert_identical(&format!("texture, view {k}"), &got[k], &want);
        assert_eq!(
            got[k], buffer[k],
            "view {k}: texture and buffer targets differ"
        );
    }
    eprintln!(
        "texture target: {} views equal to the reference and to the buffer target",
        views.len()
    );
}

/// The knot is closed and its outside is counter-clockwise: with back faces culled, the
/// nearest surface along every pixel is a front face, so drawing front faces alone gives
/// the depth that drawing both windings gives. Drawing the back faces instead would show
/// the inside of the far wall.
#[test]
fn front_faces_are_the_mesh_outside() {
    let mut scene = knot_scene();
    let slots: Vec<Cluster> = clusters_of(&scene, 0, |l| l == 0);
    let input = Input::every_in_one_row(slots);
    let views = seeded_views(11, 2);
    let got = run(&mut scene, &input, &views, pass(16)).unwrap_or_else(|e| panic!("{e}"));
    for (k, view) in views.iter().enumerate() {
        let want = input.reference(&scene, view);
        assert_identical(&format!("view {k}"), &got[k], &want);
        // Both windings of every triangle.
        let mut nearest = vec![0f32; (W * H) as usize];
        for c in &input.slots {
            for t in cpu::screen_triangles(&scene, view, c, W, H) {
                let [a, b, c] = t.corners;
                for corners in [[a, b, c], [a, c, b]] {
                    cpu::cover_triangle(corners, W, H, |x, y, d| {
                        let p = &mut nearest[(y * W + x) as usize];
                        *p = p.max(d);
                    });
                }
            }
        }
        let drawn: Vec<usize> = (0..want.len())
            .filter(|&i| want[i] != visbuffer::EMPTY)
            .collect();
        assert!(drawn.len() > 500, "view {k}: {} pixels", drawn.len());
        let same = drawn
            .iter()
            .filter(|&&i| visbuffer::depth(want[i]) == nearest[i])
            .count();
        eprintln!(
            "view {k}: {same} of {} pixels show the nearest surface",
            drawn.len()
        );
        // Triangles seen edge-on at the silhouette may flip winding when their corners
        // snap; a handful of pixels, never a share.
        assert!(
            same as f64 >= 0.99 * drawn.len() as f64,
            "view {k}: only {same} of {} pixels show the nearest surface",
            drawn.len()
        );
    }
}

/// Pixels whose centre lies at least one pixel inside the screen quadrilateral of the
/// square's corners.
fn inside_square(view: &View) -> Vec<bool> {
    let corners = [[-1.0, -1.0], [1.0, -1.0], [1.0, 1.0], [-1.0, 1.0]].map(|[x, y]| {
        let clip = cpu::affine(&view.view_projection, [x, y, 0.0]);
        let (p, _) = cpu::snap(glam::Vec4::from_array(clip), [W as f32, H as f32]).unwrap();
        [p[0] as f64 / 256.0, p[1] as f64 / 256.0]
    });
    (0..W * H)
        .map(|i| {
            let p = [(i % W) as f64 + 0.5, (i / W) as f64 + 0.5];
            (0..4).all(|k| {
                let (a, b) = (corners[k], corners[(k + 1) % 4]);
                let len = ((b[0] - a[0]).powi(2) + (b[1] - a[1]).powi(2)).sqrt();
                // Counter-clockwise on the y-down screen: inside is left of each edge.
                let cross = (b[0] - a[0]) * (p[1] - a[1]) - (b[1] - a[1]) * (p[0] - a[0]);
                -cross / len >= 1.0
            })
        })
        .collect()
}

#[test]
fn shared_edges_of_a_flat_quad_cover_every_pixel_exactly_once() {
    let mut scene = flat_scene(&[
        ("regular", flat_quad(16, 0.0)),
        ("jittered", flat_quad(20, 0.35)),
    ]);

    // Orthographic, 24 pixels per unit, the origin on a pixel centre: the regular grid
    // (3 pixels a cell) puts vertices on pixel centres and edges through them, where
    // only the top-left rule decides. Then perspective views, one rolled.
    let ortho = Camera {
        position: Vec3::new(-1.0 / 48.0, 1.0 / 48.0, 5.0),
        target: Vec3::new(-1.0 / 48.0, 1.0 / 48.0, 0.0),
        up: Vec3::Y,
        projection: Projection::Orthographic {
            height: H as f32 / 24.0,
            near: 1.0,
            far: 10.0,
        },
    };
    let mut rolled = Camera::perspective(Vec3::new(0.3, -0.4, 2.6), Vec3::ZERO, 0.9, 0.5);
    rolled.up = Vec3::new(0.6, 0.8, 0.0);
    let cameras = [
        ortho,
        Camera::perspective(
            Vec3::new(-0.2, 0.3, 2.7),
            Vec3::new(0.1, 0.0, 0.0),
            0.9,
            0.5,
        ),
        rolled,
    ];
    let views: Vec<View> = cameras.iter().map(|c| c.view([W, H], 0, None)).collect();

    for instance in 0..2 {
        let slots: Vec<Cluster> = clusters_of(&scene, instance, |l| l == 0);
        assert!(slots.len() >= 2, "the square fits one meshlet");
        let input = Input::every(slots, 3);
        for (loop_name, width) in [("scanline", SCANLINES), ("box", BOXES)] {
            let got =
                run(&mut scene, &input, &views, pass(width)).unwrap_or_else(|e| panic!("{e}"));
            for (k, view) in views.iter().enumerate() {
                let name = format!("instance {instance}, {loop_name} loop, view {k}");
                // Coverage counted per triangle from the reference's own edge tests.
                let mut coverage = vec![0u32; (W * H) as usize];
                let mut on_centres = 0;
                for c in &input.slots {
                    for t in cpu::screen_triangles(&scene, view, c, W, H) {
                        on_centres += t
                            .corners
                            .iter()
                            .filter(|(p, _)| p[0] % 256 == 128 && p[1] % 256 == 128)
                            .count();
                        cpu::cover_triangle(t.corners, W, H, |x, y, _| {
                            coverage[(y * W + x) as usize] += 1
                        });
                    }
                }
                if instance == 0 && k == 0 {
                    assert!(
                        on_centres > 500,
                        "{name}: {on_centres} corners on pixel centres"
                    );
                }
                let twice = coverage.iter().filter(|&&n| n > 1).count();
                assert_eq!(twice, 0, "{name}: {twice} pixels covered more than once");
                let inside = inside_square(view);
                let inner = inside.iter().filter(|&&b| b).count();
                assert!(
                    inner > 1500,
                    "{name}: only {inner} pixels inside the square"
                );
                let holes = (0..inside.len())
                    .filter(|&i| inside[i] && coverage[i] == 0)
                    .count();
                assert_eq!(holes, 0, "{name}: {holes} pixels inside the square skipped");

                let want = input.reference(&scene, view);
                assert_identical(&name, &got[k], &want);
                let gpu_holes = (0..inside.len())
                    .filter(|&i| inside[i] && got[k][i] == visbuffer::EMPTY)
                    .count();
                assert_eq!(gpu_holes, 0, "{name}: background inside the square");
            }
        }
    }
}

/// Triangles whose corners lie just within the small-triangle path's bound (63.98
/// pixels apart), exactly on it (64: the 64-bit path) and past it (80 and 400 pixels),
/// at sub-pixel offsets: the largest edge functions the 32-bit path meets. Both paths
/// equal the reference; 32-bit edge functions for the 400-pixel triangles would
/// overflow.
#[test]
fn triangles_at_the_small_paths_bound_match_the_reference() {
    let mut scene = flat_scene(&[("square", flat_quad(1, 0.0)), ("cells", flat_quad(2, 0.0))]);
    // The square is 2 units wide: `pixels` pixels per unit make its triangles' corners
    // 2 × `pixels` apart (one cell of the 2 × 2 grid: `pixels`).
    let ortho = |pixels: f32, offset: Vec2| {
        let eye = Vec3::new(offset.x, offset.y, 5.0);
        Camera {
            position: eye,
            target: eye - Vec3::Z,
            up: Vec3::Y,
            projection: Projection::Orthographic {
                height: H as f32 / pixels,
                near: 1.0,
                far: 10.0,
            },
        }
        .view([W, H], 0, None)
    };
    let views = [
        ortho(31.99, Vec2::new(0.0013, -0.0021)),
        ortho(32.0, Vec2::ZERO),
        ortho(31.999, Vec2::new(-0.0107, 0.0031)),
        ortho(40.0, Vec2::new(0.3, 0.1)),
        ortho(200.0, Vec2::new(0.71, 0.23)),
    ];
    for instance in 0..2 {
        let slots: Vec<Cluster> = clusters_of(&scene, instance, |l| l == 0);
        let input = Input::every(slots, 2);
        let mut widest = 0;
        for view in &views {
            for c in &input.slots {
                for t in cpu::screen_triangles(&scene, view, c, W, H) {
                    let xs = t.corners.map(|(p, _)| p[0]);
                    let ys = t.corners.map(|(p, _)| p[1]);
                    let extent = (xs.iter().max().unwrap() - xs.iter().min().unwrap())
                        .max(ys.iter().max().unwrap() - ys.iter().min().unwrap());
                    if extent < 64 * 256 {
                        widest = widest.max(extent);
                    }
                }
            }
        }
        if instance == 0 {
            assert!(
                widest > 63 * 256,
                "the widest triangle within the bound is {} px",
                widest as f32 / 256.0
            );
        }
        let want: Vec<Vec<u64>> = views.iter().map(|v| input.reference(&scene, v)).collect();
        for (name, raster) in [
            ("small-triangle path", pass(SCANLINES)),
            ("64-bit path", small_below(SCANLINES, 0)),
        ] {
            let got = run(&mut scene, &input, &views, raster).unwrap_or_else(|e| panic!("{e}"));
            for (k, (g, w)) in got.iter().zip(&want).enumerate() {
                assert!(covered(w) > 1000, "view {k} covers {} pixels", covered(w));
                assert_identical(&format!("instance {instance}, {name}, view {k}"), g, w);
            }
        }
    }
}

#[test]
fn a_small_triangle_bound_past_the_safe_one_is_a_parameter_error() {
    let mut registry = file::Registry::new();
    meshlight_pass_sw_raster::register(&mut registry);
    let text = |px: u32| {
        format!(
            "[[pass]]\nname = \"raster\"\nstage = \"sw_raster\"\nimplementation = \"buffer\"\n\
             params = {{ width = {W}, height = {H}, small_triangle_px = {px} }}\n"
        )
    };
    match file::parse_pipeline(&text(65), "p.toml", &registry) {
        Err(GraphError::Parameter { pass, message }) => {
            assert_eq!(pass, "raster");
            assert!(
                message.contains("`small_triangle_px = 65`") && message.contains("64 or less"),
                "{message}"
            );
        }
        Err(other) => panic!("not a parameter error: {other}"),
        Ok(_) => panic!("a small-triangle bound of 65 pixels was accepted"),
    }
    // The file binds no slots, so it fails later, but not on its parameters.
    for px in [0, 1, 64] {
        if let Err(GraphError::Parameter { message, .. }) =
            file::parse_pipeline(&text(px), "p.toml", &registry)
        {
            panic!("small_triangle_px = {px} refused: {message}");
        }
    }
}

#[test]
fn each_frame_starts_from_a_cleared_visibility_buffer() {
    let mut scene = knot_scene();
    let slots = [
        clusters_of(&scene, 0, |l| l == 0),
        clusters_of(&scene, 1, |l| l == 0),
    ]
    .concat();
    let input = Input::every(slots, 5);
    let near = Camera::perspective(Vec3::new(1.0, 2.0, 6.0), Vec3::ZERO, 0.8, 0.5);
    let far = Camera::perspective(
        Vec3::new(-9.0, 4.0, -10.0),
        Vec3::new(1.0, 0.0, 1.0),
        0.8,
        0.5,
    );
    let views = [near.view([W, H], 0, None), far.view([W, H], 1, None)];
    let got = run(&mut scene, &input, &views, pass(16)).unwrap_or_else(|e| panic!("{e}"));
    let first = input.reference(&scene, &views[0]);
    let second = input.reference(&scene, &views[1]);
    // Frame 1 leaves pixels the second view does not draw, and pixels nearer than the
    // second view's: a missing clear would keep both.
    let left = (0..first.len())
        .filter(|&i| first[i] != visbuffer::EMPTY && second[i] == visbuffer::EMPTY)
        .count();
    let nearer = (0..first.len())
        .filter(|&i| second[i] != visbuffer::EMPTY && first[i] > second[i])
        .count();
    assert!(left > 200 && nearer > 100, "{left} / {nearer}");
    assert_identical("frame 1", &got[0], &first);
    assert_identical("frame 2", &got[1], &second);
}

#[test]
fn a_viewport_other_than_the_params_is_a_record_error_naming_both() {
    let mut scene = knot_scene();
    let slots: Vec<Cluster> = clusters_of(&scene, 0, |l| l == 0);
    let input = Input::every_in_one_row(slots);
    let camera = Camera::perspective(Vec3::new(1.0, 2.0, 8.0), Vec3::ZERO, 0.8, 0.5);
    let view = camera.view([W + 1, H], 0, None);
    match run(&mut scene, &input, &[view], pass(16)) {
        Err(GraphError::Record { pass, message }) => {
            assert_eq!(pass, "sw_raster");
            assert!(
                message.contains(&format!("{:?}", [(W + 1) as f32, H as f32])),
                "{message}"
            );
            assert!(message.contains(&format!("{W} × {H}")), "{message}");
        }
        Err(other) => panic!("not a record error: {other}"),
        Ok(_) => panic!(
            "a {} × {H} view ran on a {W} × {H} visibility buffer",
            W + 1
        ),
    }
}

#[test]
fn a_zero_width_in_a_pipeline_file_is_a_parameter_error() {
    let mut registry = file::Registry::new();
    meshlight_pass_sw_raster::register(&mut registry);
    let text = |width: u32| {
        format!(
            "[[pass]]\nname = \"raster\"\nstage = \"sw_raster\"\nimplementation = \"buffer\"\n\
             params = {{ width = {width}, height = {H} }}\n"
        )
    };
    match file::parse_pipeline(&text(0), "p.toml", &registry) {
        Err(GraphError::Parameter { pass, message }) => {
            assert_eq!(pass, "raster");
            assert!(
                message.contains("`width`") && message.contains("0 × 64"),
                "{message}"
            );
        }
        Err(other) => panic!("not a parameter error: {other}"),
        Ok(_) => panic!("a zero-width visibility buffer was accepted"),
    }
    // A height of 0 is refused the same way, and a positive size passes the parameters.
    let text_h0 = text(W).replace(&format!("height = {H}"), "height = 0");
    match file::parse_pipeline(&text_h0, "p.toml", &registry) {
        Err(GraphError::Parameter { message, .. }) => {
            assert!(message.contains("`height`"), "{message}")
        }
        Err(other) => panic!("not a parameter error: {other}"),
        Ok(_) => panic!("a zero-height visibility buffer was accepted"),
    }
    if let Err(GraphError::Parameter { message, .. }) =
        file::parse_pipeline(&text(W), "p.toml", &registry)
    {
        panic!("{W} × {H} refused: {message}");
    }
}

/// Two passes over one visibility buffer: the first clears it and draws slots `0..k`,
/// the second (`accumulate`) keeps it and draws slots `k..n` from the base in word 7 of
/// its counts. Together they equal one pass over `0..n`, ids included; a second pass that
/// cleared, or numbered its clusters from 0, or started elsewhere, would differ.
#[test]
fn an_accumulating_pass_draws_its_slots_over_the_first_passs_image() {
    let mut scene = knot_scene();
    let mut slots = [
        clusters_of(&scene, 0, |l| l == 0),
        clusters_of(&scene, 1, |l| l == 1),
        clusters_of(&scene, 2, |l| l >= 2),
    ]
    .concat();
    let n = slots.len() as u32;
    let k = n / 2;
    // A real cluster past the second pass's slots: drawing it would show.
    slots.extend(clusters_of(&scene, 0, |l| l == 0).into_iter().take(4));
    let views = seeded_views(11, 3);
    let whole = Input::new(slots.clone(), n, n);
    let gpu = gpu();
    let gpu_scene = GpuScene::new(&gpu, &mut scene);
    let mut g = GraphBuilder::new();
    gpu_scene.import(&mut g);
    // Each pass's counts (its cluster count, and in word 7 its first slot) and dispatch.
    let x = 5;
    let words = [(k, 0), (n - k, k)].map(|(count, base)| [count, 0, 0, 0, 0, 0, 0, base]);
    let args = [k, n - k].map(|count| [x, count.div_ceil(x), 1]);
    let Imported {
        handles:
            [
                slots_h,
                counts_first,
                args_first,
                counts_second,
                args_second,
            ],
        imports,
        ..
    } = import_filled(
        &mut g,
        &gpu,
        [
            filled("raster_clusters", elements::CLUSTER, &slots),
            filled("counts_first", Element::U32, &words[0]),
            filled("args_first", Element::DISPATCH_ARGS, &args[0]),
            filled("counts_second", Element::U32, &words[1]),
            filled("args_second", Element::DISPATCH_ARGS, &args[1]),
        ],
        gpu_scene.imports(),
    );
    let vis = g.create_buffer("visbuffer", BufferDesc::array(Element::U64, (W * H) as u64));
    let mut vis: AnyHandle = vis.into();
    for (pass_name, counts, args, accumulate) in [
        ("first", counts_first, args_first, false),
        ("second", counts_second, args_second, true),
    ] {
        let drawn = g
            .add_pass(
                pass_name,
                SwRaster {
                    accumulate,
                    ..pass(16)
                },
                Bindings::new()
                    .bind("raster_clusters", slots_h)
                    .bind("raster_counts", counts)
                    .bind("sw_args", args)
                    .bind("visbuffer", vis),
            )
            .unwrap_or_else(|e| panic!("{e}"));
        vis = drawn.buffer("visbuffer").unwrap().into();
    }
    g.export(vis);
    let compiled = g
        .compile(&CompileOptions::for_gpu(&gpu))
        .unwrap_or_else(|e| panic!("{e}"));
    let mut exec = Executor::new(gpu);
    let frames = run_per_view(&mut exec, &compiled, &imports, &views, |exec| {
        Ok(bytemuck::pod_collect_to_vec::<u8, u64>(
            &exec.read_buffer("visbuffer")?,
        ))
    })
    .unwrap_or_else(|e| panic!("{e}"));
    for (i, (view, got)) in views.iter().zip(&frames).enumerate() {
        let want = whole.reference(&scene, view);
        let second_ids = want
            .iter()
            .filter(|&&v| v != visbuffer::EMPTY && visbuffer::cluster(v) >= k)
            .count();
        assert!(
            second_ids > 100,
            "view {i}: the second pass owns {second_ids} pixels"
        );
        assert_identical(&format!("view {i}"), got, &want);
    }
}

// ---------------------------------------------------------------------------------------
// Clipping

/// Views from just outside the first knot's tube (its centre line is the procedural
/// mesh's torus-knot curve, its radius about 0.45), looking obliquely along it with the
/// near plane cutting into the tube: many triangles cross the near plane, some reach
/// behind the eye and some far past the screen's sides.
fn near_views() -> Vec<View> {
    let curve = |t: f32| {
        let r = 2.0 + (5.0 * t).cos();
        Vec3::new(r * (3.0 * t).cos(), r * (3.0 * t).sin(), -(5.0 * t).sin())
    };
    let mut rng = Rng(11);
    (0..6)
        .map(|k| {
            let t = rng.range(0.0, std::f32::consts::TAU);
            let c = curve(t);
            let tangent = (curve(t + 1e-3) - curve(t - 1e-3)).normalize();
            let side = tangent.cross(Vec3::Z).normalize();
            let up = side.cross(tangent);
            let s = rng.range(0.0, std::f32::consts::TAU);
            let out = side * s.cos() + up * s.sin();
            let position = c + out * 0.62;
            let target = c + tangent * rng.range(0.5, 1.2);
            let near = [0.3, 0.25, 0.4][k % 3];
            Camera::perspective(position, target, 1.2, near).view([W, H], 0, None)
        })
        .collect()
}

/// Pieces of clipped triangles (more than one piece per triangle index, or a corner on
/// the near plane) among the reference's triangles of `slots` for `view`.
fn clipped_pieces(scene: &SceneData, view: &View, slots: &[Cluster]) -> usize {
    let mut pieces = 0;
    for c in slots {
        let tris = cpu::screen_triangles(scene, view, c, W, H);
        for t in &tris {
            let siblings = tris.iter().filter(|u| u.index == t.index).count();
            if siblings > 1 || t.corners.iter().any(|(_, z)| *z >= 0.999_999) {
                pieces += 1;
            }
        }
    }
    pieces
}

#[test]
fn triangles_crossing_the_near_plane_are_clipped_as_the_reference_clips_them() {
    let mut scene = knot_scene();
    let slots: Vec<Cluster> = [
        clusters_of(&scene, 0, |l| l == 0),
        clusters_of(&scene, 1, |l| l <= 1),
    ]
    .concat();
    let input = Input::every(slots, 7);
    let views = near_views();
    let mut clipped = 0;
    for view in &views {
        clipped += clipped_pieces(&scene, view, &input.slots);
    }
    assert!(clipped > 50, "only {clipped} clipped pieces over the views");
    let want: Vec<Vec<u64>> = views.iter().map(|v| input.reference(&scene, v)).collect();
    for (k, w) in want.iter().enumerate() {
        // Close to the surface, most of the screen is covered.
        assert!(
            covered(w) > (W * H / 3) as usize,
            "view {k}: {}",
            covered(w)
        );
    }
    for (shape, pass) in [
        ("scanline", pass(SCANLINES)),
        ("box", pass(BOXES)),
        (
            "tiled",
            SwRaster {
                big_triangle_px: 8,
                ..pass(SCANLINES)
            },
        ),
    ] {
        let got = run(&mut scene, &input, &views, pass).unwrap_or_else(|e| panic!("{e}"));
        for k in 0..views.len() {
            assert_identical(&format!("{shape}, view {k}"), &got[k], &want[k]);
        }
    }
}

/// A flat square seen from just above with the near plane cutting it: every pixel
/// whose ray meets the square well inside its edges and well past the near plane is
/// covered exactly once, clipped pieces and unclipped triangles alike.
#[test]
fn a_square_cut_by_the_near_plane_has_no_holes_and_no_overlaps() {
    let mut scene = flat_scene(&[("jittered", flat_quad(20, 0.35))]);
    // Low over the square (z = 0, front face +z), looking along it and down a little,
    // the near plane cutting it; one camera rolled, one reaching past the sides.
    let mut rolled = Camera::perspective(
        Vec3::new(-0.2, -0.9, 0.12),
        Vec3::new(0.1, 1.0, -0.3),
        1.4,
        0.2,
    );
    rolled.up = Vec3::new(0.4, 0.0, 1.0);
    let cameras = [
        Camera::perspective(
            Vec3::new(0.0, -0.8, 0.1),
            Vec3::new(0.0, 1.0, -0.25),
            1.0,
            0.3,
        ),
        Camera::perspective(
            Vec3::new(0.3, -0.3, 0.08),
            Vec3::new(-0.2, 1.0, -0.3),
            2.0,
            0.12,
        ),
        rolled,
    ];
    let views: Vec<View> = cameras.iter().map(|c| c.view([W, H], 0, None)).collect();
    let slots = clusters_of(&scene, 0, |l| l == 0);
    let input = Input::every(slots, 2);
    let got = run(&mut scene, &input, &views, pass(SCANLINES)).unwrap_or_else(|e| panic!("{e}"));
    for (k, view) in views.iter().enumerate() {
        let name = format!("view {k}");
        assert!(
            clipped_pieces(&scene, view, &input.slots) > 0,
            "{name}: the near plane cuts nothing"
        );
        let mut coverage = vec![0u32; (W * H) as usize];
        for c in &input.slots {
            for t in cpu::screen_triangles(&scene, view, c, W, H) {
                cpu::cover_triangle(t.corners, W, H, |x, y, _| {
                    coverage[(y * W + x) as usize] += 1
                });
            }
        }
        let twice = coverage.iter().filter(|&&n| n > 1).count();
        assert_eq!(twice, 0, "{name}: {twice} pixels covered more than once");
        // The ray through each pixel centre, met with the plane z = 0.
        let vp = Mat4::from_cols_array_2d(&view.view_projection);
        let inverse = vp.inverse();
        let mut inner = 0;
        let mut holes = 0;
        for i in 0..W * H {
            let ndc = glam::Vec2::new(
                ((i % W) as f32 + 0.5) / W as f32 * 2.0 - 1.0,
                1.0 - ((i / W) as f32 + 0.5) / H as f32 * 2.0,
            );
            let a = inverse.project_point3(ndc.extend(1.0));
            let b = inverse.project_point3(ndc.extend(0.01));
            let t = a.z / (a.z - b.z);
            if !(0.0..=1.0).contains(&t) {
                continue;
            }
            let p = a + (b - a) * t;
            let depth = vp.project_point3(p).z;
            if p.x.abs() < 0.95 && p.y.abs() < 0.95 && depth < 0.98 {
                inner += 1;
                if coverage[i as usize] == 0 {
                    holes += 1;
                }
            }
        }
        assert!(inner > 600, "{name}: only {inner} pixels see the square");
        assert_eq!(holes, 0, "{name}: {holes} pixels inside the square skipped");
        assert_identical(&name, &got[k], &input.reference(&scene, view));
    }
}

#[test]
fn clipping_keeps_a_crossing_edge_shared_by_two_triangles_identical() {
    // Two triangles sharing the edge (a, b), which crosses the near plane: each finds
    // the crossing from the edge's inside corner, so both pieces meet at one point.
    let a = glam::Vec4::new(0.3, -0.2, 0.5, 2.0);
    let b = glam::Vec4::new(-0.1, 0.4, 0.5, 0.2);
    let c = glam::Vec4::new(1.0, 1.0, 0.5, 3.0);
    let d = glam::Vec4::new(-1.5, -0.5, 0.5, 1.5);
    let first = cpu::clip_triangle([a, b, c]);
    let second = cpu::clip_triangle([b, a, d]);
    let on_plane = |p: &Vec<glam::Vec4>| -> Vec<[u32; 4]> {
        p.iter()
            .filter(|v| cpu::plane_distance(**v, 0).abs() < 1e-3)
            .map(|v| v.to_array().map(f32::to_bits))
            .collect()
    };
    let shared: Vec<[u32; 4]> = on_plane(&first)
        .into_iter()
        .filter(|v| on_plane(&second).contains(v))
        .collect();
    assert_eq!(shared.len(), 1, "{first:?} / {second:?}");
    assert!(
        first
            .iter()
            .all(|v| cpu::inside(*v) || cpu::plane_distance(*v, 0).abs() < 1e-5)
    );
}

/// A double-sided material's back faces are drawn, turned to face the eye, by every
/// path of the kernel (whole triangles, clipped pieces, big-triangle tiles): the flat
/// square seen from behind, and the inside of the knot's tube from views that cut into
/// it, match the reference; with a one-sided material the square from behind is empty
/// and the tube's inside is not drawn.
#[test]
fn double_sided_materials_draw_their_back_faces_like_the_reference() {
    let behind =
        Camera::perspective(Vec3::new(0.4, -0.3, -2.6), Vec3::ZERO, 0.9, 0.5).view([W, H], 0, None);
    for two_sided in [false, true] {
        let mut scene = flat_scene(&[("square", flat_quad(3, 0.2))]);
        if two_sided {
            scene.materials[0].flags |= MATERIAL_FLAG_DOUBLE_SIDED;
        }
        let input = Input::every_in_one_row(clusters_of(&scene, 0, |l| l == 0));
        let want = input.reference(&scene, &behind);
        if two_sided {
            assert!(covered(&want) > (W * H / 4) as usize, "{}", covered(&want));
        } else {
            assert_eq!(covered(&want), 0, "a one-sided square from behind");
        }
        let drawing = SwRaster {
            two_sided: true,
            ..pass(SCANLINES)
        };
        // Tiles only where there is something to tile (the run checks tiles were listed).
        let tiled = SwRaster {
            big_triangle_px: 8,
            ..drawing
        };
        let passes = if two_sided {
            // Without the pass's `two_sided`, no material is read: culled like any.
            let off = run(&mut scene, &input, &[behind], pass(SCANLINES)).unwrap();
            assert_eq!(covered(&off[0]), 0, "two_sided off draws no back face");
            vec![drawing, tiled]
        } else {
            vec![drawing]
        };
        for p in passes {
            let got = run(&mut scene, &input, &[behind], p).unwrap_or_else(|e| panic!("{e}"));
            assert_identical(&format!("square, two-sided {two_sided}"), &got[0], &want);
        }
    }

    let views = near_views();
    let mut covered_by = Vec::new();
    for two_sided in [false, true] {
        let mut scene = knot_scene();
        if two_sided {
            for m in &mut scene.materials {
                m.flags |= MATERIAL_FLAG_DOUBLE_SIDED;
            }
        }
        let input = Input::every(clusters_of(&scene, 0, |l| l == 0), 7);
        let want: Vec<Vec<u64>> = views.iter().map(|v| input.reference(&scene, v)).collect();
        let drawing = SwRaster {
            two_sided: true,
            ..pass(SCANLINES)
        };
        let got = run(&mut scene, &input, &views, drawing).unwrap_or_else(|e| panic!("{e}"));
        for k in 0..views.len() {
            assert_identical(
                &format!("knot, two-sided {two_sided}, view {k}"),
                &got[k],
                &want[k],
            );
        }
        covered_by.push(want.iter().map(|w| covered(w)).sum::<usize>());
    }
    // From inside the tube, its back faces fill what the one-sided knot leaves open.
    assert!(
        covered_by[1] > covered_by[0] + (W * H / 4) as usize,
        "pixels covered one-sided, two-sided: {covered_by:?}"
    );
}

/// Pixels where `got` equals neither bracket, of references drawn with the cutoff an
/// eighth of an 8-bit step below and above: a pixel whose alpha lies within rounding of
/// the cutoff may be cut by one and kept by the other, and both rasterisers compute
/// the alpha with the driver's float operations.
fn outside_brackets(got: &[u64], low: &[u64], high: &[u64]) -> Vec<usize> {
    (0..got.len())
        .filter(|&i| got[i] != low[i] && got[i] != high[i])
        .collect()
}

/// The cutoff's brackets (see [`outside_brackets`]).
const CUTOFF_ROUNDING: f32 = 1.0 / 2048.0;

/// A MASK material's pixels whose texture alpha falls below the cutoff are left undrawn
/// by every path of the kernel (whole triangles, big-triangle tiles, pieces of
/// triangles clipped at the near plane), so the opaque square behind shows through, as
/// the reference draws it; without the pass's `alpha_mask` the quad is drawn whole.
#[test]
fn mask_materials_cut_out_the_pixels_the_reference_cuts() {
    let scene = masked_scene(4, 1.0);
    let views = [
        Camera::perspective(Vec3::new(0.3, -0.4, 2.4), Vec3::ZERO, 0.9, 0.5).view([W, H], 0, None),
        // Grazing, from above the quad: its near end is clipped at the near plane.
        Camera::perspective(
            Vec3::new(0.1, -0.9, 0.6),
            Vec3::new(0.0, 0.8, 0.0),
            1.2,
            0.5,
        )
        .view([W, H], 0, None),
    ];
    let clusters = [0, 1]
        .iter()
        .flat_map(|&i| clusters_of(&scene, i, |l| l == 0))
        .collect();
    let input = Input::every_in_one_row(clusters);
    let opaque = with_cutoff(&scene, None);
    let low = with_cutoff(&scene, Some(MASK_CUTOFF - CUTOFF_ROUNDING));
    let high = with_cutoff(&scene, Some(MASK_CUTOFF + CUTOFF_ROUNDING));
    let front = |v: &[u64]| {
        v.iter()
            .filter(|&&p| {
                p != visbuffer::EMPTY && input.slots[visbuffer::cluster(p) as usize].instance == 0
            })
            .count()
    };
    let drawing = SwRaster {
        alpha_mask: true,
        ..pass(SCANLINES)
    };
    let tiled = SwRaster {
        big_triangle_px: 8,
        ..drawing
    };
    for (k, view) in views.iter().enumerate() {
        let whole = input.reference(&opaque, view);
        let want = input.reference(&scene, view);
        // The checker cuts about half the quad, and the square behind fills the holes.
        let (kept, all) = (front(&want), front(&whole));
        assert!(
            kept > all / 4 && kept < all * 3 / 4,
            "view {k}: the reference keeps {kept} of the quad's {all} pixels"
        );
        assert!(
            covered(&want) > kept + (all - kept) / 2,
            "view {k}: nothing shows behind"
        );
        let (low, high) = (input.reference(&low, view), input.reference(&high, view));
        for p in [drawing, tiled] {
            let got =
                run(&mut scene.clone(), &input, &[*view], p).unwrap_or_else(|e| panic!("{e}"));
            let wrong = outside_brackets(&got[0], &low, &high);
            assert!(
                wrong.is_empty(),
                "view {k}, big_triangle_px {}: {} pixels differ from the reference, first at {:?}: GPU {} / CPU {}",
                p.big_triangle_px,
                wrong.len(),
                wrong.first().map(|&i| (i as u32 % W, i as u32 / W)),
                wrong
                    .first()
                    .map_or(String::new(), |&i| describe(got[0][i])),
                wrong.first().map_or(String::new(), |&i| describe(want[i])),
            );
        }
        // Without the pass's `alpha_mask`, no material is read: the quad is whole.
        let off = run(&mut scene.clone(), &input, &[*view], pass(SCANLINES)).unwrap();
        assert_identical(&format!("view {k}, alpha_mask off"), &off[0], &whole);
    }
}

/// A depth-only pass (a shadow map's) draws one layer of a stack of `u32` depths: the
/// layer holds the high word of the reference's visibility values, bit for bit, and the
/// other layers keep what they held.
#[test]
fn a_depth_only_layer_holds_the_references_depths_and_leaves_the_other_layers() {
    let mut scene = knot_scene();
    let slots: Vec<Cluster> = [
        clusters_of(&scene, 0, |l| l == 0),
        clusters_of(&scene, 1, |l| l == 2),
    ]
    .concat();
    let count = slots.len() as u32;
    let input = Input::new(slots, count, count);
    let views = seeded_views(11, 2);
    let layer_len = (W * H) as usize;
    let stale: Vec<u32> = (0..2 * layer_len as u32).map(|i| i * 7 + 1).collect();
    for raster in [
        pass(SCANLINES),
        SwRaster {
            big_triangle_px: 3,
            ..pass(BOXES)
        },
    ] {
        let raster = SwRaster {
            depth_only: true,
            layer: 1,
            ..raster
        };
        let gpu = gpu();
        let gpu_scene = GpuScene::new(&gpu, &mut scene);
        let mut g = GraphBuilder::new();
        gpu_scene.import(&mut g);
        let Imported {
            buffers: [.., maps],
            imports,
            ..
        } = import_filled(
            &mut g,
            &gpu,
            [
                filled("raster_clusters", elements::CLUSTER, &input.slots),
                filled("raster_counts", Element::U32, &[count, 0, 0, 0]),
                filled("sw_args", Element::DISPATCH_ARGS, &input.args),
                filled("visbuffer", Element::U32, &stale),
            ],
            gpu_scene.imports(),
        );
        g.add_pass("shadow_raster", raster, Bindings::new())
            .unwrap_or_else(|e| panic!("{e}"));
        let compiled = g
            .compile(&CompileOptions::for_gpu(&gpu))
            .unwrap_or_else(|e| panic!("{e}"));
        // A depth-only pass asks nothing of the 64-bit atomics.
        assert!(
            !compiled
                .plan
                .enabled_features
                .contains(wgpu::Features::SHADER_INT64_ATOMIC_MIN_MAX)
        );
        let mut exec = Executor::new(gpu);
        let got = run_per_view(&mut exec, &compiled, &imports, &views, |exec| {
            let bytes = exec.gpu.read_buffer(&maps, 0, (2 * layer_len * 4) as u64)?;
            Ok(bytemuck::pod_collect_to_vec::<u8, u32>(&bytes))
        })
        .unwrap_or_else(|e| panic!("{e}"));
        for (k, (maps, view)) in got.iter().zip(&views).enumerate() {
            assert_eq!(
                &maps[..layer_len],
                &stale[..layer_len],
                "view {k}: layer 0 was touched"
            );
            let want: Vec<u32> = input
                .reference(&scene, view)
                .iter()
                .map(|&v| (v >> 32) as u32)
                .collect();
            assert!(
                want.iter().filter(|&&d| d != 0).count() > 300,
                "view {k} covers little"
            );
            let wrong = (0..layer_len)
                .filter(|&i| maps[layer_len + i] != want[i])
                .count();
            assert_eq!(
                wrong, 0,
                "view {k}: {wrong} depths differ from the reference"
            );
        }
    }
}

#[test]
fn a_layer_without_depth_only_is_a_parameter_error() {
    let params = meshlight_testing::params("width = 96\nheight = 64\nlayer = 2");
    let e = SwRaster::from_params(&params, Visibility64::Buffer).unwrap_err();
    assert!(e.to_string().contains("`depth_only = true`"), "{e}");
    let params = meshlight_testing::params("width = 90\nheight = 66\ndepth_only = true");
    let e = SwRaster::from_params(&params, Visibility64::Buffer)
        .unwrap_err()
        .to_string();
    assert!(e.contains("multiple of 256"), "{e}");
}
