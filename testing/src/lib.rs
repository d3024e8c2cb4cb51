//! Helpers every crate's tests share: the GPU they run on and a runner for one pass.
//! A dev-dependency only; nothing in a library depends on it.

use meshlight_graph::{
    Bindings, BufferDesc, CompileOptions, Executor, FrameData, GpuContext, GraphBuilder, Imports,
    Pass, Result,
};

/// The first Vulkan adapter, opened with every feature it has that a pass may use.
/// Without one the test fails with the error, which says how to install a driver
/// (lavapipe with apt-get).
pub fn gpu() -> GpuContext {
    GpuContext::with_available(wgpu::Features::all()).unwrap_or_else(|e| panic!("{e}"))
}

/// An executor on [`gpu`].
pub fn executor() -> Executor {
    Executor::new(gpu())
}

/// A buffer the pass reads: imported under `name` with these contents.
pub struct Input<'a> {
    pub name: &'static str,
    pub desc: BufferDesc,
    pub bytes: &'a [u8],
}

/// A buffer the pass writes: created under `name`, exported, read back after the frame.
pub struct Output {
    pub name: &'static str,
    pub desc: BufferDesc,
}

/// Runs `pass` for one frame on `exec` with its slots bound to the inputs and outputs of
/// the same names, and returns each output's bytes in order.
pub fn run_one_pass(
    exec: &mut Executor,
    pass: impl Pass + 'static,
    inputs: &[Input],
    outputs: &[Output],
    frame: &FrameData,
) -> Result<Vec<Vec<u8>>> {
    let usage = wgpu::BufferUsages::STORAGE
        | wgpu::BufferUsages::COPY_DST
        | wgpu::BufferUsages::COPY_SRC
        | wgpu::BufferUsages::INDIRECT;
    let mut g = GraphBuilder::new();
    for i in inputs {
        g.import_buffer(i.name, i.desc.clone(), usage);
    }
    for o in outputs {
        g.create_buffer(o.name, o.desc.clone());
    }
    let written = g.add_pass("pass", pass, Bindings::new())?;
    for o in outputs {
        g.export(written.buffer(o.name)?);
    }
    let compiled = g.compile(&CompileOptions::for_gpu(&exec.gpu))?;
    let buffers: Vec<wgpu::Buffer> = inputs
        .iter()
        .map(|i| exec.gpu.buffer_with_data(i.name, i.bytes, usage))
        .collect();
    let imports = inputs
        .iter()
        .zip(&buffers)
        .fold(Imports::new(), |imports, (i, b)| imports.buffer(i.name, b));
    exec.execute_frame(&compiled, &imports, frame)?;
    outputs.iter().map(|o| exec.read_buffer(o.name)).collect()
}
