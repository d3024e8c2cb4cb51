//! Small passes for graph tests: `fill` writes `i * k`, `add` writes `input[i] + k`.
#![allow(dead_code)]

use meshlight_graph::*;

pub mod fake;
pub mod rects;

/// The text of `graph/tests/support/<file>`, embedded.
#[allow(unused_macros)] // not every test binary reads a shader of its own
macro_rules! support_text {
    ($file:literal) => {
        include_str!(concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/tests/support/",
            $file
        ))
    };
}

/// A pass shader read from `graph/tests/support/<file>`, with the `modules` it imports.
#[allow(unused_macros)] // not every test binary reads a shader of its own
macro_rules! support_shader {
    ($name:literal, $file:literal) => {
        $crate::support::support_shader!($name, $file, modules: [])
    };
    ($name:literal, $file:literal, modules: [$($module:expr),* $(,)?]) => {
        PassShader {
            name: $name,
            source: $crate::support::support_text!($file),
            file_path: concat!("graph/tests/support/", $file),
            modules: &[$($module),*],
        }
    };
}
#[allow(unused_imports)] // not every test binary reads a shader of its own
pub(crate) use {support_shader, support_text};

pub const SHADER: PassShader = support_shader!("test::arith", "arith.wgsl");

fn u32s(name: &'static str, access: Access, doc: &'static str) -> Slot {
    Slot::buffer(name, access, Element::U32, doc)
}

/// One dispatch of the arithmetic kernel `entry` over `count` words: `fill` (stage
/// `produce`) writes `i * k`, `add` (stage `transform`) writes `input[i] + k`. The two
/// differ only in their contract and layout, so one pass type serves both.
pub struct Arith {
    entry: &'static str,
    contract: fn() -> StageContract,
    layout: fn() -> BindingLayout,
    count: u32,
    k: u32,
}

impl Arith {
    /// Stage `produce`: writes `output`.
    pub fn fill(count: u32, k: u32) -> Self {
        Self::new("fill", produce_contract, layout_out_only, count, k)
    }
    /// Stage `transform`: reads `input`, writes `output`. `AddTwice` implements it too.
    pub fn add(count: u32, k: u32) -> Self {
        Self::new("add", transform_contract, layout_in_out, count, k)
    }
    fn new(
        entry: &'static str,
        contract: fn() -> StageContract,
        layout: fn() -> BindingLayout,
        count: u32,
        k: u32,
    ) -> Self {
        Self {
            entry,
            contract,
            layout,
            count,
            k,
        }
    }
}

/// A second implementation of `transform` giving the same result as `Arith::add(count, k)`
/// for k = 2·half.
pub struct AddTwice {
    pub count: u32,
    pub half: u32,
}

pub fn produce_contract() -> StageContract {
    StageContract {
        stage: "produce",
        slots: vec![u32s("output", Access::StorageWrite, "values written")],
    }
}
pub fn transform_contract() -> StageContract {
    StageContract {
        stage: "transform",
        slots: vec![
            u32s("input", Access::StorageRead, "values read"),
            u32s("output", Access::StorageWrite, "values written"),
        ],
    }
}

fn layout_out_only() -> BindingLayout {
    // `fill` reads no input, but the shader declares it; bind the output twice would alias,
    // so `fill` uses a layout without binding 0.
    BindingLayout::compute("fill")
        .slot(1, "output")
        .uniform(2, "params")
}
fn layout_in_out() -> BindingLayout {
    BindingLayout::compute("add")
        .slot(0, "input")
        .slot(1, "output")
        .uniform(2, "params")
}

fn program(entry: &'static str, layout: BindingLayout) -> ProgramDesc {
    ProgramDesc::compute(&SHADER, entry).layout(layout)
}

/// Declares the scratch buffer `words` of `count` u32s, read and written by the pass.
pub fn scratch_words(ctx: &mut SetupContext, count: u32) {
    ctx.scratch_buffer(
        "words",
        BufferDesc::array(Element::U32, count as u64),
        &[Access::StorageReadWrite],
    );
}

