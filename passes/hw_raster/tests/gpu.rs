//! `hw_raster` on the GPU (lavapipe in CI) against `cpu::rasterize` and against the
//! software rasteriser's reference, on two instances of the procedural mesh; surplus
//! triangles, the software slots, the earlier contents of the visibility buffer and the
//! errors.

use glam::{Mat4, Vec3};
use meshlight_gpu_scene::{Camera, GpuScene, SceneData};
use meshlight_graph::*;
use meshlight_pass_hw_raster::{Feed, HwRaster, VERTICES_PER_CLUSTER, cpu};
use meshlight_scene::asset::format::MeshletRecord;
use meshlight_scene::procedural_mesh;
use meshlight_shaders::cpu::layout::{Cluster, View};
use meshlight_shaders::cpu::visbuffer;

const W: u32 = 128;
const H: u32 = 96;
/// Software slots at the left of the slot buffer: real clusters the pass must not draw.
const SOFTWARE: u32 = 3;
/// Unused slots between the software and hardware ones.
const GAP: u32 = 2;

use meshlight_gpu_scene::gpu::elements;
use meshlight_testing::features::where_supported;
use meshlight_testing::frames::{Imported, filled, import_filled, run_per_view};
use meshlight_testing::gpu;

#[path = "../../sw_raster/tests/support/scenes.rs"]
mod scenes;

/// A scene, a camera, and the slot buffer culling would have left.
struct Frame {
    scene: SceneData,
    view: View,
    raster_clusters: Vec<Cluster>,
    hw_count: u32,
    /// What the software pass left in the visibility buffer.
    initial: Vec<u64>,
    /// The pass's `two_sided` (on unless a test turns it off).
    two_sided: bool,
    /// The pass's `alpha_mask` (off unless a test turns it on).
    alpha_mask: bool,
}

impl Frame {
    /// The integer reference's visibility buffer for this frame.
    fn reference(&self) -> Vec<u64> {
        cpu::rasterize(
            &self.scene,
            &self.view,
            &self.raster_clusters,
            self.hw_count,
            &self.initial,
            W,
            H,
        )
    }
}

/// The knot at its place and a smaller copy moved up and turned.
fn scene() -> SceneData {
    scenes::knot_scene(&procedural_mesh(12), &[])
}

/// The meshlets `pick` chooses, of every instance, in hardware slots; `SOFTWARE` real clusters in
/// the software slots; a visibility buffer holding a near band (which must survive) and
/// a far band (which must be overdrawn) from the "software" pass.
fn frame(
    scene: SceneData,
    camera: Camera,
    pick: impl Fn(&Cluster, &MeshletRecord) -> bool,
) -> Frame {
    let view = camera.view([W, H], 0, None);
    let mut hardware = Vec::new();
    for (i, instance) in scene.instances.iter().enumerate() {
        for m in instance.first_meshlet..instance.first_meshlet + instance.meshlet_count {
            let c = Cluster {
                instance: i as u32,
                meshlet: m,
            };
            if pick(&c, &scene.meshlets[m as usize]) {
                hardware.push(c);
            }
        }
    }
    let hw_count = hardware.len() as u32;
    let capacity = SOFTWARE + GAP + hw_count;
    let mut raster_clusters = vec![
        Cluster {
            instance: 0,
            meshlet: 0
        };
        capacity as usize
    ];
    for (j, c) in hardware.into_iter().enumerate() {
        raster_clusters[(capacity - 1) as usize - j] = c;
    }
    let initial = (0..W * H)
        .map(|i| match (i % W) / 8 {
            3 => visbuffer::pack(0.9999, 1, 5),
            9 => visbuffer::pack(1e-6, 2, 9),
            _ => visbuffer::EMPTY,
        })
        .collect();
    Frame {
        scene,
        view,
        raster_clusters,
        hw_count,
        initial,
        two_sided: true,
        alpha_mask: false,
    }
}

fn camera() -> Camera {
    Camera::perspective(
        Vec3::new(1.0, 3.0, 12.0),
        Vec3::new(0.5, 0.2, 0.0),
        0.8,
        0.5,
    )
}

