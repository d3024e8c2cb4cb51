//! The README's "Write your own pass": a stage of one compute shader (double.wgsl beside
//! this file), its pass, and a graph that runs it.
use meshlight::graph::prelude::*;
use meshlight::graph::{Bindings, CompileOptions, Executor, GpuContext, GraphBuilder, Imports};
use meshlight::{bytemuck, wgpu};

/// Stage `double`: `output[i] = 2 * input[i]`.
struct Double {
    count: u32,
}

const SHADER: PassShader = PassShader {
    name: "double",
    source: include_str!("double.wgsl"),
    file_path: "double.wgsl",
    modules: &[],
};

impl Pass for Double {
    // What it is: implementation `compute` of stage `double`, whose contract says what
    // the stage reads and writes, by slot name.
    fn implementation(&self) -> Implementation {
        Implementation::new(
            "compute",
            StageContract {
                stage: "double",
                slots: vec![
                    Slot::read("input", Element::U32, "values"),
                    Slot::buffer("output", Access::StorageWrite, Element::U32, "doubled"),
                ],
            },
        )
    }
    // Setup: the program; its bindings come from the WGSL variables' names.
    fn setup(&self, ctx: &mut SetupContext) -> Result<()> {
        ctx.program(
            "double",
            ProgramDesc::compute(&SHADER, "double").layout(BindingLayout::from_shader("double")),
        );
        Ok(())
    }
    // Record: one dispatch.
    fn record(&self, ctx: &mut RecordContext<'_>) -> Result<()> {
        let groups = [self.count.div_ceil(64), 1, 1];
        ctx.dispatch_compute("double", &[], Workgroups::Direct(groups))
    }
}

fn run(gpu: GpuContext, values: &[u32]) -> Result<Vec<u32>> {
    let n = values.len() as u64;
    let mut g = GraphBuilder::new();
    g.import_buffer(
        "input",
        BufferDesc::array(Element::U32, n),
        wgpu::BufferUsages::STORAGE,
    );
    g.create_buffer("output", BufferDesc::array(Element::U32, n));
    let written = g.add_pass("double", Double { count: n as u32 }, Bindings::new())?;
    g.export(written.buffer("output")?);
    let compiled = g.compile(&CompileOptions::for_gpu(&gpu))?;
    let input = gpu.buffer_with_data(
        "input",
        bytemuck::cast_slice(values),
        wgpu::BufferUsages::STORAGE,
    );
    let mut exec = Executor::new(gpu);
    exec.execute(&compiled, &Imports::new().buffer("input", &input))?;
    Ok(bytemuck::pod_collect_to_vec(&exec.read_buffer("output")?))
}

fn main() -> Result<()> {
    let gpu = GpuContext::with_available(wgpu::Features::empty())?;
    let values: Vec<u32> = (0..100).collect();
    let doubled = run(gpu, &values)?;
    assert!(doubled.iter().zip(&values).all(|(d, v)| *d == 2 * v));
    println!("doubled {} values on the GPU", doubled.len());
    Ok(())
}
