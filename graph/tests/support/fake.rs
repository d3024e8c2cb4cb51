//! Passes whose contract and work a test states inline: `Fake` with any contract and no
//! GPU work, for compile tests, and `pass` built from closures.
#![allow(dead_code)]

use meshlight_graph::*;

pub struct Fake {
    contract: StageContract,
    pub required: wgpu::Features,
    pub side_effect: bool,
    pub scratch: Option<u64>,
}

impl Fake {
    pub fn new(stage: &'static str, slots: Vec<Slot>) -> Self {
        Self {
            contract: StageContract { stage, slots },
            required: wgpu::Features::empty(),
            side_effect: false,
            scratch: None,
        }
    }
    /// Reads each of `inputs`, writes each of `outputs` (u32 buffers).
    pub fn rw(inputs: &[&'static str], outputs: &[&'static str]) -> Self {
        let mut slots: Vec<Slot> = inputs
            .iter()
            .map(|n| Slot::buffer(n, Access::StorageRead, Element::U32, ""))
            .collect();
        slots.extend(
            outputs
                .iter()
                .map(|n| Slot::buffer(n, Access::StorageWrite, Element::U32, "")),
        );
        Self::new("fake", slots)
    }
}

impl Pass for Fake {
    fn implementation(&self) -> Implementation {
        Implementation::new("fake", self.contract.clone())
    }
    fn setup(&self, ctx: &mut SetupContext) -> Result<()> {
        ctx.require_features(self.required);
        if self.side_effect {
            ctx.side_effect();
        }
        if let Some(bytes) = self.scratch {
            ctx.scratch_buffer(
                "tmp",
                BufferDesc::bytes(Element::BYTES, bytes),
                &[Access::StorageReadWrite],
            );
        }
        Ok(())
    }
    fn record(&self, _: &mut RecordContext<'_>) -> Result<()> {
        Ok(())
    }
}

pub fn u32s(n: u64) -> BufferDesc {
    BufferDesc::array(Element::U32, n)
}

pub const IMPORT_USAGE: wgpu::BufferUsages =
    wgpu::BufferUsages::STORAGE.union(wgpu::BufferUsages::COPY_SRC);

pub fn opts() -> CompileOptions {
    CompileOptions::new(wgpu::Features::empty())
}

/// The error compiling `g` with [`opts`] fails with, for a test to match; panics when the
/// graph compiles.
pub fn compile_error(g: GraphBuilder) -> GraphError {
    g.compile(&opts())
        .err()
        .expect("the graph compiled; the test expects a compile error")
}

/// Compiles `$graph` expecting the error `$variant` and binds the pattern's fields for the
/// checks that follow; any other outcome panics naming what came instead.
#[allow(unused_macros)] // not every test binary expects compile errors
macro_rules! let_compile_error {
    ($graph:expr => $variant:pat) => {
        let e = compile_error($graph);
        let $variant = e else {
            panic!("{e:?}");
        };
    };
}
#[allow(unused_imports)] // not every test binary expects compile errors
pub(crate) use let_compile_error;

/// A pass built from closures, so each test states its contract, setup and record inline.
pub struct TestPass<S, R> {
    contract: StageContract,
    setup: S,
    record: R,
}

impl<S, R> Pass for TestPass<S, R>
where
    S: Fn(&mut SetupContext) -> Result<()> + Send + Sync,
    R: Fn(&mut RecordContext<'_>) -> Result<()> + Send + Sync,
{
    fn implementation(&self) -> Implementation {
        Implementation::new("test", self.contract.clone())
    }
    fn setup(&self, ctx: &mut SetupContext) -> Result<()> {
        (self.setup)(ctx)
    }
    fn record(&self, ctx: &mut RecordContext<'_>) -> Result<()> {
        (self.record)(ctx)
    }
}

pub fn pass<S, R>(stage: &'static str, slots: Vec<Slot>, setup: S, record: R) -> TestPass<S, R>
where
    S: Fn(&mut SetupContext) -> Result<()> + Send + Sync,
    R: Fn(&mut RecordContext<'_>) -> Result<()> + Send + Sync,
{
    TestPass {
        contract: StageContract { stage, slots },
        setup,
        record,
    }
}

/// A `u32` buffer slot `out` the pass writes: what keeps a setup-only test pass alive.
pub fn out_u32() -> Slot {
    Slot::buffer("out", Access::StorageWrite, Element::U32, "")
}