/// Runs the pass over `frame` and reads the visibility buffer back.
fn run(frame: &mut Frame) -> Vec<u64> {
    run_fed(frame, Feed::IndirectDraw).unwrap_or_else(|e| panic!("{e}"))
}

/// [`run`] with either implementation; compile and frame errors come back.
fn run_fed(frame: &mut Frame, feed: Feed) -> Result<Vec<u64>> {
    let gpu = gpu();
    let scene = GpuScene::new(&gpu, &mut frame.scene);
    let capacity = frame.raster_clusters.len() as u32;
    let counts: [u32; 8] = [SOFTWARE, frame.hw_count, 0, capacity, 0, 0, 0, 0];
    let args = [VERTICES_PER_CLUSTER, frame.hw_count, 0, 0];
    let mut g = GraphBuilder::new();
    scene.import(&mut g);
    // Each buffer is imported under its slot's name, which binds it.
    let Imported {
        buffers: [.., visbuffer],
        imports,
        ..
    } = import_filled(
        &mut g,
        &gpu,
        [
            filled("raster_clusters", elements::CLUSTER, &frame.raster_clusters),
            filled("raster_counts", Element::U32, &counts),
            filled("hw_args", Element::DRAW_ARGS, &args),
            filled("visbuffer", Element::U64, &frame.initial),
        ],
        scene.imports(),
    );
    g.add_pass(
        "hw_raster",
        HwRaster {
            auto_skip: false,
            width: W,
            height: H,
            feed,
            two_sided: frame.two_sided,
            alpha_mask: frame.alpha_mask,
            depth_only: false,
            layer: 0,
        },
        Bindings::new(),
    )?;
    let compiled = g.compile(&CompileOptions::for_gpu(&gpu))?;
    let mut exec = Executor::new(gpu);
    let mut frames = run_per_view(&mut exec, &compiled, &imports, &[frame.view], |exec| {
        let bytes = exec.gpu.read_buffer(&visbuffer, 0, (W * H) as u64 * 8)?;
        Ok(bytemuck::pod_collect_to_vec(&bytes))
    })?;
    Ok(frames.remove(0))
}

/// Depth agreement with the float reference: 1e-5 on lavapipe, which interpolates from
/// the unsnapped corners in f32 as the reference does; on a GPU's fixed-function
/// interpolation 4e-5 (an NVIDIA H100 reached 2e-5 on steep triangles), plus what its
/// vertex snapping moves a steep surface ([`SNAP_PX`]).
fn depth_tolerance() -> DepthTolerance {
    if gpu().adapter.get_info().device_type == wgpu::DeviceType::Cpu {
        DepthTolerance::flat(1e-5)
    } else {
        DepthTolerance {
            flat: 4e-5,
            snap_px: SNAP_PX,
        }
    }
}

/// How far a rasteriser's depth may stray from a reference's at a pixel: `flat`, plus
/// the reference's depth slope there times `snap_px`.
#[derive(Clone, Copy, Debug)]
struct DepthTolerance {
    flat: f32,
    snap_px: f32,
}

impl DepthTolerance {
    /// The same bound at every pixel: for rasterisers that snap alike, or not at all.
    fn flat(flat: f32) -> Self {
        Self { flat, snap_px: 0.0 }
    }
}

/// How two visibility buffers agree: pixels covered by either, of those the ones with
/// the same id, and the depth differences on those with what the reference's depth
/// slope allows there.
struct Agreement {
    covered: usize,
    same_id: usize,
    depth_diffs: Vec<DepthDiff>,
}

struct DepthDiff {
    diff: f32,
    /// The reference's depth change per pixel there, across x plus across y.
    slope: f32,
}

/// How far a GPU's rasteriser may move a surface on the screen, in pixels: it snaps
/// vertices to a 1/256-pixel grid, which the float reference does not. Where a
/// triangle's depth changes steeply, that shift alone changes the depth at a pixel by the
/// slope times this, which no bound for flat triangles covers.
const SNAP_PX: f32 = 1.0 / 256.0;

