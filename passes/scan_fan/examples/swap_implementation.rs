//! Swapping the prefix-sum implementation is a one-line change: both share the `scan_fan`
//! stage contract, so the graph around them stays as it is.
//!
//! Runs `scan_fan` and `two_step` over the same counts on the first Vulkan adapter and
//! checks they agree with each other and with the CPU.
//!
//! `cargo run -p meshlight-pass-scan-fan --example swap_implementation`

use meshlight_graph::*;
use meshlight_pass_scan_fan::{ScanFan, TwoStep, cpu_scan};

const COUNT: u32 = 1_000_000;
const USAGE: wgpu::BufferUsages = wgpu::BufferUsages::STORAGE.union(wgpu::BufferUsages::COPY_SRC);

/// Builds counts → scan → offsets around `scan`, runs it, and returns offsets and total.
fn prefix_sum(
    exec: &mut Executor,
    scan: impl Pass + 'static,
    counts: &[u32],
) -> Result<(Vec<u32>, u32)> {
    let mut g = GraphBuilder::new();
    g.import_buffer(
        "counts",
        BufferDesc::array(Element::U32, COUNT as u64),
        USAGE,
    );
    let offsets = g.create_buffer("offsets", BufferDesc::array(Element::U32, COUNT as u64));
    let total = g.create_buffer("total", BufferDesc::array(Element::U32, 1));
    g.export(offsets);
    g.export(total);
    g.add_pass(
        "scan",
        scan,
        Bindings::new()
            .bind_named("input", "counts")
            .bind("output", offsets),
    )?;
    let compiled = g.compile(&CompileOptions::for_gpu(&exec.gpu))?;
    let counts = exec
        .gpu
        .buffer_with_data("counts", bytemuck::cast_slice(counts), USAGE);
    exec.execute(&compiled, &Imports::new().buffer("counts", &counts))?;
    let stats = exec.finish()?.expect("one frame ran");
    if let Some(us) = stats.passes[0].gpu_us {
        println!("  {:<9} {:>9.1} µs on the GPU", stats.passes[0].name, us);
    }
    let offsets: Vec<u32> = bytemuck::pod_collect_to_vec(&exec.read_buffer("offsets")?);
    let total: Vec<u32> = bytemuck::pod_collect_to_vec(&exec.read_buffer("total")?);
    Ok((offsets, total[0]))
}

fn main() -> Result<()> {
    let mut exec = Executor::new(GpuContext::with_available(wgpu::Features::all())?);
    println!("adapter: {}", exec.gpu.info.name);
    let counts: Vec<u32> = (0..COUNT)
        .map(|i| (i.wrapping_mul(2_654_435_761) >> 28) & 7)
        .collect();

    println!("scan_fan:");
    let a = prefix_sum(&mut exec, ScanFan::new(COUNT), &counts)?;
    println!("two_step:");
    let b = prefix_sum(&mut exec, TwoStep::new(COUNT), &counts)?; // ← the one-line swap

    let cpu = cpu_scan(&counts, false);
    println!("total: scan_fan {}, two_step {}, CPU {}", a.1, b.1, cpu.1);
    if a == b && a == cpu {
        println!(
            "both implementations agree with each other and with the CPU on all {COUNT} offsets"
        );
        Ok(())
    } else {
        let i = (0..COUNT as usize)
            .find(|&i| a.0[i] != b.0[i] || a.0[i] != cpu.0[i])
            .unwrap_or(0);
        Err(GraphError::Readback(format!(
            "implementations disagree at element {i}: scan_fan {}, two_step {}, CPU {}",
            a.0[i], b.0[i], cpu.0[i]
        )))
    }
}
