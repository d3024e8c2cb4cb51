//! Batched recording: consecutive compute-only passes share one compute pass, a pass that
//! needs the encoder ends the batch, and every graph gives the same results batched and
//! unbatched (lavapipe in CI).

mod support;

use meshlight_graph::*;
use support::fake::pass;
use support::{add_writer, dispatch_once, gpu, render_once};

const KERNELS: PassShader = PassShader {
    name: "test::batches",
    source: r#"
struct Params {
    // Constant of the step.
    k: u32,
    // Elements.
    n: u32,
    a: u32,
    b: u32,
}

// The words a step updates in place.
@group(0) @binding(0) var<storage, read_write> data: array<u32>;
// k and n.
@group(0) @binding(1) var<uniform> params: Params;

// x ← 3x + k: the order of steps changes the result, so a step that ran before the one it
// depends on is seen.
@compute @workgroup_size(64)
fn step(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x < params.n {
        data[id.x] = data[id.x] * 3u + params.k;
    }
}

// The pixel colour the draw writes: data[0]'s low byte.
@group(0) @binding(2) var<storage, read> shown: array<u32>;

@vertex
fn fullscreen(@builtin(vertex_index) v: u32) -> @builtin(position) vec4<f32> {
    let uv = vec2<f32>(f32((v << 1u) & 2u), f32(v & 2u));
    return vec4<f32>(uv * 2.0 - 1.0, 0.0, 1.0);
}

@fragment
fn shade() -> @location(0) vec4<f32> {
    return vec4<f32>(f32(shown[0] & 255u) / 255.0, 0.0, 0.0, 1.0);
}

// Each texel's red byte, one word per texel.
@group(0) @binding(3) var picture: texture_2d<f32>;
@group(0) @binding(4) var<storage, read_write> texels: array<u32>;

@compute @workgroup_size(8, 8)
fn read_back(@builtin(global_invocation_id) id: vec3<u32>) {
    let size = textureDimensions(picture);
    if id.x < size.x && id.y < size.y {
        texels[id.y * size.x + id.x] = u32(round(textureLoad(picture, id.xy, 0).r * 255.0));
    }
}
"#,
    file_path: "graph/tests/batches.rs",
    modules: &[],
};

const N: u32 = 4096;
const USAGE: wgpu::BufferUsages = wgpu::BufferUsages::STORAGE
    .union(wgpu::BufferUsages::COPY_SRC)
    .union(wgpu::BufferUsages::COPY_DST);

/// x ← 3x + k on every element of slot `data`, optionally zeroing it first (`clear`).
struct Step {
    k: u32,
    clear: bool,
}

impl Pass for Step {
    fn implementation(&self) -> Implementation {
        let access = if self.clear {
            Access::ClearedReadWrite
        } else {
            Access::StorageReadWrite
        };
        Implementation::new(
            "compute",
            StageContract {
                stage: "step",
                slots: vec![Slot::buffer(
                    "data",
                    access,
                    Element::U32,
                    "updated in place",
                )],
            },
        )
    }
    fn setup(&self, ctx: &mut SetupContext) -> Result<()> {
        let layout = BindingLayout::compute("step")
            .slot(0, "data")
            .uniform(1, "params");
        ctx.program(
            "step",
            ProgramDesc::compute(&KERNELS, "step").layout(layout),
        );
        Ok(())
    }
    fn record(&self, ctx: &mut RecordContext<'_>) -> Result<()> {
        if self.clear {
            ctx.clear("data")?;
        }
        step_dispatch(ctx, self.k, N.div_ceil(64))
    }
}

/// Dispatches the program `step` (x ← 3x + k) over `groups` workgroups.
fn step_dispatch(ctx: &mut RecordContext<'_>, k: u32, groups: u32) -> Result<()> {
    let params = [k, N, 0, 0];
    dispatch_once(
        ctx,
        "step",
        &[("params", bytemuck::cast_slice(&params))],
        [groups, 1, 1],
    )
}

/// The slots of a stage that copies its slot `from` into its slot `to`.
fn copy_slots() -> Vec<Slot> {
    vec![
        Slot::buffer("from", Access::CopySrc, Element::U32, ""),
        Slot::buffer("to", Access::CopyDst, Element::U32, ""),
    ]
}

