//! `brute_force` on the GPU (lavapipe in CI) against `cpu::draw`: overlapping instances
//! of the procedural mesh from the GPU scene's instance buffer, a second frame from
//! another camera (the targets are cleared every frame), and the record errors.

use glam::{Mat4, Quat, Vec3};
use meshlight_gpu_scene::{Camera, GpuScene, SceneData};
use meshlight_graph::*;
use meshlight_pass_brute_force::{
    BruteForce, DEPTH_FORMAT, EMPTY_ID, IDS_FORMAT, Lod0Buffers, cpu, lod0_buffers,
};
use meshlight_scene::procedural_mesh;
use meshlight_shaders::cpu::layout::View;

const W: u32 = 96;
const H: u32 = 64;

const BUFFER_USAGE: wgpu::BufferUsages = wgpu::BufferUsages::STORAGE
    .union(wgpu::BufferUsages::INDEX)
    .union(wgpu::BufferUsages::COPY_DST)
    .union(wgpu::BufferUsages::COPY_SRC);
const TEXTURE_USAGE: wgpu::TextureUsages = wgpu::TextureUsages::RENDER_ATTACHMENT
    .union(wgpu::TextureUsages::COPY_SRC)
    .union(wgpu::TextureUsages::COPY_DST);

use meshlight_testing::frames::run_per_view;
use meshlight_testing::{gpu, read_texture, texture};

#[path = "../../sw_raster/tests/support/scenes.rs"]
mod scenes;

/// The mesh's LOD 0 and a GPU scene of overlapping instances of its asset.
struct Scene {
    mesh: Lod0Buffers,
    data: SceneData,
}

/// Four knots: the two the rasterisers' tests draw, then two more, turned and stretched.
fn scene() -> Scene {
    let mesh = procedural_mesh(8);
    let placements = [
        Mat4::from_scale_rotation_translation(
            Vec3::splat(0.8),
            Quat::from_rotation_x(1.1),
            Vec3::new(-2.0, -0.5, 1.0),
        ),
        Mat4::from_scale_rotation_translation(
            Vec3::new(1.2, 0.7, 1.0),
            Quat::from_rotation_z(0.4),
            Vec3::new(0.5, -1.5, -3.0),
        ),
    ];
    Scene {
        data: scenes::knot_scene(&mesh, &placements),
        mesh: lod0_buffers(&mesh),
    }
}

fn camera() -> Camera {
    Camera::perspective(Vec3::new(1.0, 2.5, 8.0), Vec3::new(0.5, 0.2, 0.0), 0.8, 0.5)
}

/// Another camera, further and from the side: most pixels change owner or empty.
fn other_camera() -> Camera {
    Camera::perspective(
        Vec3::new(-14.0, 2.0, 12.0),
        Vec3::new(1.0, 0.0, 0.0),
        0.9,
        0.5,
    )
}

/// The two targets read back.
struct Targets {
    depth: Vec<f32>,
    ids: Vec<u32>,
}

/// A graph of the one pass over imported buffers and targets, run once per view in
/// `views` with the same executor (so the targets keep what the frame before left);
/// returns the targets after each frame, or the first error.
fn run(
    scene: &mut Scene,
    pass: BruteForce,
    views: &[View],
    ids_size: [u32; 2],
) -> Result<Vec<Targets>> {
    let gpu = gpu();
    let gpu_scene = GpuScene::new(&gpu, &mut scene.data);
    let mut g = GraphBuilder::new();
    gpu_scene.import(&mut g);
    // Each resource is named as the slot it binds.
    g.import_buffer(
        "positions",
        BufferDesc::array(Element::VEC4_F32, scene.mesh.positions.len() as u64),
        BUFFER_USAGE,
    );
    g.import_buffer(
        "indices",
        BufferDesc::array(Element::U32, scene.mesh.indices.len() as u64),
        BUFFER_USAGE,
    );
    g.import_texture("depth", TextureDesc::d2(DEPTH_FORMAT, W, H), TEXTURE_USAGE);
    g.import_texture(
        "ids",
        TextureDesc::d2(IDS_FORMAT, ids_size[0], ids_size[1]),
        TEXTURE_USAGE,
    );
    g.add_pass("brute_force", pass, Bindings::new())?;
    let compiled = g.compile(&CompileOptions::for_gpu(&gpu))?;
    let buffers = [
        gpu.buffer_with_data("positions", scene.mesh.position_bytes(), BUFFER_USAGE),
        gpu.buffer_with_data("indices", scene.mesh.index_bytes(), BUFFER_USAGE),
    ];
    let texture = |label, format, [width, height]: [u32; 2]| {
        texture(
            &gpu,
            label,
            &TextureDesc::d2(format, width, height),
            TEXTURE_USAGE,
        )
    };
    let depth_texture = texture("depth", DEPTH_FORMAT, [W, H]);
    let ids_texture = texture("ids", IDS_FORMAT, ids_size);
    let imports = gpu_scene
        .imports()
        .buffer("positions", &buffers[0])
        .buffer("indices", &buffers[1])
        .texture("depth", &depth_texture)
        .texture("ids", &ids_texture);
    let mut exec = Executor::new(gpu);
    run_per_view(&mut exec, &compiled, &imports, views, |exec| {
        Ok(Targets {
            depth: bytemuck::pod_collect_to_vec(&read_texture(
                &exec.gpu,
                &depth_texture,
                wgpu::TextureAspect::DepthOnly,
            )),
            ids: bytemuck::pod_collect_to_vec(&read_texture(
                &exec.gpu,
                &ids_texture,
                wgpu::TextureAspect::All,
            )),
        })
    })
}