impl Agreement {
    fn depth_within(&self, tolerance: DepthTolerance) -> usize {
        self.depth_diffs
            .iter()
            .filter(|d| d.diff <= tolerance.flat + d.slope * tolerance.snap_px)
            .count()
    }
    fn max_depth_diff(&self) -> f32 {
        self.depth_diffs.iter().map(|d| d.diff).fold(0.0, f32::max)
    }
}

/// The depth change per pixel of the reference at pixel `i`, across x plus across y,
/// measured to the neighbours it covers (0 where it covers none). Those may show other
/// triangles: a pixel on a silhouette often holds a sliver of a steep triangle whose
/// own neighbours are empty, and the surface around it slopes as that triangle does.
fn depth_slope(want: &[u64], i: usize) -> f32 {
    let (x, y) = (i as u32 % W, i as u32 / W);
    let at = |x: u32, y: u32| want[(y * W + x) as usize];
    let here = visbuffer::depth(want[i]);
    let across = |neighbours: [Option<u64>; 2]| {
        neighbours
            .into_iter()
            .flatten()
            .filter(|&v| v != visbuffer::EMPTY)
            .map(|v| (visbuffer::depth(v) - here).abs())
            .fold(0.0, f32::max)
    };
    let dx = across([
        (x > 0).then(|| at(x - 1, y)),
        (x + 1 < W).then(|| at(x + 1, y)),
    ]);
    let dy = across([
        (y > 0).then(|| at(x, y - 1)),
        (y + 1 < H).then(|| at(x, y + 1)),
    ]);
    dx + dy
}

fn agreement(got: &[u64], want: &[u64]) -> Agreement {
    let mut a = Agreement {
        covered: 0,
        same_id: 0,
        depth_diffs: Vec::new(),
    };
    for (i, (&g, &w)) in got.iter().zip(want).enumerate() {
        if g == visbuffer::EMPTY && w == visbuffer::EMPTY {
            continue;
        }
        a.covered += 1;
        if g as u32 == w as u32 && (g == visbuffer::EMPTY) == (w == visbuffer::EMPTY) {
            a.same_id += 1;
            a.depth_diffs.push(DepthDiff {
                diff: (visbuffer::depth(g) - visbuffer::depth(w)).abs(),
                slope: depth_slope(want, i),
            });
        }
    }
    a
}

/// At least `min_covered` pixels covered, ≥ 99% of them with identical ids, and depth
/// on those within `depth_tolerance` on ≥ 99.9% of them and within 1e-4 on all.
fn check(
    name: &str,
    got: &[u64],
    want: &[u64],
    min_covered: usize,
    depth_tolerance: DepthTolerance,
) {
    let a = agreement(got, want);
    let share = a.same_id as f64 / a.covered.max(1) as f64;
    let depth_share = a.depth_within(depth_tolerance) as f64 / a.same_id.max(1) as f64;
    eprintln!(
        "{name}: {} covered pixels, {} with the same id ({:.3}%), depth within {:e} (+ slope × {}) on {:.3}% of those, largest difference {:e}",
        a.covered,
        a.same_id,
        share * 100.0,
        depth_tolerance.flat,
        depth_tolerance.snap_px,
        depth_share * 100.0,
        a.max_depth_diff()
    );
    assert!(
        a.covered >= min_covered,
        "{name}: only {} pixels covered",
        a.covered
    );
    assert!(
        share >= 0.99,
        "{name}: only {:.3}% identical ids",
        share * 100.0
    );
    assert!(
        depth_share >= 0.999,
        "{name}: depth within {:e} (+ slope × {}) on only {:.3}%",
        depth_tolerance.flat,
        depth_tolerance.snap_px,
        depth_share * 100.0
    );
    assert!(
        a.max_depth_diff() <= 1e-4,
        "{name}: depth differs by {:e}",
        a.max_depth_diff()
    );
}

