//! The prefix-sum benchmark `meshlight bench` runs: every implementation against a compute
//! copy of the same bytes (the yardstick: 16-byte loads and stores, timed in the same
//! frame with the same per-pass timestamps), with `copy_buffer_to_buffer` as a second,
//! labelled column, and against the CPU prefix sum of the same data.
//!
//! The copy command is no yardstick: through wgpu on an H100/H200 it moves about a fifth of
//! what a compute kernel moves, so a ratio against it flatters every kernel.
//!
//! Absolute figures mean something only on a real GPU; on lavapipe the run checks that the
//! benchmark works, not how fast anything is.

use meshlight::graph::{
    Access, BindingLayout, Bindings, BufferDesc, CompileOptions, Element, Executor, GraphBuilder,
    GraphError, Implementation, Imports, Pass, ProgramDesc, RecordContext, Result, SetupContext,
    Slot, StageContract,
};
use meshlight::scan_fan::{
    DecoupledLookback, MAX_COUNT, ScanFan, ScanOptions, Subgroups, TileAccess, TwoStep,
    cpu_scan_into,
};
use meshlight::shaders::{PassShader, pass_shader};
use serde::Serialize;
use std::time::Instant;

/// The sizes measured: 4,096 and 65,536 (light clustering's counts, where latency rules),
/// then 2^20 … 2^28 elements (bandwidth).
pub const SIZES: [u64; 7] = [
    1 << 12,
    1 << 16,
    1 << 20,
    1 << 22,
    1 << 24,
    1 << 26,
    1 << 28,
];

/// Bytes each element costs a scan at the least: read once, written once.
const BYTES_PER_ELEMENT: f64 = 8.0;

/// One implementation at one size.
#[derive(Clone, Debug, Serialize)]
pub struct Row {
    pub implementation: String,
    pub elements: u64,
    /// Median over the repeats of the pass's GPU time (its timestamp pair).
    pub gpu_ms: f64,
    pub elements_per_s: f64,
    /// `elements × 8 bytes / gpu time`: the bandwidth of one read and one write per element.
    pub gb_per_s: f64,
    /// Bandwidth of a compute copy of the same `elements × 4` bytes (counting the read and
    /// the write), median over the same frames: the yardstick.
    pub copy_gb_per_s: f64,
    /// Bandwidth of `copy_buffer_to_buffer` of the same bytes, for comparison only.
    pub copy_command_gb_per_s: f64,
    /// Median GPU time of the compute copy, for latency at small sizes.
    pub copy_ms: f64,
    /// Median time of the single-threaded CPU prefix sum of the same data.
    pub cpu_ms: f64,
    /// `gb_per_s / copy_gb_per_s` (the compute copy); the goals at 2^26 elements are ≥ 0.6
    /// for `scan_fan` and ≥ 0.8 for a single-pass scan.
    pub ratio_to_copy: f64,
}

/// The implementations measured, by the name in the table: the three with their defaults
/// (vector tiles), then the variants that show what each choice buys.
fn variants(count: u32) -> Vec<(&'static str, Box<dyn Pass>)> {
    let with = |tile_access: TileAccess, items_per_thread: u32| ScanOptions {
        tile_access,
        items_per_thread,
        ..ScanOptions::new(count)
    };
    let lookback = |options: ScanOptions| -> Box<dyn Pass> {
        Box::new(DecoupledLookback::with_options(options))
    };
    use TileAccess::{Staged, Vector};
    vec![
        ("scan_fan", Box::new(ScanFan::new(count))),
        ("two_step", Box::new(TwoStep::new(count))),
        (
            "decoupled_lookback",
            Box::new(DecoupledLookback::new(count)),
        ),
        // The default before vector tiles: scalar loads staged through workgroup memory.
        (
            "scan_fan/staged",
            Box::new(ScanFan::with_options(with(Staged, 8))),
        ),
        (
            "scan_fan/vector4",
            Box::new(ScanFan::with_options(with(Vector, 4))),
        ),
        (
            "scan_fan/vector16",
            Box::new(ScanFan::with_options(with(Vector, 16))),
        ),
        ("decoupled_lookback/staged", lookback(with(Staged, 8))),
        ("decoupled_lookback/vector8", lookback(with(Vector, 8))),
        ("decoupled_lookback/vector16", lookback(with(Vector, 16))),
        // No subgroups: the shared-memory row scans and the one-lane look-back.
        (
            "decoupled_lookback/serial",
            lookback(ScanOptions {
                subgroups: Subgroups::Off,
                ..with(Vector, 32)
            }),
        ),
    ]
}