fn pass_for(scene: &Scene) -> BruteForce {
    BruteForce {
        width: W,
        height: H,
        index_count: scene.mesh.index_count(),
        instance_count: scene.data.instances.len() as u32,
    }
}

fn reference(scene: &Scene, view: &View) -> cpu::Image {
    let image = cpu::draw(
        &scene.mesh.positions,
        &scene.mesh.indices,
        &scene.data.instances,
        view,
        W,
        H,
    );
    // The reference does not clip at the near plane, so the scene must not need it.
    assert_eq!(
        image.clipped_triangles, 0,
        "the test scene crosses the near plane"
    );
    image
}

/// Compares the GPU's targets with the reference.
///
/// Tolerance: the hardware snaps corners to its sub-pixel grid (8 bits on lavapipe)
/// before its edge functions, the reference tests exact f64 edges at pixel centres; a
/// pixel centre within that rounding of an edge can fall on either side. Where that
/// edge is a silhouette, the pixel changes owner (or becomes empty), so ids may differ
/// on up to 1% of the covered pixels and coverage counts by up to 1%. On pixels with
/// the same id the depth is the same surface's almost everywhere (within 1e-5: f32
/// interpolation against f64), except where a silhouette of an instance over itself
/// moved, so 99% of them must agree to 1e-5. Empty pixels must hold depth 0 exactly.
fn check(name: &str, got: &Targets, want: &cpu::Image, min_covered: usize) {
    let pixels = (W * H) as usize;
    assert_eq!(got.ids.len(), pixels);
    assert_eq!(got.depth.len(), pixels);
    let got_covered = got.ids.iter().filter(|&&id| id != EMPTY_ID).count();
    let want_covered = want.covered();
    let either = (0..pixels)
        .filter(|&i| got.ids[i] != EMPTY_ID || want.ids[i] != EMPTY_ID)
        .count();
    let same: Vec<usize> = (0..pixels)
        .filter(|&i| want.ids[i] != EMPTY_ID && got.ids[i] == want.ids[i])
        .collect();
    let depth_close = same
        .iter()
        .filter(|&&i| (got.depth[i] - want.depth[i]).abs() <= 1e-5)
        .count();
    let id_share = same.len() as f64 / either.max(1) as f64;
    let depth_share = depth_close as f64 / same.len().max(1) as f64;
    eprintln!(
        "{name}: {got_covered} covered (reference {want_covered}), ids identical on {:.3}% of {either}, depth within 1e-5 on {:.3}% of those",
        id_share * 100.0,
        depth_share * 100.0
    );
    assert!(
        want_covered >= min_covered,
        "{name}: only {want_covered} pixels covered"
    );
    assert!(
        got_covered.abs_diff(want_covered) as f64 <= 0.01 * want_covered as f64,
        "{name}: {got_covered} pixels covered, the reference covers {want_covered}"
    );
    assert!(
        id_share >= 0.99,
        "{name}: ids identical on only {:.3}%",
        id_share * 100.0
    );
    assert!(
        depth_share >= 0.99,
        "{name}: depth within 1e-5 on only {:.3}%",
        depth_share * 100.0
    );
    let instances = want.ids.iter().copied().max().unwrap_or(0);
    for i in 0..pixels {
        let (id, depth) = (got.ids[i], got.depth[i]);
        if id == EMPTY_ID {
            assert_eq!(depth, 0.0, "{name}: empty pixel {i} holds depth {depth}");
        } else {
            assert!(id <= instances, "{name}: pixel {i} holds id {id}");
            assert!(
                depth > 0.0 && depth <= 1.0,
                "{name}: pixel {i} depth {depth}"
            );
        }
    }
}

