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
    /// The capacity: elements to scan, or the most a GPU count may say.
    pub fn count(mut self, count: u32) -> Self {
        self.options.count = count;
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

/// Every combination of the options listed: the tables the tests walk instead of nested
/// loops. Unlisted options keep [`Case::new`]'s defaults; both modes by default.
#[derive(Clone, Debug)]
pub struct Matrix {
    implementations: Vec<Implementation>,
    items: Vec<u32>,
    inclusive: Vec<bool>,
    subgroups: Vec<Subgroups>,
    access: Vec<TileAccess>,
}

impl Matrix {
    pub fn new(implementations: &[Implementation]) -> Self {
        Self {
            implementations: implementations.to_vec(),
            items: vec![ScanOptions::DEFAULT_ITEMS_PER_THREAD],
            inclusive: vec![false, true],
            subgroups: vec![Subgroups::Auto],
            access: vec![TileAccess::Vector],
        }
    }
    pub fn items(mut self, items: &[u32]) -> Self {
        self.items = items.to_vec();
        self
    }
    pub fn subgroups(mut self, subgroups: &[Subgroups]) -> Self {
        self.subgroups = subgroups.to_vec();
        self
    }
    /// Subgroups where the device has them, and off.
    pub fn both_subgroups(self) -> Self {
        self.subgroups(&[Subgroups::Auto, Subgroups::Off])
    }
    pub fn access(mut self, access: &[TileAccess]) -> Self {
        self.access = access.to_vec();
        self
    }
    /// Calls `f` with every combination; the count is 0, for `f` to set.
    pub fn each(&self, mut f: impl FnMut(Case)) {
        for &implementation in &self.implementations {
            for &items in &self.items {
                for &inclusive in &self.inclusive {
                    for &subgroups in &self.subgroups {
                        for &access in &self.access {
                            f(Case::new(implementation, 0)
                                .items(items)
                                .inclusive(inclusive)
                                .subgroups(subgroups)
                                .access(access));
                        }
                    }
                }
            }
        }
    }
}

/// What one GPU run produced.
pub struct Outcome {
    /// The whole output buffer (capacity elements).
    pub output: Vec<u32>,
    pub total: u32,
}

/// `case`'s graph on `exec`'s GPU: the scan over imported `input`, `output` and `total`
/// (and `count` with a GPU count), each of the capacity.
pub fn graph(exec: &Executor, case: &Case) -> CompiledGraph {
    let capacity = case.options.count as u64;
    let mut g = GraphBuilder::new();
    let mut bindings = Bindings::new();
    for (name, elements) in [("input", capacity), ("output", capacity), ("total", 1)] {
        let desc = BufferDesc::array(Element::U32, elements);
        bindings = bindings.bind(name, g.import_buffer(name, desc, USAGE));
    }
    if case.gpu_count.is_some() {
        let desc = BufferDesc::array(Element::U32, 1);
        bindings = bindings.bind("count", g.import_buffer("count", desc, USAGE));
    }
    g.add_boxed_pass("scan", case.implementation.pass(case.options), bindings)
        .expect("add the scan pass");
    g.compile(&CompileOptions::for_gpu(&exec.gpu))
        .expect("compile")
}

/// Runs one frame of `compiled` (`case`'s [`graph`]) over `input` (at least capacity
/// elements), into an output and a total poisoned first.
pub fn frame(exec: &mut Executor, compiled: &CompiledGraph, case: &Case, input: &[u32]) -> Outcome {
    let capacity = case.options.count as usize;
    assert!(input.len() >= capacity);
    let gpu = &exec.gpu;
    let upload =
        |name: &str, words: &[u32]| gpu.buffer_with_data(name, bytemuck::cast_slice(words), USAGE);
    let input_buf = upload("input", &input[..capacity]);
    let output_buf = upload("output", &vec![POISON; capacity]);
    let total_buf = upload("total", &[POISON]);
    let count_buf = upload("count", &[case.gpu_count.unwrap_or(0)]);
    let imports = Imports::new()
        .buffer("input", &input_buf)
        .buffer("output", &output_buf)
        .buffer("total", &total_buf)
        .buffer("count", &count_buf);
    exec.execute(compiled, &imports)
        .unwrap_or_else(|e| panic!("{case:?}: {e}"));
    let output = read_u32s(&exec.gpu, &output_buf, capacity);
    let total = read_u32s(&exec.gpu, &total_buf, 1)[0];
    Outcome { output, total }
}

/// Runs `case` over `input` (at least capacity elements).
pub fn run(exec: &mut Executor, case: &Case, input: &[u32]) -> Outcome {
    let compiled = graph(exec, case);
    frame(exec, &compiled, case, input)
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
