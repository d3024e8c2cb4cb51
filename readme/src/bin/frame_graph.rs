//! The README's "The frame graph in one example": a graph of one shipped pass (a prefix
//! sum) around a caller's buffer, compiled without a device, dumped, run four frames with
//! new input each, and a value read back two frames later without waiting.
use meshlight::graph::*;
use meshlight::scan_fan::ScanFan;
use meshlight::{bytemuck, wgpu};

fn main() -> Result<()> {
    const N: u32 = 1 << 16;
    let mut g = GraphBuilder::new();
    // A caller-owned buffer, and transients the graph pools.
    let usage = wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST;
    let counts = g.import_buffer("counts", BufferDesc::array(Element::U32, N as u64), usage);
    let offsets = g.create_buffer("offsets", BufferDesc::array(Element::U32, N as u64));
    g.create_buffer("total", BufferDesc::array(Element::U32, 1));
    g.export(offsets);
    // Slots bound by handle here; `total` binds the resource of its own name.
    let scan = Bindings::new()
        .bind("input", counts)
        .bind("output", offsets);
    let written = g.add_pass("scan", ScanFan::new(N), scan)?;
    // The sum, copied to the CPU every frame and readable two frames later.
    g.readback("total", written.buffer("total")?, None, 2)?;

    let gpu = GpuContext::with_available(wgpu::Features::all())?;
    let compiled = g.compile(&CompileOptions::for_gpu(&gpu))?;
    println!("{}", dump::to_dot(&compiled.plan));
    let buffer = gpu.buffer_with_data("counts", &[0; 4 * N as usize], usage);
    let mut exec = Executor::new(gpu);
    for frame in 0..4u32 {
        let values = vec![frame + 1; N as usize];
        exec.queue()
            .write_buffer(&buffer, 0, bytemuck::cast_slice(&values));
        exec.execute(&compiled, &Imports::new().buffer("counts", &buffer))?;
        // Never waits: `None` until the frame's copy is back.
        while let Some(r) = exec.take_readback("total")? {
            let total: u32 = bytemuck::pod_read_unaligned(&r.bytes[..4]);
            println!("frame {}: total {total}", r.frame);
            assert_eq!(total, (r.frame as u32 + 1) * N);
        }
    }
    Ok(())
}
