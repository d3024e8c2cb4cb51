//! The virtual-geometry benchmark's lattice of bunnies (15³ by default, 2240×1260, as
//! `meshlight bench` draws it): `fill_clusters` flat and as a hierarchy walk, each alone
//! and followed by `cull_lod`, timed on whatever adapter runs it, with the counts that
//! explain the times (clusters listed, nodes tested, the cut).
//!
//! `cargo run --release -p meshlight-pass-fill-clusters --example walk_vs_flat [n]`

use glam::{Mat4, Vec3};
use meshlight_gpu_scene::gpu::elements;
use meshlight_gpu_scene::{Camera, GpuScene, Material, SceneData, data::Limits};
use meshlight_graph::*;
use meshlight_pass_cull_lod::CullLod;
use meshlight_pass_fill_clusters::{FillClusters, HierarchyFill};
use meshlight_scene::{BuildOptions, build_asset};
use std::time::Instant;

const FRAMES: u32 = 10;

fn main() -> std::result::Result<(), Box<dyn std::error::Error>> {
    let n: u32 = std::env::args()
        .nth(1)
        .map_or(Ok(15), |a| a.parse())
        .map_err(|e| format!("the lattice size: {e}"))?;
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../assets/meshes/stanford-bunny.obj"
    );
    let mesh = meshlight_scene::load::load_mesh(std::path::Path::new(path))?;
    let asset = build_asset(&mesh, &BuildOptions::default(), &mut |_| {})?.asset;
    let mut data = SceneData::new(Limits::default());
    let material = data.add_material(Material {
        base_color: [1.0; 3],
    });
    let bunny = data.add_mesh("bunny", &asset)?;
    let radius = data.meshes[0].bounding_sphere[3];
    let spacing = radius * 2.5;
    for i in 0..n * n * n {
        let cell = Vec3::new((i % n) as f32, (i / n % n) as f32, (i / (n * n)) as f32);
        data.add_instance(bunny, Mat4::from_translation(cell * spacing), material)?;
    }
    let centre = Vec3::splat((n as f32 - 1.0) * 0.5 * spacing);
    let extent = n as f32 * spacing;
    let camera = Camera::perspective(
        centre + Vec3::new(0.9, 0.6, 1.2).normalize() * extent * 1.3,
        centre,
        50f32.to_radians(),
        radius * 0.05,
    );
    let view = camera.view([2240, 1260], 0, None);
    let clusters = data.total_clusters().max(1);
    println!("{n}³ bunnies, {clusters} clusters in all, 2240x1260, {FRAMES} frames each");
    for (label, hierarchy, cull) in [
        ("flat fill", false, false),
        ("flat fill + cull", false, true),
        ("hierarchy fill", true, false),
        ("hierarchy fill + cull", true, true),
    ] {
        let gpu = GpuContext::with_available(wgpu::Features::all())?;
        let adapter = gpu.adapter.get_info().name;
        let scene = GpuScene::new(&gpu, &mut data);
        let mut g = GraphBuilder::new();
        let h = scene.import(&mut g);
        let list = g.create_buffer("clusters", BufferDesc::array(elements::CLUSTER, clusters));
        let count = g.create_buffer("cluster_count", BufferDesc::array(Element::U32, 2));
        let mut bindings = Bindings::new()
            .bind("clusters", list)
            .bind("cluster_count", count);
        let pass: Box<dyn Pass> = if hierarchy {
            let t = scene.import_hierarchy(&mut g);
            let counts = g.create_buffer("hierarchy_counts", BufferDesc::array(Element::U32, 4));
            bindings = bindings
                .bind("hierarchy_nodes", t.nodes)
                .bind("hierarchy_clusters", t.clusters)
                .bind("hierarchy_roots", t.roots)
                .bind("hierarchy_counts", counts);
            Box::new(HierarchyFill::default())
        } else {
            Box::new(FillClusters::default())
        };
        let out = g.add_boxed_pass("fill", pass, bindings)?;
        g.export(out.buffer("cluster_count")?);
        if hierarchy {
            g.export(out.buffer("hierarchy_counts")?);
        }
        if cull {
            let slots = g.create_buffer(
                "raster_clusters",
                BufferDesc::array(elements::CLUSTER, 1 << 20),
            );
            let counts = g.create_buffer("raster_counts", BufferDesc::array(Element::U32, 8));
            let hw_args = g.create_buffer("hw_args", BufferDesc::array(Element::DRAW_ARGS, 1));
            let culled = g.add_pass(
                "cull",
                CullLod::default(),
                Bindings::new()
                    .bind("clusters", out.buffer("clusters")?)
                    .bind("cluster_count", out.buffer("cluster_count")?)
                    .bind("meshlet_groups", h.groups)
                    .bind("raster_clusters", slots)
                    .bind("raster_counts", counts)
                    .bind("hw_args", hw_args),
            )?;
            g.export(culled.buffer("raster_counts")?);
        }
        let compiled = g.compile(&CompileOptions::for_gpu(&gpu))?;
        let mut exec = Executor::new(gpu);
        let frame = FrameData::new().with("view", bytemuck::bytes_of(&view));
        // One frame to create pipelines and buffers, then the timed ones.
        exec.execute_frame(&compiled, &scene.imports(), &frame)?;
        exec.finish()?;
        let (mut wall, mut gpu_us) = (0.0, 0.0);
        for _ in 0..FRAMES {
            let start = Instant::now();
            exec.execute_frame(&compiled, &scene.imports(), &frame)?;
            let stats = exec.finish()?;
            wall += start.elapsed().as_secs_f64() * 1e3;
            gpu_us += stats.and_then(|s| s.gpu_total_us).unwrap_or(f64::NAN);
        }
        let words =
            |exec: &mut Executor, name: &str| -> std::result::Result<Vec<u32>, GraphError> {
                Ok(bytemuck::pod_collect_to_vec(&exec.read_buffer(name)?))
            };
        let listed = words(&mut exec, "cluster_count")?[1];
        let nodes = if hierarchy {
            words(&mut exec, "hierarchy_counts")?[0]
        } else {
            0
        };
        let cut = if cull {
            format!(", cut {}", words(&mut exec, "raster_counts")?[2])
        } else {
            String::new()
        };
        println!(
            "{label:>22}: {:8.3} ms per frame (GPU {:8.3} ms) on {adapter}; {listed} clusters listed, {nodes} nodes tested{cut}",
            wall / FRAMES as f64,
            gpu_us / FRAMES as f64 / 1e3
        );
    }
    Ok(())
}