/// Every drawn value names a hardware slot and a triangle the meshlet has, or is one
/// the software pass left.
fn check_ids(frame: &Frame, got: &[u64]) {
    let slots = cpu::hardware_slots(frame.raster_clusters.len() as u32, frame.hw_count);
    for (i, (&g, &before)) in got.iter().zip(&frame.initial).enumerate() {
        assert!(g >= before, "pixel {i} lost the software pass's value");
        if g == visbuffer::EMPTY || g == before {
            continue;
        }
        let slot = visbuffer::cluster(g);
        assert!(
            slots.contains(&slot),
            "pixel {i}: slot {slot} is not hardware"
        );
        let c = frame.raster_clusters[slot as usize];
        let count = frame.scene.meshlets[c.meshlet as usize].triangle_count();
        let t = visbuffer::triangle(g);
        assert!(
            t < count,
            "pixel {i}: triangle {t} of a {count}-triangle meshlet"
        );
    }
}

/// The software rasteriser's fixed-point reference (`meshlight_pass_sw_raster::cpu`:
/// its snapping, edge functions, top-left rule and depth) over the hardware slots, onto
/// `initial`. Its `cover_triangle` keeps triangles clockwise on the y-down screen, so
/// corners go in as (0, 2, 1): the contract's front faces are counter-clockwise in NDC,
/// the mesh's outside, which the hardware keeps with `FrontFace::Ccw`.
fn fixed_point_reference(f: &Frame) -> Vec<u64> {
    use meshlight_pass_sw_raster::cpu::{cover_triangle, snap};
    let mut out = f.initial.clone();
    let view_projection = Mat4::from_cols_array_2d(&f.view.view_projection);
    for slot in cpu::hardware_slots(f.raster_clusters.len() as u32, f.hw_count) {
        let c = f.raster_clusters[slot as usize];
        let instance = &f.scene.instances[c.instance as usize];
        let mesh = &f.scene.meshes[instance.mesh as usize];
        let m = &f.scene.meshlets[c.meshlet as usize];
        let world_from_local = Mat4::from_cols_array_2d(&instance.world_from_local);
        let (positions, corners) = cpu::decode_geometry(&f.scene, mesh, m);
        let screen: Vec<_> = positions
            .iter()
            .map(|&p| {
                let clip = cpu::clip_position(&world_from_local, &view_projection, p);
                snap(clip, [W as f32, H as f32])
            })
            .collect();
        for (t, k) in corners.iter().enumerate() {
            let [Some(a), Some(b), Some(c)] = [k[0], k[2], k[1]].map(|i| screen[i as usize]) else {
                continue;
            };
            cover_triangle([a, b, c], W, H, |x, y, depth| {
                let px = &mut out[(y * W + x) as usize];
                *px = (*px).max(visbuffer::pack(depth, slot, t as u32));
            });
        }
    }
    out
}

#[test]
fn hardware_raster_matches_both_references_and_keeps_the_software_values() {
    let mut f = frame(scene(), camera(), |_, m| m.level() == 0);
    let got = run(&mut f);
    let want = f.reference();
    // The float reference interpolates depth from the unsnapped corners, as lavapipe
    // does: within 1e-5 everywhere.
    check("float reference", &got, &want, 2000, depth_tolerance());
    assert!(agreement(&got, &want).max_depth_diff() <= depth_tolerance().flat);
    check_ids(&f, &got);

    let fixed = fixed_point_reference(&f);
    // The software rasteriser interpolates from corners snapped to 1/256 pixel: on
    // steep triangles that moves depth by up to the depth gradient × 1/512 pixel.
    check(
        "software rasteriser's fixed point",
        &got,
        &fixed,
        2000,
        depth_tolerance(),
    );

    // Both instances are seen, the near band survives, the far band is overdrawn.
    let slots = cpu::hardware_slots(f.raster_clusters.len() as u32, f.hw_count);
    let instances: std::collections::BTreeSet<u32> = got
        .iter()
        .filter(|&&g| slots.contains(&visbuffer::cluster(g)) && g != visbuffer::EMPTY)
        .map(|&g| f.raster_clusters[visbuffer::cluster(g) as usize].instance)
        .collect();
    assert_eq!(instances.len(), 2, "{instances:?}");
    let near = visbuffer::pack(0.9999, 1, 5);
    let far = visbuffer::pack(1e-6, 2, 9);
    assert!(
        got.iter()
            .zip(&f.initial)
            .all(|(g, i)| *i != near || g == i)
    );
    let overdrawn = got
        .iter()
        .zip(&f.initial)
        .filter(|(g, i)| **i == far && g > i)
        .count();
    assert!(overdrawn > 0, "the far band was never drawn over");
}