/// Copies slot `from` into slot `to` with a copy command (the encoder).
fn copy_buffer(ctx: &mut RecordContext<'_>) -> Result<()> {
    let (from, bytes) = ctx.buffer("from")?;
    let (to, _) = ctx.buffer("to")?;
    ctx.encoder().copy_buffer_to_buffer(from, 0, to, 0, bytes);
    Ok(())
}

/// The slot `data` a clearing pass writes in place.
fn data_slot() -> Vec<Slot> {
    vec![Slot::buffer(
        "data",
        Access::StorageReadWrite,
        Element::U32,
        "",
    )]
}

/// Clears slot `data` with `clear_buffer`, a command of the encoder.
fn clear_data(ctx: &mut RecordContext<'_>) -> Result<()> {
    let (data, bytes) = ctx.buffer("data")?;
    ctx.encoder().clear_buffer(data, 0, Some(bytes));
    Ok(())
}

/// A compute-only pass (so the plan batches it) that takes the encoder anyway.
fn sneaky_clear() -> impl Pass {
    pass("sneaky", data_slot(), |_| Ok(()), clear_data)
}

/// A step that dispatches more workgroups than any device allows: a validation error.
struct Oversized;

impl Pass for Oversized {
    fn implementation(&self) -> Implementation {
        Implementation::new(
            "oversized",
            Step { k: 0, clear: false }.implementation().contract,
        )
    }
    fn setup(&self, ctx: &mut SetupContext) -> Result<()> {
        Step { k: 0, clear: false }.setup(ctx)
    }
    fn record(&self, ctx: &mut RecordContext<'_>) -> Result<()> {
        step_dispatch(ctx, 0, u32::MAX)
    }
}

fn cpu_steps(start: &[u32], ks: &[u32]) -> Vec<u32> {
    start
        .iter()
        .map(|&x| ks.iter().fold(x, |x, &k| x.wrapping_mul(3).wrapping_add(k)))
        .collect()
}

fn start_words() -> Vec<u32> {
    (0..N).map(|i| i.wrapping_mul(2_654_435_761)).collect()
}

/// Runs `graph` with batching on or off and returns the imported `data` after `frames`.
fn run(
    graph: &CompiledGraph,
    batching: bool,
    frames: u32,
    extra: &[(&str, u64)],
) -> (Vec<u32>, FrameStats, Vec<Vec<u32>>) {
    let gpu = gpu();
    let data = gpu.buffer_with_data("data", bytemuck::cast_slice(&start_words()), USAGE);
    let mut imports = Imports::new().buffer("data", &data);
    let mut others = Vec::new();
    for (name, words) in extra {
        let b = gpu.buffer_with_data(name, &vec![0xABu8; *words as usize * 4], USAGE);
        imports = imports.buffer(name, &b);
        others.push(b);
    }
    let mut exec = Executor::new(gpu);
    exec.batching = batching;
    exec.checked = true;
    let mut stats = None;
    for _ in 0..frames {
        stats = Some(exec.execute(graph, &imports).unwrap());
    }
    exec.finish().unwrap();
    let got = support::read_u32s(&exec.gpu, &data, N as usize);
    let extra = others
        .iter()
        .zip(extra)
        .map(|(b, (_, words))| support::read_u32s(&exec.gpu, b, *words as usize))
        .collect();
    (got, stats.unwrap(), extra)
}

/// Adds `step` on `data` as pass `name` and returns the version it writes.
fn step_on(g: &mut GraphBuilder, name: &str, step: Step, data: Handle<Buffer>) -> Handle<Buffer> {
    add_writer(g, name, step, Bindings::new().bind("data", data), "data")
}

/// Each batch's pass count and whether it is a shared compute pass.
fn batch_shape(compiled: &CompiledGraph) -> Vec<(usize, bool)> {
    let batches = &compiled.plan.batches;
    batches
        .iter()
        .map(|b| (b.passes.len(), b.compute))
        .collect()
}

fn chain(ks: &[u32]) -> GraphBuilder {
    let mut g = GraphBuilder::new();
    g.import_buffer("data", BufferDesc::array(Element::U32, N as u64), USAGE);
    for (i, &k) in ks.iter().enumerate() {
        g.add_pass(
            &format!("step{i}"),
            Step { k, clear: false },
            Bindings::new(),
        )
        .unwrap();
    }
    g
}