/// Records the compute program `name` with bind group 0 (built with `uniforms`) in the
/// pass's compute pass; `dispatch` issues the dispatches.
pub fn compute_once(
    ctx: &mut RecordContext<'_>,
    name: &str,
    uniforms: &[(&str, &[u8])],
    dispatch: impl FnOnce(&mut wgpu::ComputePass<'static>),
) -> Result<()> {
    let p = ctx.compute(name)?;
    let bg = ctx.bind_group(&p, 0, uniforms)?;
    let mut cp = ctx.compute_pass();
    cp.set_pipeline(&p.pipeline);
    cp.set_bind_group(0, &bg, &[]);
    dispatch(&mut cp);
    Ok(())
}

/// Records the compute program `name` once over `groups` (`RecordContext::dispatch_compute`
/// with a direct grid).
pub fn dispatch_once(
    ctx: &mut RecordContext<'_>,
    name: &str,
    uniforms: &[(&str, &[u8])],
    groups: [u32; 3],
) -> Result<()> {
    ctx.dispatch_compute(name, uniforms, Workgroups::Direct(groups))
}

/// Records the render program `name` with bind group 0 (built with `uniforms`) into one
/// render pass on `colors` and `depth`; `draw` issues the draws.
pub fn render_once(
    ctx: &mut RecordContext<'_>,
    name: &str,
    uniforms: &[(&str, &[u8])],
    colors: &[ColorAttachment],
    depth: Option<DepthAttachment>,
    draw: impl FnOnce(&mut wgpu::RenderPass<'_>),
) -> Result<()> {
    let p = ctx.render(name)?;
    let bg = ctx.bind_group(&p, 0, uniforms)?;
    let mut rp = ctx.render_pass(colors, depth)?;
    rp.set_pipeline(&p.pipeline);
    rp.set_bind_group(0, &bg, &[]);
    draw(&mut rp);
    Ok(())
}

fn dispatch(ctx: &mut RecordContext<'_>, name: &str, count: u32, k: u32) -> Result<()> {
    let params = [count, k, 0, 0];
    let uniforms = [("params", bytemuck::cast_slice(&params))];
    dispatch_once(ctx, name, &uniforms, [count.div_ceil(64), 1, 1])
}

impl Pass for Arith {
    fn implementation(&self) -> Implementation {
        Implementation::new(self.entry, (self.contract)())
    }
    fn setup(&self, ctx: &mut SetupContext) -> Result<()> {
        ctx.min_bytes("output", self.count as u64 * 4);
        ctx.program(self.entry, program(self.entry, (self.layout)()));
        Ok(())
    }
    fn record(&self, ctx: &mut RecordContext<'_>) -> Result<()> {
        dispatch(ctx, self.entry, self.count, self.k)
    }
}

impl Pass for AddTwice {
    fn implementation(&self) -> Implementation {
        Implementation::new("add_twice", transform_contract())
    }
    fn setup(&self, ctx: &mut SetupContext) -> Result<()> {
        ctx.scratch_buffer(
            "half",
            BufferDesc::array(Element::U32, self.count as u64),
            &[Access::StorageReadWrite, Access::StorageRead],
        );
        // input + half into scratch, then scratch + half into output.
        let first = BindingLayout::compute("add_twice.first")
            .slot(0, "input")
            .scratch(1, "half", Access::StorageReadWrite)
            .uniform(2, "params");
        let second = BindingLayout::compute("add_twice.second")
            .scratch(0, "half", Access::StorageRead)
            .slot(1, "output")
            .uniform(2, "params");
        ctx.program("first", program("add", first));
        ctx.program("second", program("add", second));
        Ok(())
    }
    fn record(&self, ctx: &mut RecordContext<'_>) -> Result<()> {
        dispatch(ctx, "first", self.count, self.half)?;
        dispatch(ctx, "second", self.count, self.half)
    }
}

#[allow(unused_imports)] // not every test binary that includes this module opens a GPU
pub use meshlight_testing::gpu;

pub fn storage_buffer(gpu: &GpuContext, label: &str, words: &[u32]) -> wgpu::Buffer {
    gpu.buffer_with_data(
        label,
        bytemuck::cast_slice(words),
        wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
    )
}

/// Uploads `bytes` as the storage buffer imported as `import.0`, runs `frames` frames of
/// `compiled` and returns the executor, to read the results from.
pub fn run_frames(
    gpu: GpuContext,
    compiled: &CompiledGraph,
    import: (&str, &[u8]),
    frames: u32,
) -> Executor {
    let (name, bytes) = import;
    let buffer = gpu.buffer_with_data(name, bytes, wgpu::BufferUsages::STORAGE);
    let imports = Imports::new().buffer(name, &buffer);
    let mut exec = Executor::new(gpu);
    for _ in 0..frames {
        exec.execute(compiled, &imports).unwrap();
    }
    exec
}

/// Adds `pass` and returns the version of the buffer it writes through `slot`, for the
/// next pass to bind.
pub fn add_writer(
    g: &mut GraphBuilder,
    name: &str,
    pass: impl Pass + 'static,
    bindings: Bindings,
    slot: &str,
) -> Handle<Buffer> {
    g.add_pass(name, pass, bindings)
        .unwrap()
        .buffer(slot)
        .unwrap()
}

/// Adds `pass` and exports the buffer it writes through `slot`, for the test to read.
pub fn add_exported(
    g: &mut GraphBuilder,
    name: &str,
    pass: impl Pass + 'static,
    bindings: Bindings,
    slot: &str,
) {
    let out = add_writer(g, name, pass, bindings, slot);
    g.export(out);
}

/// The exported buffer `name` as the last frame left it, as `T`s.
pub fn read_export<T: bytemuck::Pod>(exec: &mut Executor, name: &str) -> Vec<T> {
    bytemuck::pod_collect_to_vec(&exec.read_buffer(name).unwrap())
}

/// Checks that every `u32` of the exported buffer `name` is `want`; a failure shows the
/// first words and `case`.
pub fn assert_every_word(exec: &mut Executor, name: &str, want: u32, case: &str) {
    let words: Vec<u32> = read_export(exec, name);
    assert!(
        words.iter().all(|&w| w == want),
        "{case}: {:?} want {want}",
        &words[..words.len().min(4)]
    );
}

pub fn read_u32s(gpu: &GpuContext, buffer: &wgpu::Buffer, count: usize) -> Vec<u32> {
    let bytes = gpu
        .read_buffer(buffer, 0, count as u64 * 4)
        .expect("readback");
    bytemuck::pod_collect_to_vec(&bytes)
}
