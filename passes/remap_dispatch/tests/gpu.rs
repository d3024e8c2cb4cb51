//! `remap_dispatch` on the GPU against `cpu_remap`, and the arguments driving a real
//! indirect dispatch whose workgroups count themselves.

use meshlight_graph::*;
use meshlight_pass_remap_dispatch::{RemapDispatch, cpu_remap};
use meshlight_testing::frames::filled;
use meshlight_testing::pass_errors::pass_parameter_message;
use meshlight_testing::{Input, Output, USAGE, executor, run_graph, run_one_pass};

/// A consumer of the arguments: every workgroup below the count marks its linear index.
const CONSUMER: PassShader = PassShader {
    name: "test::consumer",
    source: r#"
// The count the dispatch was made for.
@group(0) @binding(0) var<storage, read> count: array<u32>;
// The x size of the dispatch, to linearise the workgroup id.
@group(0) @binding(1) var<storage, read> args: array<u32>;
// One counter per workgroup index; each must end at 1.
@group(0) @binding(2) var<storage, read_write> hits: array<atomic<u32>>;

@compute @workgroup_size(1)
fn consume(@builtin(workgroup_id) wg: vec3<u32>) {
    let i = wg.y * args[0] + wg.x;
    if i < count[0] {
        atomicAdd(&hits[i], 1u);
    }
}
"#,
    file_path: "passes/remap_dispatch/tests/gpu.rs",
    modules: &[],
};

struct Consume;

impl Pass for Consume {
    fn implementation(&self) -> Implementation {
        Implementation::new(
            "test",
            StageContract {
                stage: "consume",
                slots: vec![
                    Slot::buffer("count", Access::StorageRead, Element::U32, ""),
                    Slot::buffer("args", Access::StorageRead, Element::DISPATCH_ARGS, "")
                        .also(Access::Indirect),
                    Slot::buffer("hits", Access::ClearedReadWrite, Element::U32, ""),
                ],
            },
        )
    }
    fn setup(&self, ctx: &mut SetupContext) -> Result<()> {
        let layout = BindingLayout::from_shader("consume");
        ctx.program(
            "consume",
            ProgramDesc::compute(&CONSUMER, "consume").layout(layout),
        );
        Ok(())
    }
    fn record(&self, ctx: &mut RecordContext<'_>) -> Result<()> {
        ctx.clear("hits")?;
        let p = ctx.compute("consume")?;
        let bg = ctx.bind_group(&p, 0, &[])?;
        let (args, _) = ctx.buffer("args")?;
        let mut cp = ctx.compute_pass();
        cp.set_pipeline(&p.pipeline);
        cp.set_bind_group(0, &bg, &[]);
        cp.dispatch_workgroups_indirect(args, 0);
        Ok(())
    }
}

/// Remaps `count` under `max` on the GPU; returns the arguments and the per-workgroup hits.
fn run(exec: &mut Executor, count: u32, max: u32, capacity: u32) -> ([u32; 3], Vec<u32>) {
    let mut g = GraphBuilder::new();
    let count_h = g.import_buffer("count", BufferDesc::array(Element::U32, 1), USAGE);
    let args = g.create_buffer("args", BufferDesc::array(Element::DISPATCH_ARGS, 1));
    let hits = g.create_buffer("hits", BufferDesc::array(Element::U32, capacity as u64));
    let remap = RemapDispatch {
        count_word: 0,
        max_per_dimension: Some(max),
    };
    let out = g
        .add_pass(
            "remap",
            remap,
            Bindings::new().bind("count", count_h).bind("args", args),
        )
        .unwrap();
    let args = out.buffer("args").unwrap();
    g.export(args);
    let out = g
        .add_pass(
            "consume",
            Consume,
            Bindings::new()
                .bind("count", count_h)
                .bind("args", args)
                .bind("hits", hits),
        )
        .unwrap();
    g.export(out.buffer("hits").unwrap());
    let count = [count];
    let input = filled("count", Element::U32, &count);
    let [args, hits] = run_graph(exec, g, &[input], &["args", "hits"], &FrameData::new())
        .unwrap()
        .try_into()
        .unwrap();
    let args: Vec<u32> = bytemuck::pod_collect_to_vec(&args);
    (
        [args[0], args[1], args[2]],
        bytemuck::pod_collect_to_vec(&hits),
    )
}

#[test]
fn arguments_equal_the_reference_and_every_workgroup_runs_once() {
    let mut exec = executor();
    for (count, max) in [
        (0, 7),
        (1, 7),
        (6, 7),
        (7, 7),
        (8, 7),
        (48, 7),
        (49, 7),
        (1000, 32),
        // Past max²: the last rows are dropped, as the contract says.
        (1000, 31),
        (70_000, 65_535),
    ] {
        let (args, hits) = run(&mut exec, count, max, 70_000);
        assert_eq!(args, cpu_remap(count, max), "{count} under {max}");
        let runs = count.min(args[0] * args[1]);
        for (i, h) in hits.iter().enumerate() {
            let want = u32::from((i as u32) < runs);
            assert_eq!(*h, want, "{count} under {max}: workgroup {i} ran {h} times");
        }
    }
}

#[test]
fn a_limit_above_the_adapters_is_a_parameter_error() {
    let exec = executor();
    let limit = exec
        .gpu
        .device
        .limits()
        .max_compute_workgroups_per_dimension;
    let mut g = GraphBuilder::new();
    g.import_buffer("count", BufferDesc::array(Element::U32, 1), USAGE);
    let args = g.create_buffer("args", BufferDesc::array(Element::DISPATCH_ARGS, 1));
    let remap = RemapDispatch {
        count_word: 0,
        max_per_dimension: Some(limit + 1),
    };
    let out = g
        .add_pass("remap", remap, Bindings::new().bind("args", args))
        .unwrap();
    g.export(out.buffer("args").unwrap());
    let message = pass_parameter_message(g.compile(&CompileOptions::for_gpu(&exec.gpu)), "remap");
    assert!(message.contains("max_per_dimension"), "{message}");
}

/// The pass alone, its count at a word other than the first.
#[test]
fn the_count_is_read_at_its_word() {
    let mut exec = executor();
    for count in [0u32, 5, 1000, 70_000] {
        let words = [9u32, 9, count, 9];
        let remap = RemapDispatch {
            count_word: 2,
            max_per_dimension: Some(100),
        };
        let out = run_one_pass(
            &mut exec,
            remap,
            &[Input {
                name: "count",
                desc: BufferDesc::array(Element::U32, 4),
                bytes: bytemuck::cast_slice(&words),
            }],
            &[Output {
                name: "args",
                desc: BufferDesc::array(Element::DISPATCH_ARGS, 1),
            }],
            &FrameData::default(),
        )
        .unwrap_or_else(|e| panic!("{e}"));
        let args: Vec<u32> = bytemuck::pod_collect_to_vec(&out[0]);
        assert_eq!(args, cpu_remap(count, 100), "{count}");
    }
}