#[test]
fn a_chain_on_one_buffer_is_one_batch_and_equals_the_unbatched_run_and_the_cpu() {
    let ks = [1, 7, 11, 2, 5, 13, 3, 17];
    let compiled = chain(&ks)
        .compile(&CompileOptions::for_gpu(&gpu()))
        .unwrap();
    assert_eq!(compiled.plan.batches.len(), 1);
    assert!(compiled.plan.batches[0].compute);
    let (batched, stats, _) = run(&compiled, true, 1, &[]);
    let (unbatched, plain, _) = run(&compiled, false, 1, &[]);
    assert_eq!(batched, cpu_steps(&start_words(), &ks));
    assert_eq!(batched, unbatched);
    assert_eq!(stats.compute_passes, 1, "the batch shares one compute pass");
    assert_eq!(plain.compute_passes, 0, "unbatched passes open their own");
    assert_eq!(stats.unplanned_splits, 0);
}

#[test]
fn a_clear_stays_in_the_batch_and_a_copy_splits_it() {
    let mut g = GraphBuilder::new();
    let data = g.import_buffer("data", BufferDesc::array(Element::U32, N as u64), USAGE);
    let copy = g.import_buffer("copy", BufferDesc::array(Element::U32, N as u64), USAGE);
    let data = step_on(&mut g, "first", Step { k: 5, clear: false }, data);
    let data = step_on(&mut g, "cleared", Step { k: 9, clear: true }, data);
    let data = step_on(&mut g, "after", Step { k: 4, clear: false }, data);
    let copier = pass("copy", copy_slots(), |_| Ok(()), copy_buffer);
    let bindings = Bindings::new().bind("from", data).bind("to", copy);
    let copy = add_writer(&mut g, "copy", copier, bindings, "to");
    step_on(&mut g, "on_copy", Step { k: 1, clear: false }, copy);
    let compiled = g.compile(&CompileOptions::for_gpu(&gpu())).unwrap();
    let shape = batch_shape(&compiled);
    assert_eq!(shape, [(3, true), (1, false), (1, true)]);
    let extra = [("copy", N as u64)];
    let (data_b, stats, copy_b) = run(&compiled, true, 1, &extra);
    let (data_u, _, copy_u) = run(&compiled, false, 1, &extra);
    // The clear zeroes whatever `first` left: 3·0 + 9, then 3·9 + 4.
    assert!(data_b.iter().all(|&x| x == 31), "{:?}", &data_b[..4]);
    assert!(copy_b[0].iter().all(|&x| x == 94), "{:?}", &copy_b[0][..4]);
    assert_eq!((data_b, copy_b), (data_u, copy_u));
    assert_eq!(stats.compute_passes, 2);
    assert_eq!(stats.batches.len(), 3);
}