#[test]
fn meshlets_with_fewer_than_128_triangles_draw_nothing_past_their_count() {
    let scene = scene();
    // The meshlet of instance 0 with the fewest triangles (LOD-0 ones are full), seen
    // up close.
    let first = scene.instances[0].first_meshlet;
    let (index, m) = scene
        .meshlets
        .iter()
        .enumerate()
        .skip(first as usize)
        .take(scene.instances[0].meshlet_count as usize)
        .min_by_key(|(_, m)| m.triangle_count())
        .unwrap();
    assert!(m.triangle_count() < 128, "{}", m.triangle_count());
    let centre = Vec3::from_slice(&m.bounds[..3]);
    let radius = m.bounds[3];
    let mut best = None;
    // Look from the side that shows the most of it.
    for dir in [Vec3::X, -Vec3::X, Vec3::Y, -Vec3::Y, Vec3::Z, -Vec3::Z] {
        let camera = Camera::perspective(centre + dir * radius * 3.0, centre, 0.9, radius * 0.5);
        let mut f = frame(scene.clone(), camera, |c, _| {
            c.instance == 0 && c.meshlet == index as u32
        });
        f.initial = vec![visbuffer::EMPTY; (W * H) as usize];
        let want = f.reference();
        let covered = want.iter().filter(|&&v| v != visbuffer::EMPTY).count();
        if best.as_ref().is_none_or(|(n, _, _)| covered > *n) {
            best = Some((covered, f, want));
        }
    }
    let (covered, mut f, want) = best.unwrap();
    assert_eq!(f.hw_count, 1);
    assert!(covered > 300, "{covered}");
    let got = run(&mut f);
    check("one small meshlet", &got, &want, 300, depth_tolerance());
    check_ids(&f, &got);
}

/// `mesh_shader` draws the clusters `indirect_draw` draws, where the adapter has mesh
/// shaders (NVIDIA through Vulkan): ≥ 99% identical ids and both within the float
/// reference's tolerance. Where it has not (lavapipe), compiling it is the typed error
/// naming the feature.
#[test]
fn mesh_shader_draws_what_the_indirect_draw_draws_or_names_the_missing_feature() {
    let mut f = frame(scene(), camera(), |_, m| m.level() <= 1);
    let Some(mesh) = where_supported(
        run_fed(&mut f, Feed::MeshShader),
        wgpu::Features::EXPERIMENTAL_MESH_SHADER,
        "hw_raster",
        "EXPERIMENTAL_MESH_SHADER",
        "mesh shaders",
    ) else {
        return;
    };
    let indirect = run(&mut f);
    check(
        "mesh shader against indirect draw",
        &mesh,
        &indirect,
        2000,
        DepthTolerance::flat(1e-6),
    );
    let want = f.reference();
    check(
        "mesh shader against the float reference",
        &mesh,
        &want,
        2000,
        DepthTolerance::flat(1e-5),
    );
    check_ids(&f, &mesh);
}

#[test]
fn a_viewport_other_than_the_params_is_a_record_error_and_zero_size_a_parameter_error() {
    let mut f = frame(scene(), camera(), |_, m| m.level() == 0);
    f.view = camera().view([W + 1, H], 0, None);
    let result = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| run(&mut f)));
    let message = match result {
        Err(e) => e
            .downcast_ref::<String>()
            .cloned()
            .unwrap_or_else(|| "?".into()),
        Ok(_) => panic!("a mismatched viewport ran"),
    };
    assert!(
        message.contains("viewport") && message.contains(&format!("{W} × {H}")),
        "{message}"
    );

    // Registered for pipeline files; a file that leaves the size out is refused.
    let mut registry = file::Registry::new();
    meshlight_pass_hw_raster::register(&mut registry);
    match registry.build("hw_raster", "indirect_draw", &file::Params::default()) {
        Err(GraphError::Parameter { message, .. }) => assert!(message.contains("width")),
        Err(other) => panic!("{other}"),
        Ok(_) => panic!("a zero-sized visibility buffer was accepted"),
    }
}

