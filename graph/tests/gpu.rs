//! Graphs executed on a real Vulkan adapter (lavapipe in CI).

mod support;
use meshlight_graph::*;
use support::*;

const N: u32 = 1000;
const USAGE: wgpu::BufferUsages = wgpu::BufferUsages::STORAGE
    .union(wgpu::BufferUsages::COPY_SRC)
    .union(wgpu::BufferUsages::COPY_DST);

fn three_pass_graph(transform: impl Pass + 'static) -> GraphBuilder {
    let mut g = GraphBuilder::new();
    let a = g.create_buffer("a", BufferDesc::array(Element::U32, N as u64));
    let b = g.create_buffer("b", BufferDesc::array(Element::U32, N as u64));
    let result = g.import_buffer("result", BufferDesc::array(Element::U32, N as u64), USAGE);
    let bindings = Bindings::new().bind("output", a);
    let a = add_writer(&mut g, "fill", Arith::fill(N, 3), bindings, "output");
    let bindings = Bindings::new().bind("input", a).bind("output", b);
    let b = add_writer(&mut g, "transform", transform, bindings, "output");
    g.add_pass(
        "add",
        Arith::add(N, 7),
        Bindings::new().bind("input", b).bind("output", result),
    )
    .unwrap();
    g
}

fn run_once(g: GraphBuilder) -> Vec<u32> {
    let gpu = gpu();
    let compiled = g.compile(&CompileOptions::for_gpu(&gpu)).unwrap();
    let result = gpu.buffer_with_data("result", &vec![0xFFu8; N as usize * 4], USAGE);
    let mut exec = Executor::new(gpu);
    let stats = exec
        .execute(&compiled, &Imports::new().buffer("result", &result))
        .unwrap();
    assert_eq!(stats.passes.len(), 3);
    read_u32s(&exec.gpu, &result, N as usize)
}

#[test]
fn three_pass_compute_graph_gives_the_known_result() {
    let out = run_once(three_pass_graph(Arith::add(N, 5)));
    let expected: Vec<u32> = (0..N).map(|i| i * 3 + 5 + 7).collect();
    assert_eq!(out, expected);
}

#[test]
fn swapped_implementation_gives_the_same_result() {
    let a = run_once(three_pass_graph(Arith::add(N, 10)));
    let b = run_once(three_pass_graph(AddTwice { count: N, half: 5 }));
    assert_eq!(a, b);
    assert_eq!(b[9], 9 * 3 + 10 + 7);
}

#[test]
fn history_resource_carries_from_frame_to_frame() {
    let gpu = gpu();
    let mut g = GraphBuilder::new();
    let h = g.history_buffer("counter", BufferDesc::array(Element::U32, 64));
    g.add_pass(
        "accumulate",
        Arith::add(64, 1),
        Bindings::new()
            .bind("input", h.prev)
            .bind("output", h.current),
    )
    .unwrap();
    let compiled = g.compile(&CompileOptions::for_gpu(&gpu)).unwrap();
    let mut exec = Executor::new(gpu);
    for frame in 1..=4u32 {
        exec.execute(&compiled, &Imports::new()).unwrap();
        assert_every_word(&mut exec, "counter", frame, &format!("frame {frame}"));
    }
}

#[test]
fn steady_graph_allocates_nothing_after_the_first_frame() {
    let gpu = gpu();
    let compiled = three_pass_graph(Arith::add(N, 1))
        .compile(&CompileOptions::for_gpu(&gpu))
        .unwrap();
    let result = gpu.buffer_with_data("result", &[0u8; N as usize * 4], USAGE);
    let mut exec = Executor::new(gpu);
    let imports = Imports::new().buffer("result", &result);
    let first = exec.execute(&compiled, &imports).unwrap();
    let second = exec.execute(&compiled, &imports).unwrap();
    assert!(first.allocations > 0 && first.pipelines_created > 0);
    assert_eq!((second.allocations, second.pipelines_created), (0, 0));
    if exec.gpu.features.contains(wgpu::Features::TIMESTAMP_QUERY) {
        let finished = exec.finish().unwrap().unwrap();
        assert_eq!(finished.frame, second.frame);
        // The default `frame` timing times each batch; the three passes share one.
        assert_eq!(finished.timing, TimingMode::Frame);
        assert_eq!(finished.batches.len(), 1);
        assert!(finished.batches.iter().all(|b| b.gpu_us.is_some()));
    }
}

#[test]
fn wgpu_validation_error_surfaces_as_an_error() {
    // Dispatching more workgroups than the device allows is a validation error.
    let oversized = fake::pass(
        "produce",
        produce_contract().slots,
        |ctx| {
            let layout = BindingLayout::compute("fill")
                .slot(1, "output")
                .uniform(2, "params");
            ctx.program("fill", ProgramDesc::compute(&SHADER, "fill").layout(layout));
            Ok(())
        },
        |ctx| {
            let params = [1u32, 1, 0, 0];
            let uniforms = [("params", bytemuck::cast_slice(&params))];
            dispatch_once(ctx, "fill", &uniforms, [u32::MAX, 1, 1])
        },
    );
    let gpu = gpu();
    let mut g = GraphBuilder::new();
    let out = g.import_buffer("out", BufferDesc::array(Element::U32, 16), USAGE);
    g.add_pass("too_big", oversized, Bindings::new().bind("output", out))
        .unwrap();
    let compiled = g.compile(&CompileOptions::for_gpu(&gpu)).unwrap();
    let buffer = gpu.buffer_with_data("out", &[0u8; 64], USAGE);
    let mut exec = Executor::new(gpu);
    // Naming the pass is checked mode's work, which release builds leave off.
    exec.set_checked(true);
    match exec.execute(&compiled, &Imports::new().buffer("out", &buffer)) {
        Err(GraphError::Validation { pass, message }) => {
            assert_eq!(pass, "too_big");
            assert!(!message.is_empty());
        }
        other => panic!(
            "expected a validation error, got {:?}",
            other.map(|s| s.frame)
        ),
    }
    // Unchecked, the frame still fails with wgpu's message, naming no pass.
    exec.set_checked(false);
    match exec.execute(&compiled, &Imports::new().buffer("out", &buffer)) {
        Err(GraphError::FrameValidation { message, .. }) => assert!(!message.is_empty()),
        other => panic!(
            "expected a frame validation error, got {:?}",
            other.map(|s| s.frame)
        ),
    }
}