#[test]
fn a_render_pass_between_compute_passes_sees_the_first_and_is_seen_by_the_next() {
    const SIDE: u32 = 16;
    let mut g = GraphBuilder::new();
    let data = g.import_buffer("data", BufferDesc::array(Element::U32, N as u64), USAGE);
    let texels = g.import_buffer(
        "texels",
        BufferDesc::array(Element::U32, (SIDE * SIDE) as u64),
        USAGE,
    );
    let picture = g.create_texture(
        "picture",
        TextureDesc::d2(wgpu::TextureFormat::Rgba8Unorm, SIDE, SIDE),
    );
    let data = step_on(&mut g, "before", Step { k: 7, clear: true }, data);
    let draw = pass(
        "draw",
        vec![
            Slot::buffer("shown", Access::StorageRead, Element::U32, ""),
            Slot::texture("picture", Access::RenderTarget, None, ""),
        ],
        |ctx| {
            ctx.program(
                "draw",
                ProgramDesc::render(&KERNELS, "fullscreen")
                    .fragment("shade")
                    .target(ColorTarget::new("picture"))
                    .layout(BindingLayout::render("draw").slot(2, "shown")),
            );
            Ok(())
        },
        |ctx| {
            let picture = [ColorAttachment::new("picture")];
            render_once(ctx, "draw", &[], &picture, None, |rp| rp.draw(0..3, 0..1))
        },
    );
    let picture = g
        .add_pass(
            "draw",
            draw,
            Bindings::new().bind("shown", data).bind("picture", picture),
        )
        .unwrap()
        .texture("picture")
        .unwrap();
    struct ReadBack;
    impl Pass for ReadBack {
        fn implementation(&self) -> Implementation {
            Implementation::new(
                "compute",
                StageContract {
                    stage: "read_back",
                    slots: vec![
                        Slot::texture("picture", Access::Sampled, None, ""),
                        Slot::buffer("texels", Access::StorageWrite, Element::U32, ""),
                    ],
                },
            )
        }
        fn setup(&self, ctx: &mut SetupContext) -> Result<()> {
            let layout = BindingLayout::compute("read_back")
                .slot(3, "picture")
                .slot(4, "texels");
            ctx.program(
                "read_back",
                ProgramDesc::compute(&KERNELS, "read_back").layout(layout),
            );
            Ok(())
        }
        fn record(&self, ctx: &mut RecordContext<'_>) -> Result<()> {
            dispatch_once(ctx, "read_back", &[], [SIDE / 8, SIDE / 8, 1])
        }
    }
    g.add_pass(
        "read_back",
        ReadBack,
        Bindings::new()
            .bind("picture", picture)
            .bind("texels", texels),
    )
    .unwrap();
    let compiled = g.compile(&CompileOptions::for_gpu(&gpu())).unwrap();
    let kinds: Vec<bool> = compiled.plan.batches.iter().map(|b| b.compute).collect();
    assert_eq!(kinds, [true, false, true]);
    let extra = [("texels", (SIDE * SIDE) as u64)];
    let (_, _, batched) = run(&compiled, true, 1, &extra);
    let (_, _, unbatched) = run(&compiled, false, 1, &extra);
    assert!(batched[0].iter().all(|&t| t == 7), "{:?}", &batched[0][..4]);
    assert_eq!(batched, unbatched);
}

#[test]
fn a_readback_between_compute_passes_returns_each_frames_value() {
    let mut g = GraphBuilder::new();
    let data = g.import_buffer("data", BufferDesc::array(Element::U32, N as u64), USAGE);
    let data = step_on(&mut g, "before", Step { k: 2, clear: false }, data);
    g.readback("snapshot", data, Some(0..16), 1).unwrap();
    step_on(&mut g, "after", Step { k: 1, clear: false }, data);
    let compiled = g.compile(&CompileOptions::for_gpu(&gpu())).unwrap();
    let kinds: Vec<bool> = compiled.plan.batches.iter().map(|b| b.compute).collect();
    assert_eq!(kinds, [true, false, true]);
    for batching in [true, false] {
        let gpu = gpu();
        let start = start_words();
        let buffer = gpu.buffer_with_data("data", bytemuck::cast_slice(&start), USAGE);
        let imports = Imports::new().buffer("data", &buffer);
        let mut exec = Executor::new(gpu);
        exec.batching = batching;
        let mut want = start[..4].to_vec();
        let mut expected = Vec::new();
        for _ in 0..4 {
            want = cpu_steps(&want, &[2]);
            expected.push(want.clone());
            want = cpu_steps(&want, &[1]);
            exec.execute(&compiled, &imports).unwrap();
        }
        exec.finish().unwrap();
        let mut got = Vec::new();
        while let Some(r) = exec.take_readback("snapshot").unwrap() {
            got.push(bytemuck::pod_collect_to_vec::<u8, u32>(&r.bytes));
        }
        assert_eq!(got, expected, "batching {batching}");
    }
}