#[test]
fn the_draw_matches_the_reference_and_every_instance_shows() {
    let mut s = scene();
    let view = camera().view([W, H], 0, None);
    let pass = pass_for(&s);
    let got = run(&mut s, pass, &[view], [W, H]).unwrap();
    let want = reference(&s, &view);
    check("one frame", &got[0], &want, 1000);
    // Every instance owns pixels, and instances hide each other somewhere: drawing
    // them alone covers more than together.
    let shown: std::collections::BTreeSet<u32> = got[0].ids.iter().copied().collect();
    assert_eq!(
        shown,
        (0..=s.data.instances.len() as u32).collect(),
        "instances shown"
    );
    let alone: usize = (0..s.data.instances.len())
        .map(|i| {
            cpu::draw(
                &s.mesh.positions,
                &s.mesh.indices,
                &s.data.instances[i..=i],
                &view,
                W,
                H,
            )
            .covered()
        })
        .sum();
    assert!(
        alone > want.covered() + 100,
        "{alone} vs {}",
        want.covered()
    );
}

#[test]
fn each_frame_starts_from_cleared_targets() {
    let mut s = scene();
    let first = camera().view([W, H], 0, None);
    let second = other_camera().view([W, H], 1, None);
    let pass = pass_for(&s);
    let got = run(&mut s, pass, &[first, second], [W, H]).unwrap();
    let (a, b) = (reference(&s, &first), reference(&s, &second));
    // The two frames differ enough that keeping the first frame's targets would fail
    // the comparison: pixels the first covers and the second leaves empty, or nearer
    // depth the second frame's test would not overwrite.
    let stale = (0..(W * H) as usize)
        .filter(|&i| a.ids[i] != b.ids[i] && (b.ids[i] == EMPTY_ID || a.depth[i] > b.depth[i]))
        .count();
    eprintln!("{stale} pixels would be stale");
    assert!(stale > 1000, "{stale}");
    check("first frame", &got[0], &a, 1000);
    check("second frame", &got[1], &b, 300);
}

#[test]
fn fewer_instances_or_indices_draw_only_those() {
    let mut s = scene();
    let view = camera().view([W, H], 0, None);
    // The first two instances and the first half of the triangles.
    let half = s.mesh.triangle_count() / 2 * 3;
    let pass = BruteForce {
        instance_count: 2,
        index_count: half,
        ..pass_for(&s)
    };
    let got = run(&mut s, pass, &[view], [W, H]).unwrap();
    let want = cpu::draw(
        &s.mesh.positions,
        &s.mesh.indices[..half as usize],
        &s.data.instances[..2],
        &view,
        W,
        H,
    );
    check("two instances, half the triangles", &got[0], &want, 300);
    assert!(got[0].ids.iter().all(|&id| id <= 2));
}

fn record_error(result: Result<Vec<Targets>>) -> String {
    match result {
        Err(GraphError::Record { message, .. }) => message,
        Err(other) => panic!("not a record error: {other}"),
        Ok(_) => panic!("ran"),
    }
}

#[test]
fn a_viewport_or_target_other_than_the_params_is_a_record_error() {
    let mut s = scene();
    let wide = camera().view([W + 1, H], 0, None);
    let pass = pass_for(&s);
    let m = record_error(run(&mut s, pass, &[wide], [W, H]));
    assert!(
        m.contains("viewport") && m.contains(&format!("{W} × {H}")),
        "{m}"
    );

    let view = camera().view([W, H], 0, None);
    let m = record_error(run(&mut s, pass, &[view], [W, H + 1]));
    assert!(
        m.contains("`ids`") && m.contains(&format!("{W} × {}", H + 1)),
        "{m}"
    );
}
