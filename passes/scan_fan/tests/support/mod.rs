//! Runs one scan on the GPU and checks it against the CPU reference.
#![allow(dead_code)]

use meshlight_graph::*;
use meshlight_pass_scan_fan::{
    DecoupledLookback, ScanFan, ScanOptions, Subgroups, TileAccess, TwoStep, cpu_scan,
};

/// Written over `output` and `total` before every run, so an element the scan should have
/// written and did not shows up as a mismatch.
pub const POISON: u32 = 0xDEAD_BEEF;

pub const USAGE: wgpu::BufferUsages = wgpu::BufferUsages::STORAGE
    .union(wgpu::BufferUsages::COPY_SRC)
    .union(wgpu::BufferUsages::COPY_DST);

#[allow(unused_imports)] // not every test binary that includes this module runs a pass
pub use meshlight_testing::executor;

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Implementation {
    ScanFan,
    TwoStep,
    DecoupledLookback,
}

impl Implementation {
    pub const ALL: [Implementation; 3] = [
        Implementation::ScanFan,
        Implementation::TwoStep,
        Implementation::DecoupledLookback,
    ];
    pub fn pass(self, options: ScanOptions) -> Box<dyn Pass> {
        match self {
            Implementation::ScanFan => Box::new(ScanFan::with_options(options)),
            Implementation::TwoStep => Box::new(TwoStep::with_options(options)),
            Implementation::DecoupledLookback => Box::new(DecoupledLookback::with_options(options)),
        }
    }
}

/// One scan to run: `options.count` is the capacity; `gpu_count`, when set, is written to
/// the `count` slot and the dispatch is indirect.
#[derive(Clone, Copy, Debug)]
pub struct Case {
    pub implementation: Implementation,
    pub options: ScanOptions,
    pub gpu_count: Option<u32>,
}

impl Case {
    pub fn new(implementation: Implementation, count: u32) -> Self {
        Self {
            implementation,
            options: ScanOptions::new(count),
            gpu_count: None,
        }
    }
    pub fn inclusive(mut self, inclusive: bool) -> Self {
        self.options.inclusive = inclusive;
        self
    }
    pub fn subgroups(mut self, subgroups: Subgroups) -> Self {
        self.options.subgroups = subgroups;
        self
    }
    pub fn items(mut self, items_per_thread: u32) -> Self {
        self.options.items_per_thread = items_per_thread;
        self
    }
    pub fn access(mut self, tile_access: TileAccess) -> Self {
        self.options.tile_access = tile_access;
        self
    }
    pub fn gpu_count(mut self, count: u32) -> Self {
        self.gpu_count = Some(count);
        self
    }
    /// Elements the scan should cover.
    pub fn effective_count(&self) -> u32 {
        self.gpu_count
            .map_or(self.options.count, |c| c.min(self.options.count))
    }
}

/// What one GPU run produced.
pub struct Outcome {
    /// The whole output buffer (capacity elements).
    pub output: Vec<u32>,
    pub total: u32,
}

/// Runs `case` over `input` (at least capacity elements).
pub fn run(exec: &mut Executor, case: &Case, input: &[u32]) -> Outcome {
    let capacity = case.options.count as u64;
    assert!(input.len() as u64 >= capacity);
    let mut g = GraphBuilder::new();
    let input_h = g.import_buffer("input", BufferDesc::array(Element::U32, capacity), USAGE);
    let output_h = g.import_buffer("output", BufferDesc::array(Element::U32, capacity), USAGE);
    let total_h = g.import_buffer("total", BufferDesc::array(Element::U32, 1), USAGE);
    let mut bindings = Bindings::new()
        .bind("input", input_h)
        .bind("output", output_h)
        .bind("total", total_h);
    if case.gpu_count.is_some() {
        bindings = bindings.bind(
            "count",
            g.import_buffer("count", BufferDesc::array(Element::U32, 1), USAGE),
        );
    }
    g.add_boxed_pass("scan", case.implementation.pass(case.options), bindings)
        .expect("add the scan pass");
    let compiled = g
        .compile(&CompileOptions::for_gpu(&exec.gpu))
        .expect("compile");

    let gpu = &exec.gpu;
    let input_buf = gpu.buffer_with_data(
        "input",
        bytemuck::cast_slice(&input[..capacity as usize]),
        USAGE,
    );
    let output_buf = gpu.buffer_with_data(
        "output",
        bytemuck::cast_slice(&vec![POISON; capacity as usize]),
        USAGE,
    );
    let total_buf = gpu.buffer_with_data("total", bytemuck::bytes_of(&POISON), USAGE);
    let count_buf = gpu.buffer_with_data(
        "count",
        bytemuck::bytes_of(&case.gpu_count.unwrap_or(0)),
        USAGE,
    );
    let imports = Imports::new()
        .buffer("input", &input_buf)
        .buffer("output", &output_buf)
        .buffer("total", &total_buf)
        .buffer("count", &count_buf);
    exec.execute(&compiled, &imports)
        .unwrap_or_else(|e| panic!("{case:?}: {e}"));
    let output = read_u32s(&exec.gpu, &output_buf, capacity as usize);
    let total = read_u32s(&exec.gpu, &total_buf, 1)[0];
    Outcome { output, total }
}

pub fn read_u32s(gpu: &GpuContext, buffer: &wgpu::Buffer, count: usize) -> Vec<u32> {
    let bytes = gpu
        .read_buffer(buffer, 0, count as u64 * 4)
        .expect("readback");
    bytemuck::pod_collect_to_vec(&bytes)
}

/// Runs `case` and asserts it equals the CPU reference on the counted elements, leaves
/// the rest of the output poisoned, and writes the total.
pub fn check(exec: &mut Executor, case: &Case, input: &[u32]) {
    let n = case.effective_count() as usize;
    let got = run(exec, case, input);
    let (expected, total) = cpu_scan(&input[..n], case.options.inclusive);
    if let Some(i) = (0..n).find(|&i| got.output[i] != expected[i]) {
        panic!(
            "{case:?}: first mismatch at element {i} of {n}: GPU {:#x}, CPU {:#x}{}",
            got.output[i],
            expected[i],
            if got.output[i] == POISON {
                " (never written)"
            } else {
                ""
            }
        );
    }
    if let Some(i) = (n..got.output.len()).find(|&i| got.output[i] != POISON) {
        panic!(
            "{case:?}: element {i}, past the count {n}, was written: {:#x}",
            got.output[i]
        );
    }
    assert_eq!(got.total, total, "{case:?}: total");
}

/// A tiny deterministic generator, so failures reproduce from the seed.
pub struct XorShift(pub u64);

impl XorShift {
    pub fn next_u32(&mut self) -> u32 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        (self.0 >> 32) as u32
    }
    /// Uniform in `0..bound`.
    pub fn below(&mut self, bound: u32) -> u32 {
        ((self.next_u32() as u64 * bound as u64) >> 32) as u32
    }
    /// `n` values below `bound`.
    pub fn values(&mut self, n: usize, bound: u32) -> Vec<u32> {
        (0..n).map(|_| self.below(bound)).collect()
    }
    /// `n` values within 16 of `u32::MAX`, so nearly every sum wraps.
    pub fn near_max(&mut self, n: usize) -> Vec<u32> {
        (0..n).map(|_| u32::MAX - self.below(16)).collect()
    }
}