/// A readback moves as late as its edges allow: past passes that do not write what it
/// copies, to just before the next writer of its source, or to the end; and its values
/// are still those of the version it names.
#[test]
fn readbacks_are_recorded_as_late_as_their_source_allows() {
    let mut g = GraphBuilder::new();
    let data = g.import_buffer("data", BufferDesc::array(Element::U32, N as u64), USAGE);
    let other = g.create_buffer("other", BufferDesc::array(Element::U32, N as u64));
    let data = step_on(&mut g, "before", Step { k: 2, clear: false }, data);
    g.readback("early", data, Some(0..16), 1).unwrap();
    let other = step_on(&mut g, "other", Step { k: 5, clear: true }, other);
    g.readback("other", other, Some(0..16), 1).unwrap();
    let other = step_on(&mut g, "other again", Step { k: 6, clear: false }, other);
    g.export(other);
    let data = step_on(&mut g, "after", Step { k: 1, clear: false }, data);
    g.readback("late", data, Some(0..16), 1).unwrap();
    let compiled = g.compile(&CompileOptions::for_gpu(&gpu())).unwrap();
    let plan = &compiled.plan;
    let order: Vec<&str> = plan
        .order
        .iter()
        .map(|&p| plan.passes[p].name.as_str())
        .collect();
    // Declared (and topologically first): before, early, other, readback of other,
    // other again, after, late.
    assert_eq!(
        order,
        [
            "before",
            "other",
            "readback:other",
            "other again",
            "readback:early",
            "after",
            "readback:late"
        ]
    );
    let gpu = gpu();
    let start = start_words();
    let buffer = gpu.buffer_with_data("data", bytemuck::cast_slice(&start), USAGE);
    let mut exec = Executor::new(gpu);
    exec.execute(&compiled, &Imports::new().buffer("data", &buffer))
        .unwrap();
    exec.finish().unwrap();
    let mut words = |name: &str| {
        let r = exec.take_readback(name).unwrap().expect("one frame's copy");
        bytemuck::pod_collect_to_vec::<u8, u32>(&r.bytes)
    };
    assert_eq!(words("early"), cpu_steps(&start[..4], &[2]));
    assert_eq!(words("late"), cpu_steps(&start[..4], &[2, 1]));
    assert_eq!(words("other"), cpu_steps(&[0; 4], &[5]));
}

#[test]
fn history_carries_through_a_batch_from_frame_to_frame() {
    let mut g = GraphBuilder::new();
    let h = g.history_buffer("acc", BufferDesc::array(Element::U32, N as u64));
    // Copies last frame's value where there is one, else starts from zero.
    let carry = pass(
        "carry",
        copy_slots(),
        |_| Ok(()),
        |ctx| {
            if ctx.history_valid("from")? {
                return copy_buffer(ctx);
            }
            let (to, bytes) = ctx.buffer("to")?;
            ctx.encoder().clear_buffer(to, 0, Some(bytes));
            Ok(())
        },
    );
    let bindings = Bindings::new().bind("from", h.prev).bind("to", h.current);
    let acc = add_writer(&mut g, "carry", carry, bindings, "to");
    let acc = step_on(&mut g, "a", Step { k: 1, clear: false }, acc);
    step_on(&mut g, "b", Step { k: 2, clear: false }, acc);
    let compiled = g.compile(&CompileOptions::for_gpu(&gpu())).unwrap();
    let shape = batch_shape(&compiled);
    assert_eq!(shape, [(1, false), (2, true)]);
    for batching in [true, false] {
        let mut exec = Executor::new(gpu());
        exec.batching = batching;
        let mut want = 0u32;
        for frame in 0..4 {
            exec.execute(&compiled, &Imports::new()).unwrap();
            want = cpu_steps(&[want], &[1, 2])[0];
            let case = format!("batching {batching}, frame {frame}");
            support::assert_every_word(&mut exec, "acc", want, &case);
        }
    }
}

#[test]
fn checked_mode_names_the_pass_that_fails_validation_inside_a_batch() {
    let mut g = chain(&[1, 2]);
    g.add_pass("too_big", Oversized, Bindings::new()).unwrap();
    g.add_pass("step_after", Step { k: 3, clear: false }, Bindings::new())
        .unwrap();
    let compiled = g.compile(&CompileOptions::for_gpu(&gpu())).unwrap();
    assert_eq!(compiled.plan.batches.len(), 1);
    for checked in [true, false] {
        let gpu = gpu();
        let data = gpu.buffer_with_data("data", &[0u8; N as usize * 4], USAGE);
        let mut exec = Executor::new(gpu);
        exec.checked = checked;
        match exec.execute(&compiled, &Imports::new().buffer("data", &data)) {
            Err(GraphError::Validation { pass, message }) if checked => {
                assert_eq!(pass, "too_big");
                assert!(!message.is_empty());
            }
            // Unchecked, the frame fails as a whole and the error says how to name the pass.
            Err(e @ GraphError::FrameValidation { .. }) if !checked => {
                assert!(e.to_string().contains("checked = true"), "{e}");
            }
            other => panic!(
                "expected a validation error, got {:?}",
                other.map(|s| s.frame)
            ),
        }
    }
}

