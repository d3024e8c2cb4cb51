//! The virtual-geometry frame composed in Rust: a mesh baked into a meshlet LOD asset,
//! 400 copies placed, the six stages wired by hand, one frame rendered to a PNG.
//!
//! `cargo run --release -p meshlight-virtual-geometry --example virtual_geometry -- assets/meshes/spot.obj [OUT.png]`
//!
//! Without `OUT.png`, the image goes to `target/example-output/virtual_geometry.png`
//! (beside the build, out of the sources); the path written is printed.

use glam::{Mat4, Vec3};
use meshlight::gpu_scene::{Camera, GpuScene, Material, SceneData, gpu::elements::CLUSTER};
use meshlight::graph::*;
use meshlight::resolve::{COLOR_FORMAT, Resolve};
use meshlight::{cull_lod::CullLod, fill_clusters::FillClusters, hw_raster::HwRaster};
use meshlight::{remap_dispatch::RemapDispatch, sw_raster::SwRaster};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let mesh = args.next().unwrap_or("assets/meshes/spot.obj".into());
    let output = args
        .next()
        .map(std::path::PathBuf::from)
        .unwrap_or_else(|| {
            std::path::Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/../.."))
                .join("target/example-output/virtual_geometry.png")
        });
    let (width, height) = (1280, 720);

    // The scene: the mesh baked once, 20 × 20 copies on the ground.
    let mesh = meshlight::scene::load::load_mesh(mesh.as_ref())?;
    let asset = meshlight::scene::build_asset(&mesh, &Default::default(), &mut |_| {})?.asset;
    let mut data = SceneData::new(Default::default());
    let material = data.add_material(Material {
        base_color: [0.8, 0.5, 0.3],
        ..Material::default()
    })?;
    let id = data.add_mesh("mesh", &asset)?;
    let r = data.meshes[0].bounding_sphere[3];
    for i in 0..400 {
        let at = Vec3::new((i % 20) as f32, 0.0, (i / 20) as f32) * 2.5 * r;
        data.add_instance(id, Mat4::from_translation(at), material)?;
    }
    let (eye, target) = (
        Vec3::new(-r, 3.0 * r, -r),
        Vec3::new(25.0 * r, 0.0, 40.0 * r),
    );
    let camera = Camera::perspective(eye, target, 1.0, 0.01 * r);
    // The graph: the scene imported, the per-frame lists transient, the colour exported.
    let mut g = GraphBuilder::new();
    meshlight::gpu_scene::gpu::import_for(&data, &mut g);
    let pixels = width as u64 * height as u64;
    for (name, desc) in [
        (
            "clusters",
            BufferDesc::array(CLUSTER, data.total_clusters()),
        ),
        ("cluster_count", BufferDesc::array(Element::U32, 2)),
        ("raster_clusters", BufferDesc::array(CLUSTER, 1 << 18)),
        ("raster_counts", BufferDesc::array(Element::U32, 8)),
        ("hw_args", BufferDesc::array(Element::DRAW_ARGS, 1)),
        ("sw_args", BufferDesc::array(Element::DISPATCH_ARGS, 1)),
        ("visbuffer", BufferDesc::array(Element::U64, pixels)),
    ] {
        g.create_buffer(name, desc);
    }
    let color = g.create_texture("color", TextureDesc::d2(COLOR_FORMAT, width, height));
    g.export(color);
    // Slots left unbound bind to the resource of the same name.
    g.add_pass("fill", FillClusters::default(), Bindings::new())?;
    g.add_pass("cull", CullLod::default(), Bindings::new())?;
    let remap = RemapDispatch {
        count_word: 0,
        max_per_dimension: None,
    };
    let bind = Bindings::new()
        .bind_named("count", "raster_counts")
        .bind_named("args", "sw_args");
    g.add_pass("remap", remap, bind)?;
    let sw = SwRaster {
        width,
        height,
        target: meshlight::graph::Visibility64::Buffer,
        scanline_width: 16,
        exact_division: false,
        accumulate: false,
        big_triangle_px: meshlight::sw_raster::BIG_TRIANGLE_PX,
        small_triangle_px: meshlight::sw_raster::SMALL_TRIANGLE_PX,
        two_sided: false,
        alpha_mask: false,
        depth_only: false,
        layer: 0,
    };
    g.add_pass("sw_raster", sw, Bindings::new())?;
    g.add_pass(
        "hw_raster",
        HwRaster::indirect(width, height),
        Bindings::new(),
    )?;
    g.add_pass("resolve", Resolve::new(width, height), Bindings::new())?;
    // Compile for the adapter, open the device with the features the passes asked for.
    let adapter = GpuAdapter::select()?;
    let compiled = g.compile(&CompileOptions::for_adapter(&adapter))?;
    let gpu = adapter.open(compiled.plan.enabled_features)?;
    let scene = GpuScene::new(&gpu, &mut data);
    let mut exec = Executor::new(gpu);
    let view = camera.view([width, height], 0, None);
    let frame = FrameData::new().with("view", bytemuck::bytes_of(&view));
    exec.execute_frame(&compiled, &scene.imports(), &frame)?;
    let rgba = exec.read_texture("color")?;

    meshlight_output::write_png(&output, width, height, &rgba)?;
    println!(
        "{} source triangles → {}",
        data.source_triangles(),
        output.display()
    );
    Ok(())
}