/// A double-sided material's back faces are drawn, turned to face the eye; a one-sided
/// material's are culled. The flat square seen from behind: empty one-sided, drawn whole
/// two-sided, as the float reference draws it, by the indirect draw and (where the
/// adapter has mesh shaders) the mesh shader.
#[test]
fn double_sided_materials_draw_their_back_faces_like_the_reference() {
    let behind = Camera::perspective(Vec3::new(0.4, -0.3, -2.6), Vec3::ZERO, 0.9, 0.5);
    for two_sided in [false, true] {
        let mut scene = SceneData::new(meshlight_gpu_scene::data::Limits::default());
        let square = scenes::add_mesh(&mut scene, "square", &scenes::flat_quad(6, 0.2));
        let material = scene
            .add_material(meshlight_gpu_scene::Material {
                double_sided: two_sided,
                ..meshlight_gpu_scene::Material::default()
            })
            .unwrap();
        scene
            .add_instance(square, Mat4::IDENTITY, material)
            .unwrap()
            .unwrap();
        let mut f = frame(scene, behind, |_, m| m.level() == 0);
        f.initial = vec![visbuffer::EMPTY; (W * H) as usize];
        let want = f.reference();
        let covered = want.iter().filter(|&&v| v != visbuffer::EMPTY).count();
        let name = format!("square from behind, two-sided {two_sided}");
        let got = run(&mut f);
        if !two_sided {
            assert_eq!(covered, 0, "{name}: the reference drew back faces");
            assert!(
                got.iter().all(|&v| v == visbuffer::EMPTY),
                "{name}: back faces were drawn"
            );
            continue;
        }
        assert!(covered > (W * H / 4) as usize, "{name}: {covered}");
        check(&name, &got, &want, covered * 99 / 100, depth_tolerance());
        // Without the pass's `two_sided`, no material is read: culled like any.
        f.two_sided = false;
        assert!(
            run(&mut f).iter().all(|&v| v == visbuffer::EMPTY),
            "{name}: two_sided off drew back faces"
        );
        f.two_sided = true;
        check_ids(&f, &got);
        if let Some(mesh) = where_supported(
            run_fed(&mut f, Feed::MeshShader),
            wgpu::Features::EXPERIMENTAL_MESH_SHADER,
            "hw_raster",
            "EXPERIMENTAL_MESH_SHADER",
            "mesh shaders",
        ) {
            check(
                &format!("{name}, mesh shader"),
                &mesh,
                &want,
                covered * 99 / 100,
                depth_tolerance(),
            );
        }
    }
}

/// A MASK material's fragments whose texture alpha falls below the cutoff write
/// nothing, so the opaque square behind shows through where the reference shows it; off,
/// the quad is drawn whole. The `mesh_shader` implementation refuses `alpha_mask` with
/// an error that names the way out.
#[test]
fn mask_materials_cut_out_the_fragments_the_reference_cuts() {
    let camera = Camera::perspective(Vec3::new(0.3, -0.4, 2.4), Vec3::ZERO, 0.9, 0.5);
    let mut f = frame(scenes::masked_scene(4, 1.0), camera, |_, m| m.level() == 0);
    f.initial = vec![visbuffer::EMPTY; (W * H) as usize];
    f.alpha_mask = true;
    let want = f.reference();
    let masked_quad = |v: &[u64]| {
        v.iter()
            .filter(|&&p| {
                p != visbuffer::EMPTY
                    && f.raster_clusters[visbuffer::cluster(p) as usize].instance == 0
            })
            .count()
    };
    let whole = cpu::rasterize(
        &scenes::with_cutoff(&f.scene, None),
        &f.view,
        &f.raster_clusters,
        f.hw_count,
        &f.initial,
        W,
        H,
    );
    let (kept, all) = (masked_quad(&want), masked_quad(&whole));
    assert!(
        kept > all / 4 && kept < all * 3 / 4,
        "the reference keeps {kept} of the quad's {all} pixels"
    );
    let covered = want.iter().filter(|&&v| v != visbuffer::EMPTY).count();
    let got = run(&mut f);
    check(
        "masked quad",
        &got,
        &want,
        covered * 99 / 100,
        depth_tolerance(),
    );
    check_ids(&f, &got);
    // Without the pass's `alpha_mask`, no material is read: the quad is whole.
    f.alpha_mask = false;
    let off = run(&mut f);
    check(
        "masked quad, alpha_mask off",
        &off,
        &whole,
        covered * 99 / 100,
        depth_tolerance(),
    );
    f.alpha_mask = true;
    match run_fed(&mut f, Feed::MeshShader) {
        Err(e) if e.to_string().contains("indirect_draw") => {}
        Err(e) if e.to_string().contains("EXPERIMENTAL_MESH_SHADER") => {}
        other => panic!("mesh_shader with alpha_mask: {:?}", other.map(|_| ())),
    }
}