#[test]
fn a_batched_pass_that_takes_the_encoder_is_an_error_when_checked_and_right_when_not() {
    let mut g = chain(&[4]);
    g.add_pass("sneaky", sneaky_clear(), Bindings::new())
        .unwrap();
    g.add_pass("step_after", Step { k: 6, clear: false }, Bindings::new())
        .unwrap();
    let compiled = g.compile(&CompileOptions::for_gpu(&gpu())).unwrap();
    assert_eq!(
        compiled.plan.batches.len(),
        1,
        "compile sees no encoder use"
    );
    let gpu = gpu();
    let data = gpu.buffer_with_data("data", &[1u8; N as usize * 4], USAGE);
    let imports = Imports::new().buffer("data", &data);
    let mut exec = Executor::new(gpu);
    exec.batching = true;
    exec.checked = true;
    match exec.execute(&compiled, &imports) {
        Err(GraphError::Record { pass, message }) => {
            assert_eq!(pass, "sneaky");
            assert!(message.contains("needs_encoder"), "{message}");
        }
        other => panic!("expected a record error, got {:?}", other.map(|s| s.frame)),
    }
    exec.checked = false;
    let stats = exec.execute(&compiled, &imports).unwrap();
    assert_eq!(stats.unplanned_splits, 1);
    assert_eq!(stats.compute_passes, 2);
    exec.finish().unwrap();
    let got = support::read_u32s(&exec.gpu, &data, N as usize);
    assert!(got.iter().all(|&x| x == 6), "{:?}", &got[..4]);
}

#[test]
fn needs_encoder_takes_a_pass_out_of_its_batch() {
    let declared = pass(
        "sneaky",
        data_slot(),
        |ctx| {
            ctx.needs_encoder("clears with clear_buffer");
            Ok(())
        },
        clear_data,
    );
    let mut g = chain(&[4]);
    g.add_pass("declared", declared, Bindings::new()).unwrap();
    g.add_pass("step_after", Step { k: 6, clear: false }, Bindings::new())
        .unwrap();
    let compiled = g.compile(&CompileOptions::for_gpu(&gpu())).unwrap();
    let p = compiled.plan.pass_index("declared").unwrap();
    assert_eq!(
        compiled.plan.passes[p].recording,
        Recording::Encoder("clears with clear_buffer".into())
    );
    assert_eq!(compiled.plan.batches.len(), 3);
    let (got, stats, _) = run(&compiled, true, 1, &[]);
    assert_eq!(stats.unplanned_splits, 0);
    assert!(got.iter().all(|&x| x == 6));
}

#[test]
fn frame_timing_gives_a_time_per_batch_and_passes_timing_one_per_pass() {
    let compiled = chain(&[1, 2, 3])
        .compile(&CompileOptions::for_gpu(&gpu()))
        .unwrap();
    let gpu = gpu();
    if !gpu.features.contains(wgpu::Features::TIMESTAMP_QUERY) {
        panic!("the adapter has no TIMESTAMP_QUERY; this test needs one that has (lavapipe does)");
    }
    let data = gpu.buffer_with_data("data", &[0u8; N as usize * 4], USAGE);
    let imports = Imports::new().buffer("data", &data);
    let mut exec = Executor::new(gpu);
    exec.timing = TimingMode::Frame;
    exec.execute(&compiled, &imports).unwrap();
    let stats = exec.finish().unwrap().unwrap();
    assert_eq!(stats.timing, TimingMode::Frame);
    assert_eq!(stats.batches.len(), 1);
    assert!(stats.batches[0].gpu_us.is_some());
    assert!(stats.gpu_frame_us.is_some());
    assert!(stats.passes.iter().all(|p| p.gpu_us.is_none()));
    let timings = exec.take_gpu_timings().unwrap();
    assert_eq!(timings.last().unwrap().passes.len(), 1);

    for inside in [true, false] {
        exec.timing = TimingMode::Passes;
        exec.stamp_inside_passes = inside;
        exec.execute(&compiled, &imports).unwrap();
        let stats = exec.finish().unwrap().unwrap();
        assert_eq!(stats.timing, TimingMode::Passes);
        assert!(stats.passes.iter().all(|p| p.gpu_us.is_some()));
        let t = exec.take_gpu_timings().unwrap();
        let names: Vec<&str> = t
            .last()
            .unwrap()
            .passes
            .iter()
            .map(|(n, _)| n.as_str())
            .collect();
        assert_eq!(names, ["step0", "step1", "step2"]);
    }
    exec.timing = TimingMode::Off;
    exec.execute(&compiled, &imports).unwrap();
    exec.finish().unwrap();
    assert!(exec.take_gpu_timings().unwrap().is_empty());
}

