//! The demo compute rasteriser against its CPU reference, and the shaded image.

use meshlight::demo;

/// A small closed mesh: the procedural knot at low resolution.
fn mesh() -> meshlight::scene::Mesh {
    meshlight::scene::procedural_mesh(12)
}

#[test]
fn gpu_visibility_matches_the_cpu_reference() {
    let m = mesh();
    let (w, h) = (160, 120);
    let view_proj = demo::camera_for(&m.positions, w, h);
    let cpu = demo::cpu::rasterise(&m.positions, &m.indices, view_proj, w, h);

    // Run only the raster pass and export the visibility buffer.
    let adapter = meshlight::graph::GpuAdapter::select().unwrap_or_else(|e| panic!("{e}"));
    let mut g = meshlight::graph::GraphBuilder::new();
    let padded: Vec<[f32; 4]> = m.positions.iter().map(|p| [p.x, p.y, p.z, 1.0]).collect();
    let usage = wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST;
    use meshlight::graph::*;
    g.import_buffer(
        "positions",
        BufferDesc::array(Element::VEC4_F32, padded.len() as u64),
        usage,
    );
    g.import_buffer(
        "indices",
        BufferDesc::array(Element::U32, m.indices.len() as u64),
        usage,
    );
    let vis = g.create_buffer("visbuffer", BufferDesc::array(Element::U64, (w * h) as u64));
    g.export(vis);
    let tris = (m.indices.len() / 3) as u32;
    g.add_pass(
        "raster",
        demo::DemoRaster {
            width: w,
            height: h,
            triangle_count: tris,
        },
        Bindings::new(),
    )
    .unwrap();
    let compiled = g.compile(&CompileOptions::for_adapter(&adapter)).unwrap();
    let gpu = adapter.open(compiled.plan.enabled_features).unwrap();
    let pos = gpu.buffer_with_data(
        "positions",
        bytemuck::cast_slice(&padded),
        wgpu::BufferUsages::STORAGE,
    );
    let idx = gpu.buffer_with_data(
        "indices",
        bytemuck::cast_slice(&m.indices),
        wgpu::BufferUsages::STORAGE,
    );
    let mut exec = Executor::new(gpu);
    exec.execute_frame(
        &compiled,
        &Imports::new()
            .buffer("positions", &pos)
            .buffer("indices", &idx),
        &demo::frame_data(view_proj),
    )
    .unwrap();
    let bytes = exec.read_buffer("visbuffer").unwrap();
    let gpu_vis: Vec<u64> = bytemuck::pod_collect_to_vec(&bytes);

    let covered = cpu.iter().filter(|&&v| v != 0).count();
    assert!(
        covered > (w * h / 10) as usize,
        "the camera should see the mesh: {covered} pixels"
    );
    // Same triangle everywhere except where float evaluation order differs on an edge.
    let same_triangle = cpu
        .iter()
        .zip(&gpu_vis)
        .filter(|(a, b)| (**a as u32) == (**b as u32))
        .count();
    let agreement = same_triangle as f64 / cpu.len() as f64;
    assert!(
        agreement > 0.995,
        "GPU and CPU visibility agree on only {:.3}% of pixels",
        agreement * 100.0
    );
}

#[test]
fn shaded_image_shows_the_mesh_over_the_background() {
    let m = mesh();
    let r = demo::render(&m.positions, &m.indices, 96, 64).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(r.rgba.len(), 96 * 64 * 4);
    let px = |x: usize, y: usize| &r.rgba[(y * 96 + x) * 4..(y * 96 + x) * 4 + 4];
    // Corners show the background gradient, the centre region shows lit, warm-coloured mesh.
    assert!(px(0, 0)[2] > px(0, 0)[0], "background is blue-grey");
    let warm = (0..64)
        .flat_map(|y| (0..96).map(move |x| (x, y)))
        .filter(|&(x, y)| px(x, y)[0] > px(x, y)[2] + 30)
        .count();
    assert!(
        warm > 96 * 64 / 20,
        "the mesh covers the frame: {warm} warm pixels"
    );
    assert!(r.rgba.chunks(4).all(|p| p[3] == 255));
}

#[test]
fn gpu_shading_matches_the_cpu_reference() {
    use meshlight::graph::*;
    let m = mesh();
    let (w, h) = (96, 64);
    let view_proj = demo::camera_for(&m.positions, w, h);
    let tris = (m.indices.len() / 3) as u32;
    let mut g = demo::graph(m.positions.len() as u64 * 16, tris, w, h).unwrap();
    // Keep the visibility buffer, so the CPU shades exactly what the GPU saw.
    let vis = g.resource("visbuffer").unwrap();
    g.export(vis);
    let adapter = GpuAdapter::select().unwrap_or_else(|e| panic!("{e}"));
    let compiled = g.compile(&CompileOptions::for_adapter(&adapter)).unwrap();
    let gpu = adapter.open(compiled.plan.enabled_features).unwrap();
    let padded: Vec<[f32; 4]> = m.positions.iter().map(|p| [p.x, p.y, p.z, 1.0]).collect();
    let pos = gpu.buffer_with_data(
        "positions",
        bytemuck::cast_slice(&padded),
        wgpu::BufferUsages::STORAGE,
    );
    let idx = gpu.buffer_with_data(
        "indices",
        bytemuck::cast_slice(&m.indices),
        wgpu::BufferUsages::STORAGE,
    );
    let image = gpu.buffer_with_data(
        "image",
        &vec![0u8; (w * h * 4) as usize],
        wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
    );
    let mut exec = Executor::new(gpu);
    exec.execute_frame(
        &compiled,
        &Imports::new()
            .buffer("positions", &pos)
            .buffer("indices", &idx)
            .buffer("image", &image),
        &demo::frame_data(view_proj),
    )
    .unwrap();
    let vis: Vec<u64> = bytemuck::pod_collect_to_vec(&exec.read_buffer("visbuffer").unwrap());
    let gpu_rgba: Vec<u32> =
        bytemuck::pod_collect_to_vec(&exec.gpu.read_buffer(&image, 0, (w * h * 4) as u64).unwrap());
    let cpu_rgba = demo::cpu::shade(&vis, &m.positions, &m.indices, w, h, demo::LIGHT_DIR);
    let channel = |p: u32, c: u32| ((p >> (8 * c)) & 255) as i32;
    let worst = gpu_rgba
        .iter()
        .zip(&cpu_rgba)
        .map(|(&a, &b)| {
            (0..4)
                .map(|c| (channel(a, c) - channel(b, c)).abs())
                .max()
                .unwrap()
        })
        .max()
        .unwrap();
    assert!(
        worst <= 2,
        "GPU and CPU shading differ by up to {worst} levels in a channel"
    );
    assert!(vis.iter().any(|&v| v != 0));
}