const COPY_SHADER: PassShader = pass_shader!("scan_fan::copy", "copy.wgsl");

/// Workgroups of the compute copy: as many as one dimension of a dispatch allows, each
/// thread looping over the rest, which keeps every SM busy at every size measured.
const COPY_GROUPS: u32 = 65_535;
const COPY_WORKGROUP: u32 = 256;

/// Stage `copy`: `src` to `dst`, read and written through `src` and `dst` access.
fn copy_contract(src: Access, dst: Access) -> StageContract {
    StageContract {
        stage: "copy",
        slots: vec![
            Slot::buffer("src", src, Element::U32, "bytes to copy"),
            Slot::buffer("dst", dst, Element::U32, "where they go"),
        ],
    }
}

/// Stage `copy`, implementation `compute`: the bandwidth yardstick.
struct ComputeCopy {
    count: u32,
}

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct CopyParams {
    words4: u32,
    count: u32,
    threads: u32,
    _pad: u32,
}

impl ComputeCopy {
    fn groups(&self) -> u32 {
        (self.count / 4)
            .div_ceil(COPY_WORKGROUP)
            .clamp(1, COPY_GROUPS)
    }
    fn params(&self) -> CopyParams {
        CopyParams {
            words4: self.count / 4,
            count: self.count,
            threads: self.groups() * COPY_WORKGROUP,
            _pad: 0,
        }
    }
}

impl Pass for ComputeCopy {
    fn implementation(&self) -> Implementation {
        Implementation::new(
            "compute",
            copy_contract(Access::StorageRead, Access::StorageWrite),
        )
    }
    fn setup(&self, ctx: &mut SetupContext) -> Result<()> {
        // Named: the shader reads the same two slots as 16-byte and 4-byte words.
        let wide = BindingLayout::compute("copy4")
            .slot(0, "src")
            .slot(1, "dst")
            .uniform(2, "params");
        let tail = BindingLayout::compute("copy_tail")
            .uniform(2, "params")
            .slot(3, "src")
            .slot(4, "dst");
        ctx.program(
            "copy4",
            ProgramDesc::compute(&COPY_SHADER, "copy4").layout(wide),
        );
        ctx.program(
            "tail",
            ProgramDesc::compute(&COPY_SHADER, "copy_tail").layout(tail),
        );
        ctx.dispatch("copy4", [self.groups(), 1, 1]);
        Ok(())
    }
    fn record(&self, ctx: &mut RecordContext<'_>) -> Result<()> {
        let params = self.params();
        let wide = ctx.compute("copy4")?;
        let tail = ctx.compute("tail")?;
        let wide_bg = ctx.bind_group(&wide, 0, &[("params", bytemuck::bytes_of(&params))])?;
        let tail_bg = ctx.bind_group(&tail, 0, &[("params", bytemuck::bytes_of(&params))])?;
        let mut pass = ctx.compute_pass();
        pass.set_pipeline(&wide.pipeline);
        pass.set_bind_group(0, &wide_bg, &[]);
        pass.dispatch_workgroups(self.groups(), 1, 1);
        if !self.count.is_multiple_of(4) {
            pass.set_pipeline(&tail.pipeline);
            pass.set_bind_group(0, &tail_bg, &[]);
            pass.dispatch_workgroups(1, 1, 1);
        }
        Ok(())
    }
}

/// Stage `copy`, implementation `copy_buffer_to_buffer`: the copy command, for comparison.
struct CopyCommand;

impl Pass for CopyCommand {
    fn implementation(&self) -> Implementation {
        Implementation::new(
            "copy_buffer_to_buffer",
            copy_contract(Access::CopySrc, Access::CopyDst),
        )
    }
    fn setup(&self, _: &mut SetupContext) -> Result<()> {
        Ok(())
    }
    fn record(&self, ctx: &mut RecordContext<'_>) -> Result<()> {
        let (src, bytes) = ctx.buffer("src")?;
        let (dst, _) = ctx.buffer("dst")?;
        ctx.encoder().copy_buffer_to_buffer(src, 0, dst, 0, bytes);
        Ok(())
    }
}

fn median(values: &mut [f64]) -> f64 {
    values.sort_by(f64::total_cmp);
    values[values.len() / 2]
}

/// Small counts (so nothing wraps and a bug cannot hide behind wrap-around), reproducible.
fn data(n: usize) -> Vec<u32> {
    let mut state = 0x9e37_79b9_7f4a_7c15u64;
    (0..n)
        .map(|_| {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 59) as u32
        })
        .collect()
}