#[test]
fn timings_come_back_after_the_mode_changes_and_the_ring_reuses_larger_buffers() {
    // Per-pass timing of a long chain leaves ring buffers larger than a frame-timed
    // frame needs; the frame's timings must still come back from them.
    let ks: Vec<u32> = (0..16).collect();
    let long = chain(&ks)
        .compile(&CompileOptions::for_gpu(&gpu()))
        .unwrap();
    let short = chain(&ks[..2])
        .compile(&CompileOptions::for_gpu(&gpu()))
        .unwrap();
    let gpu = gpu();
    let data = gpu.buffer_with_data("data", &[0u8; N as usize * 4], USAGE);
    let imports = Imports::new().buffer("data", &data);
    let mut exec = Executor::new(gpu);
    exec.timing = TimingMode::Passes;
    for _ in 0..3 {
        exec.execute(&long, &imports).unwrap();
        exec.finish().unwrap();
    }
    assert_eq!(exec.take_gpu_timings().unwrap().len(), 3);
    exec.timing = TimingMode::Frame;
    for _ in 0..3 {
        exec.execute(&short, &imports).unwrap();
        let stats = exec.finish().unwrap().unwrap();
        assert!(stats.gpu_frame_us.is_some());
    }
    let timings = exec.take_gpu_timings().unwrap();
    assert_eq!(timings.len(), 3);
    assert!(
        timings
            .iter()
            .all(|t| t.mode == TimingMode::Frame && t.passes.len() == 1)
    );
}

/// Zeroes its scratch buffer (storage only, no COPY_DST) and steps it: a `clear_buffer`
/// on it would be a validation error, so the clear must be a fill dispatch whether the
/// pass is batched or not. `data` only keeps the pass from being culled.
struct ScratchClear {
    k: u32,
}

impl Pass for ScratchClear {
    fn implementation(&self) -> Implementation {
        Implementation::new(
            "fill",
            StageContract {
                stage: "scratch_clear",
                slots: vec![Slot::buffer("data", Access::StorageWrite, Element::U32, "")],
            },
        )
    }
    fn setup(&self, ctx: &mut SetupContext) -> Result<()> {
        support::scratch_words(ctx, N);
        let on_scratch = BindingLayout::compute("step")
            .scratch(0, "words", Access::StorageReadWrite)
            .uniform(1, "params");
        ctx.program(
            "step",
            ProgramDesc::compute(&KERNELS, "step").layout(on_scratch),
        );
        Ok(())
    }
    fn record(&self, ctx: &mut RecordContext<'_>) -> Result<()> {
        ctx.clear_scratch("words")?;
        step_dispatch(ctx, self.k, N.div_ceil(64))
    }
}

#[test]
fn a_scratch_buffer_without_copy_dst_is_cleared_batched_and_unbatched() {
    let mut g = GraphBuilder::new();
    g.import_buffer("data", BufferDesc::array(Element::U32, N as u64), USAGE);
    g.add_pass("scratch_clear", ScratchClear { k: 5 }, Bindings::new())
        .unwrap();
    let compiled = g.compile(&CompileOptions::for_gpu(&gpu())).unwrap();
    assert!(compiled.plan.batches[0].compute);
    for batching in [true, false] {
        let gpu = gpu();
        let data = gpu.buffer_with_data("data", &[0u8; N as usize * 4], USAGE);
        let mut exec = Executor::new(gpu);
        exec.batching = batching;
        exec.checked = true;
        for _ in 0..2 {
            exec.execute(&compiled, &Imports::new().buffer("data", &data))
                .unwrap_or_else(|e| panic!("batching {batching}: {e}"));
        }
        let r = compiled.plan.resource_index("scratch_clear/words").unwrap();
        assert!(
            !compiled.plan.resources[r]
                .buffer_usage
                .contains(wgpu::BufferUsages::COPY_DST)
        );
    }
}
