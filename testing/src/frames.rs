//! Helpers for tests that build the graph around their pass themselves (to bind a
//! texture target, chain passes, or keep one executor across frames): the buffers they
//! fill and import, and frames run one per camera.

use crate::{Input, USAGE};
use meshlight_graph::{
    Buffer, BufferDesc, CompiledGraph, Element, Executor, FrameData, GpuContext, GraphBuilder,
    Handle, Imports, Result,
};
use meshlight_shaders::cpu::layout::View;

/// An [`Input`] named `name` holding `data` as an array of `element`, as long as `data`.
pub fn filled<'a, T: bytemuck::Pod>(
    name: &'static str,
    element: Element,
    data: &'a [T],
) -> Input<'a> {
    let bytes: &[u8] = bytemuck::cast_slice(data);
    let count = bytes.len() as u64 / u64::from(element.size);
    Input {
        name,
        desc: BufferDesc::array(element, count),
        bytes,
    }
}

/// What [`import_filled`] imported, each in the order of its inputs.
pub struct Imported<const N: usize> {
    /// The handles in the graph, to bind.
    pub handles: [Handle<Buffer>; N],
    /// The buffers, to read back what a pass wrote into one.
    pub buffers: [wgpu::Buffer; N],
    /// The frame's imports with each buffer added under its name.
    pub imports: Imports,
}

/// Imports each of `inputs` into `g` under its name and makes it on `gpu` filled with
/// its bytes (both with [`USAGE`]), adding it to `imports` (a GPU scene's, say).
pub fn import_filled<const N: usize>(
    g: &mut GraphBuilder,
    gpu: &GpuContext,
    inputs: [Input; N],
    imports: Imports,
) -> Imported<N> {
    let handles = inputs
        .each_ref()
        .map(|i| g.import_buffer(i.name, i.desc.clone(), USAGE));
    let buffers = inputs
        .each_ref()
        .map(|i| gpu.buffer_with_data(i.name, i.bytes, USAGE));
    let imports = inputs
        .iter()
        .zip(&buffers)
        .fold(imports, |imports, (i, b)| imports.buffer(i.name, b));
    Imported {
        handles,
        buffers,
        imports,
    }
}

/// Runs `compiled` on `exec` once per camera of `views` (the frame input `view`, as
/// every stage that reads a camera names it), waiting for each frame to finish, and
/// returns what `read` takes from the executor after each.
pub fn run_per_view<T>(
    exec: &mut Executor,
    compiled: &CompiledGraph,
    imports: &Imports,
    views: &[View],
    read: impl FnMut(&mut Executor) -> Result<T>,
) -> Result<Vec<T>> {
    run_per_view_with(exec, compiled, imports, views, &[], read)
}

/// [`run_per_view`] with more frame inputs, `(name, bytes)`, the same in every frame.
pub fn run_per_view_with<T>(
    exec: &mut Executor,
    compiled: &CompiledGraph,
    imports: &Imports,
    views: &[View],
    inputs: &[(&str, &[u8])],
    mut read: impl FnMut(&mut Executor) -> Result<T>,
) -> Result<Vec<T>> {
    views
        .iter()
        .map(|view| {
            let mut data = FrameData::new().with("view", bytemuck::bytes_of(view));
            for (name, bytes) in inputs {
                data = data.with(name, bytes);
            }
            exec.execute_frame(compiled, imports, &data)?;
            exec.finish()?;
            read(exec)
        })
        .collect()
}