const USAGE: wgpu::BufferUsages = wgpu::BufferUsages::STORAGE
    .union(wgpu::BufferUsages::COPY_SRC)
    .union(wgpu::BufferUsages::COPY_DST);

/// Runs every implementation and the copy at each size, `repeats` timed frames after one
/// warm-up frame, and checks each implementation's total against the CPU's.
///
/// Needs `TIMESTAMP_QUERY` on the device. Memory: the input, one output per
/// implementation and the copy target, each `4 × size` bytes (6 GiB at 2^28).
pub fn run(exec: &mut Executor, sizes: &[u64], repeats: u32) -> Result<Vec<Row>> {
    if !exec.gpu.features.contains(wgpu::Features::TIMESTAMP_QUERY) {
        return Err(GraphError::Device("the benchmark needs TIMESTAMP_QUERY; open the device with it (GpuContext::with_available)".into()));
    }
    // Per-pass stamps, each pass in a compute pass of its own: every implementation is
    // timed alone, as it would run by itself.
    exec.gpu_timing = true;
    exec.timing = meshlight::graph::TimingMode::Passes;
    exec.stamp_inside_passes = false;
    let mut rows = Vec::new();
    for &size in sizes {
        if size == 0 || size > MAX_COUNT as u64 {
            return Err(GraphError::Parameter {
                pass: "bench".into(),
                message: format!("size {size} must be in 1..={MAX_COUNT}"),
            });
        }
        rows.extend(measure(exec, size, repeats.max(1))?);
    }
    Ok(rows)
}

/// The median time of the CPU prefix sum of `input` over at most five runs, and its total.
fn time_cpu(input: &[u32], repeats: u32) -> (f64, u32) {
    let mut out = vec![0u32; input.len()];
    let mut cpu_ms = Vec::new();
    let mut cpu_total = 0;
    for _ in 0..repeats.min(5) {
        let t = Instant::now();
        cpu_total = cpu_scan_into(input, &mut out, false);
        cpu_ms.push(t.elapsed().as_secs_f64() * 1e3);
        std::hint::black_box(&out);
    }
    (median(&mut cpu_ms), cpu_total)
}

/// The graph of one size: both copies and every implementation, all reading `input`;
/// implementation `name` writes `{name}.output` and `{name}.total`.
fn graph(count: u32) -> Result<GraphBuilder> {
    let desc = BufferDesc::array(Element::U32, u64::from(count));
    let mut g = GraphBuilder::new();
    let input = g.import_buffer("input", desc.clone(), USAGE);
    let copy = g.import_buffer("copy", desc.clone(), USAGE);
    let command = g.import_buffer("copy_command", desc.clone(), USAGE);
    g.add_pass(
        "copy",
        ComputeCopy { count },
        Bindings::new().bind("src", input).bind("dst", copy),
    )?;
    g.add_pass(
        "copy_command",
        CopyCommand,
        Bindings::new().bind("src", input).bind("dst", command),
    )?;
    for (name, pass) in variants(count) {
        let output = g.import_buffer(&format!("{name}.output"), desc.clone(), USAGE);
        let total = BufferDesc::array(Element::U32, 1);
        let total = g.import_buffer(&format!("{name}.total"), total, USAGE);
        let bindings = Bindings::new()
            .bind("input", input)
            .bind("output", output)
            .bind("total", total);
        g.add_boxed_pass(name, pass, bindings)?;
    }
    Ok(g)
}

/// Per pass, its GPU times in ms over the last `repeats` frames: slot 0 the compute copy,
/// 1 the copy command, then the implementations in `names` order.
fn pass_times(
    frames: &[meshlight::graph::GpuTimings],
    names: &[&str],
    repeats: u32,
) -> Vec<Vec<f64>> {
    let mut times: Vec<Vec<f64>> = vec![Vec::new(); names.len() + 2];
    for frame in frames.iter().rev().take(repeats as usize) {
        for (name, us) in &frame.passes {
            let slot = match name.as_str() {
                "copy" => 0,
                "copy_command" => 1,
                name => {
                    2 + names
                        .iter()
                        .position(|n| *n == name)
                        .expect("a benchmarked pass")
                }
            };
            times[slot].push(us / 1e3);
        }
    }
    times
}

