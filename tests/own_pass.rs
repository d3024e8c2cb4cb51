//! The README's "Write your own pass" walkthrough, run (lavapipe in CI): the code between
//! the markers below is the README's, character for character.

// walkthrough: start
use meshlight::graph::prelude::*;
use meshlight::graph::{Bindings, CompileOptions, Executor, GpuContext, GraphBuilder, Imports};

/// Stage `double`: `output[i] = 2 * input[i]`.
struct Double {
    count: u32,
}

const SHADER: PassShader = PassShader {
    name: "double",
    source: include_str!("walkthrough/double.wgsl"),
    file_path: "tests/walkthrough/double.wgsl",
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
// walkthrough: end

#[test]
fn the_walkthrough_pass_doubles_every_value() {
    let values: Vec<u32> = (0..100).collect();
    let gpu = meshlight_testing::gpu();
    let out = run(gpu, &values).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(out, values.iter().map(|v| 2 * v).collect::<Vec<_>>());
}

#[test]
fn the_readme_shows_this_walkthrough() {
    let source = include_str!("own_pass.rs");
    let start = source.find("// walkthrough: start\n").unwrap() + "// walkthrough: start\n".len();
    let end = source.find("// walkthrough: end").unwrap();
    let code = &source[start..end];
    let readme = include_str!("../README.md");
    assert!(
        readme.contains(code),
        "README.md's walkthrough differs from tests/own_pass.rs; copy the code between the markers into the README"
    );
    let wgsl = include_str!("walkthrough/double.wgsl");
    assert!(
        readme.contains(wgsl),
        "README.md's WGSL differs from tests/walkthrough/double.wgsl"
    );
}