/// A depth-only pass (a shadow map's) draws layer 1 of a stack of `u32` depths onto what
/// it held: each depth is the high word of the visibility value the ordinary pass writes
/// over the same contents, and layer 0 keeps what it held. Both feeds where the adapter
/// has them.
#[test]
fn a_depth_only_layer_holds_the_visibility_passs_depths_and_leaves_the_other_layer() {
    let mut f = frame(scene(), camera(), |_, m| m.level() == 0);
    let want: Vec<u32> = run(&mut f).iter().map(|&v| (v >> 32) as u32).collect();
    assert!(
        want.iter().filter(|&&d| d != 0).count() > 300,
        "the frame covers little"
    );
    let layer = (W * H) as usize;
    let stale: Vec<u32> = (0..layer as u32).map(|i| i * 3 + 1).collect();
    let initial: Vec<u32> = stale
        .iter()
        .copied()
        .chain(f.initial.iter().map(|&v| (v >> 32) as u32))
        .collect();
    for feed in [Feed::IndirectDraw, Feed::MeshShader] {
        let gpu = gpu();
        if feed == Feed::MeshShader
            && !gpu
                .features
                .contains(wgpu::Features::EXPERIMENTAL_MESH_SHADER)
        {
            continue;
        }
        let scene = GpuScene::new(&gpu, &mut f.scene);
        let capacity = f.raster_clusters.len() as u32;
        let counts: [u32; 8] = [SOFTWARE, f.hw_count, 0, capacity, 0, 0, 0, 0];
        let args = [VERTICES_PER_CLUSTER, f.hw_count, 0, 0];
        let mut g = GraphBuilder::new();
        scene.import(&mut g);
        let Imported {
            buffers: [.., maps],
            imports,
            ..
        } = import_filled(
            &mut g,
            &gpu,
            [
                filled("raster_clusters", elements::CLUSTER, &f.raster_clusters),
                filled("raster_counts", Element::U32, &counts),
                filled("hw_args", Element::DRAW_ARGS, &args),
                filled("visbuffer", Element::U32, &initial),
            ],
            scene.imports(),
        );
        let pass = HwRaster {
            depth_only: true,
            layer: 1,
            feed,
            ..HwRaster::indirect(W, H)
        };
        g.add_pass("shadow_hw_raster", pass, Bindings::new())
            .unwrap_or_else(|e| panic!("{e}"));
        let compiled = g
            .compile(&CompileOptions::for_gpu(&gpu))
            .unwrap_or_else(|e| panic!("{e}"));
        let mut exec = Executor::new(gpu);
        let got = run_per_view(&mut exec, &compiled, &imports, &[f.view], |exec| {
            let bytes = exec.gpu.read_buffer(&maps, 0, (2 * layer * 4) as u64)?;
            Ok(bytemuck::pod_collect_to_vec::<u8, u32>(&bytes))
        })
        .unwrap_or_else(|e| panic!("{e}"))
        .remove(0);
        assert_eq!(&got[..layer], &stale[..], "{feed:?}: layer 0 was touched");
        let differ = (0..layer).filter(|&i| got[layer + i] != want[i]).count();
        assert_eq!(
            differ, 0,
            "{feed:?}: {differ} depths differ from the visibility pass's"
        );
    }
}