/// One size: the CPU's time, then every implementation's and the copies' over `repeats`
/// frames, their totals checked.
fn measure(exec: &mut Executor, size: u64, repeats: u32) -> Result<Vec<Row>> {
    let count = size as u32;
    let input = data(size as usize);
    let (cpu_ms, cpu_total) = time_cpu(&input, repeats);
    let names: Vec<&'static str> = variants(count).iter().map(|(name, _)| *name).collect();
    let compiled = graph(count)?.compile(&CompileOptions::for_gpu(&exec.gpu))?;

    let gpu = &exec.gpu;
    let input_buf = gpu.buffer_with_data("bench input", bytemuck::cast_slice(&input), USAGE);
    drop(input);
    let make = |label: &str, bytes: u64| {
        gpu.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some(label),
            size: bytes,
            usage: USAGE,
            mapped_at_creation: false,
        })
    };
    let copy_buf = make("bench copy", size * 4);
    let command_buf = make("bench copy command", size * 4);
    let outputs: Vec<wgpu::Buffer> = names.iter().map(|n| make(n, size * 4)).collect();
    let totals: Vec<wgpu::Buffer> = names.iter().map(|n| make(n, 4)).collect();
    let mut imports = Imports::new()
        .buffer("input", &input_buf)
        .buffer("copy", &copy_buf)
        .buffer("copy_command", &command_buf);
    for ((name, output), total) in names.iter().zip(&outputs).zip(&totals) {
        imports = imports
            .buffer(&format!("{name}.output"), output)
            .buffer(&format!("{name}.total"), total);
    }

    // A warm-up frame, then each frame waited for, so no timing is dropped however slow
    // the GPU is.
    exec.execute(&compiled, &imports)?;
    exec.finish()?;
    exec.take_gpu_timings()?;
    for _ in 0..repeats {
        exec.execute(&compiled, &imports)?;
        exec.finish()?;
    }
    let frames = exec.take_gpu_timings()?;
    if frames.len() < repeats as usize {
        return Err(GraphError::Device(format!(
            "GPU timings came back for {} of {repeats} frames",
            frames.len()
        )));
    }
    let mut times = pass_times(&frames, &names, repeats);

    for (name, total) in names.iter().zip(&totals) {
        let got: Vec<u32> = bytemuck::pod_collect_to_vec(&exec.gpu.read_buffer(total, 0, 4)?);
        if got[0] != cpu_total {
            return Err(GraphError::Record {
                pass: name.to_string(),
                message: format!(
                    "total {} at {size} elements, the CPU says {cpu_total}",
                    got[0]
                ),
            });
        }
    }

    // The yardstick must copy for real: its first and last words against the input's.
    let last = (size - 1) * 4;
    for at in [0, last] {
        let want = exec.gpu.read_buffer(&input_buf, at, 4)?;
        let got = exec.gpu.read_buffer(&copy_buf, at, 4)?;
        if got != want {
            return Err(GraphError::Record {
                pass: "copy".into(),
                message: format!("the compute copy differs from its input at byte {at}"),
            });
        }
    }

    let gb_per_s_of = |ms: f64| size as f64 * BYTES_PER_ELEMENT / (ms * 1e-3) / 1e9;
    let copy_ms = median(&mut times[0]);
    let copy_gb_per_s = gb_per_s_of(copy_ms);
    let copy_command_gb_per_s = gb_per_s_of(median(&mut times[1]));
    let rows = names.iter().zip(&mut times[2..]).map(|(name, times)| {
        let gpu_ms = median(times);
        let gb_per_s = gb_per_s_of(gpu_ms);
        Row {
            implementation: name.to_string(),
            elements: size,
            gpu_ms,
            elements_per_s: size as f64 / (gpu_ms * 1e-3),
            gb_per_s,
            copy_gb_per_s,
            copy_command_gb_per_s,
            copy_ms,
            cpu_ms,
            ratio_to_copy: gb_per_s / copy_gb_per_s,
        }
    });
    Ok(rows.collect())
}

/// The rows as a fixed-width text table.
pub fn table(rows: &[Row]) -> String {
    let mut s = format!(
        "{:<26} {:>11} {:>10} {:>12} {:>9} {:>10} {:>10} {:>9} {:>8}\n",
        "implementation",
        "elements",
        "gpu ms",
        "Gelem/s",
        "GB/s",
        "copy GB/s",
        "cmd GB/s",
        "cpu ms",
        "÷ copy"
    );
    for r in rows {
        s += &format!(
            "{:<26} {:>11} {:>10.4} {:>12.2} {:>9.1} {:>10.1} {:>10.1} {:>9.2} {:>8.2}\n",
            r.implementation,
            r.elements,
            r.gpu_ms,
            r.elements_per_s / 1e9,
            r.gb_per_s,
            r.copy_gb_per_s,
            r.copy_command_gb_per_s,
            r.cpu_ms,
            r.ratio_to_copy
        );
    }
    s
}
