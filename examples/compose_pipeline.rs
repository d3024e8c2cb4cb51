//! Compose a pipeline from a file, run it on the GPU and read the result back.
//!
//!     cargo run --example compose_pipeline [pipelines/prefix_sum.toml]

use meshlight::graph::*;

fn main() -> Result<()> {
    let path = std::env::args()
        .nth(1)
        .unwrap_or_else(|| "pipelines/prefix_sum.toml".into());
    let builder = file::load_pipeline(std::path::Path::new(&path), &meshlight::registry())?;
    let adapter = GpuAdapter::select()?;
    let compiled = builder.compile(&CompileOptions::for_adapter(&adapter))?;
    let gpu = adapter.open(compiled.plan.enabled_features)?;

    let counts: Vec<u32> = (0..65_536u32).map(|i| i % 7).collect();
    let usage = wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC;
    let input = gpu.buffer_with_data("counts", bytemuck::cast_slice(&counts), usage);
    let mut exec = Executor::new(gpu);
    exec.execute(&compiled, &Imports::new().buffer("counts", &input))?;
    // Frames never wait for the GPU; `finish` does, and fills in the GPU timings.
    let stats = exec.finish()?.expect("one frame ran");

    let total: Vec<u32> = bytemuck::pod_collect_to_vec(&exec.read_buffer("total")?);
    let (_, expected) = meshlight::scan_fan::cpu_scan(&counts, false);
    println!(
        "total {} (CPU: {expected}) on {}",
        total[0], exec.gpu.info.name
    );
    // The default timing mode times each batch; MESHLIGHT_TIMING=passes times each pass.
    match stats.gpu_frame_us {
        Some(us) => println!("  frame: {us:.1} µs GPU"),
        None => println!("  no GPU timings (timing off, or no timestamps on this adapter)"),
    }
    for p in &stats.passes {
        if let Some(us) = p.gpu_us {
            println!("  {}: {us:.1} µs GPU", p.name);
        }
    }
    Ok(())
}
