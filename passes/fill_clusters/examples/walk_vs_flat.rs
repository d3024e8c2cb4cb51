//! The virtual-geometry benchmark's lattice of bunnies (15³ by default, 2240×1260, as
//! `meshlight bench` draws it): `fill_clusters` flat and as a hierarchy walk, each alone
//! and followed by `cull_lod`, timed on whatever adapter runs it, with the counts that
//! explain the times (clusters listed, nodes tested, the cut).
//!
//! `cargo run --release -p meshlight-pass-fill-clusters --example walk_vs_flat [n]`

#[path = "../tests/support/graph.rs"]
mod graph;
#[path = "../tests/support/lattice.rs"]
mod lattice;

use meshlight_gpu_scene::GpuScene;
use meshlight_gpu_scene::gpu::elements;
use meshlight_graph::*;
use meshlight_pass_cull_lod::CullLod;
use meshlight_pass_fill_clusters::{FillClusters, HierarchyFill};
use meshlight_testing::{gpu, meshes::bunny};
use std::time::Instant;

const FRAMES: u32 = 10;

fn main() -> std::result::Result<(), Box<dyn std::error::Error>> {
    let n: u32 = std::env::args()
        .nth(1)
        .map_or(Ok(15), |a| a.parse())
        .map_err(|e| format!("the lattice size: {e}"))?;
    let (mut data, view) = lattice::lattice(bunny(), n);
    let clusters = data.total_clusters().max(1);
    let [width, height] = lattice::VIEWPORT;
    println!("{n}³ bunnies, {clusters} clusters in all, {width}x{height}, {FRAMES} frames each");
    for (label, hierarchy, cull) in [
        ("flat fill", false, false),
        ("flat fill + cull", false, true),
        ("hierarchy fill", true, false),
        ("hierarchy fill + cull", true, true),
    ] {
        let gpu = gpu();
        let adapter = gpu.adapter.get_info().name;
        let scene = GpuScene::new(&gpu, &mut data);
        let mut g = GraphBuilder::new();
        g.create_buffer("clusters", BufferDesc::array(elements::CLUSTER, clusters));
        let pass: Box<dyn Pass> = if hierarchy {
            Box::new(HierarchyFill::default())
        } else {
            Box::new(FillClusters::default())
        };
        graph::add_fill(&mut g, &scene, pass)?;
        if cull {
            graph::add_cull(&mut g, CullLod::default(), 1 << 20)?;
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
