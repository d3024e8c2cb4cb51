//! GPU tests of the frame graph's render passes, sub-resources, multi-access slots, frame
//! data, async readback and growth, each against a CPU reference (lavapipe in CI).

mod support;

use meshlight_graph::*;
use support::fake::pass;
use support::rects::*;
use support::{add_exported, compute_once, dispatch_once, gpu, read_export, render_once};

const RASTER: PassShader = support::support_shader!(
    "test::features",
    "features.wgsl",
    modules: [RECT_VERTICES_WGSL]
);
const COMPUTE: PassShader = support::support_shader!("test::compute", "compute.wgsl");

fn params(a: u32, b: u32) -> [u32; 4] {
    [a, b, 0, 0]
}

/// Declares the compute program `name` running `entry` of the test kernels.
fn declare(
    ctx: &mut SetupContext,
    name: &str,
    entry: &'static str,
    layout: BindingLayout,
) -> Result<()> {
    ctx.program(name, ProgramDesc::compute(&COMPUTE, entry).layout(layout));
    Ok(())
}

/// A test pass whose one program `program.0` runs the kernel `program.1` of the test
/// kernels laid out by `layout`: most passes here differ only in those and their record.
fn kernel_pass<R>(
    stage: &'static str,
    slots: Vec<Slot>,
    program: (&'static str, &'static str),
    layout: BindingLayout,
    record: R,
) -> impl Pass + 'static
where
    R: Fn(&mut RecordContext<'_>) -> Result<()> + Send + Sync + 'static,
{
    let (name, entry) = program;
    let setup = move |ctx: &mut SetupContext| declare(ctx, name, entry, layout.clone());
    pass(stage, slots, setup, record)
}

// ---------------------------------------------------------------------------------------
// A render pass with a masked dummy colour target whose fragment shader does a 64-bit
// atomicMax into a storage buffer.

#[test]
fn render_pass_with_a_masked_target_does_64_bit_atomic_max_like_the_cpu() {
    let gpu = gpu();
    let vertices = rect_vertices();
    let vertex_count = vertices.len() as u32;
    let mut g = GraphBuilder::new();
    let rects = import_rect_vertices(&mut g, vertex_count);
    let vis = g.create_buffer("vis", BufferDesc::array(Element::U64, (W * H) as u64));
    let raster = pass(
        "raster",
        vec![
            rects_slot(),
            Slot::buffer("vis", Access::ClearedReadWrite, Element::U64, ""),
        ],
        |ctx| {
            ctx.require_features(
                wgpu::Features::SHADER_INT64 | wgpu::Features::SHADER_INT64_ATOMIC_MIN_MAX,
            );
            let layout = BindingLayout::render("raster")
                .slot(0, "rects")
                .visible_in(wgpu::ShaderStages::VERTEX)
                .slot(1, "vis")
                .visible_in(wgpu::ShaderStages::FRAGMENT)
                .uniform(2, "raster")
                .visible_in(wgpu::ShaderStages::FRAGMENT);
            let program = ProgramDesc::render(&RASTER, "rect_vs").fragment("rect_fs");
            declare_masked_raster(ctx, program.layout(layout));
            Ok(())
        },
        move |ctx| {
            let raster_params = [W, 0, 0, 0, 0, 0, 0, 0];
            let uniforms = [("raster", bytemuck::cast_slice(&raster_params))];
            record_masked_raster(ctx, &uniforms, |rp| rp.draw(0..vertex_count, 0..1))
        },
    );
    add_exported(
        &mut g,
        "raster",
        raster,
        Bindings::new().bind("rects", rects).bind("vis", vis),
        "vis",
    );
    let compiled = g.compile(&CompileOptions::for_gpu(&gpu)).unwrap();
    // The dummy target is cleared and never stored; the visibility buffer reads nothing.
    let plan = &compiled.plan;
    let dummy = plan.resource_index("raster/dummy").unwrap();
    assert_eq!(
        plan.resources[dummy].texture_usage,
        wgpu::TextureUsages::RENDER_ATTACHMENT
    );
    assert!(plan.edges.is_empty(), "{:?}", plan.edges);
    let dot = dump::to_dot(plan);
    assert!(dot.contains("vis: cleared-read-write"), "{dot}");

    // Twice: the second frame must clear what the first left.
    let rects = bytemuck::cast_slice(&vertices);
    let mut exec = support::run_frames(gpu, &compiled, ("rects", rects), 2);
    let got: Vec<u64> = read_export(&mut exec, "vis");
    let want = cpu_rects();
    let wrong = got.iter().zip(&want).filter(|(a, b)| a != b).count();
    assert_eq!(wrong, 0, "{wrong} of {} pixels differ", want.len());
    assert!(
        want.iter().any(|&k| k >> 32 == 300),
        "the reference covers the top rectangle"
    );
}

// ---------------------------------------------------------------------------------------
// A mip chain built within one frame through per-mip views, read back through a sampler.

const MIP_W: u32 = 37;
const MIP_H: u32 = 23;

/// A slot on an `R32Float` texture (the mip chain's format).
fn r32f(name: &'static str, access: Access) -> Slot {
    Slot::texture(name, access, Some(wgpu::TextureFormat::R32Float), "")
}

fn cpu_pyramid(base: &[f32]) -> Vec<Vec<f32>> {
    let desc = TextureDesc::d2(wgpu::TextureFormat::R32Float, MIP_W, MIP_H).with_full_mips();
    let mut mips = vec![base.to_vec()];
    for level in 1..desc.mip_levels {
        let (sw, sh) = desc.mip_size(level - 1);
        let (dw, dh) = desc.mip_size(level);
        let src = &mips[level as usize - 1];
        let mut dst = vec![0f32; (dw * dh) as usize];
        for y in 0..dh {
            for x in 0..dw {
                let x_end = if x == dw - 1 && sw % 2 == 1 {
                    sw
                } else {
                    x * 2 + 2
                };
                let y_end = if y == dh - 1 && sh % 2 == 1 {
                    sh
                } else {
                    y * 2 + 2
                };
                let mut m = f32::MAX;
                for sy in y * 2..y_end.min(sh) {
                    for sx in x * 2..x_end.min(sw) {
                        m = m.min(src[(sy * sw + sx) as usize]);
                    }
                }
                dst[(y * dw + x) as usize] = m;
            }
        }
        mips.push(dst);
    }
    mips
}

#[test]
fn a_mip_chain_built_in_one_frame_equals_the_cpu_min_reduction() {
    let gpu = gpu();
    let desc = TextureDesc::d2(wgpu::TextureFormat::R32Float, MIP_W, MIP_H).with_full_mips();
    let levels = desc.mip_levels;
    assert_eq!(levels, 6);
    let base: Vec<f32> = (0..MIP_W * MIP_H)
        .map(|i| ((i * 7919) % 1000) as f32 / 7.0)
        .collect();
    let total: u64 = (0..levels)
        .map(|l| {
            let (w, h) = desc.mip_size(l);
            (w * h) as u64
        })
        .sum();

    let mut g = GraphBuilder::new();
    let source = g.import_buffer(
        "source",
        BufferDesc::array(Element::F32, base.len() as u64),
        wgpu::BufferUsages::STORAGE,
    );
    let mut pyramid = g.create_texture("pyramid", desc.clone());
    let base_pass = kernel_pass(
        "base",
        vec![
            Slot::buffer("source", Access::StorageRead, Element::F32, ""),
            r32f("mip", Access::StorageWrite),
        ],
        ("base", "write_base"),
        BindingLayout::compute("base")
            .slot(0, "source")
            .slot(1, "mip"),
        |ctx| dispatch_once(ctx, "base", &[], [MIP_W.div_ceil(8), MIP_H.div_ceil(8), 1]),
    );
    pyramid = g
        .add_pass(
            "base",
            base_pass,
            Bindings::new()
                .bind("source", source)
                .bind_range("mip", pyramid, TextureRange::mip(0)),
        )
        .unwrap()
        .texture("mip")
        .unwrap();
    for level in 1..levels {
        let (dw, dh) = desc.mip_size(level);
        let down = kernel_pass(
            "downsample",
            vec![
                r32f("src", Access::Sampled),
                r32f("dst", Access::StorageWrite),
            ],
            ("downsample", "downsample"),
            BindingLayout::compute("downsample")
                .slot(3, "src")
                .slot(4, "dst"),
            move |ctx| dispatch_once(ctx, "downsample", &[], [dw.div_ceil(8), dh.div_ceil(8), 1]),
        );
        pyramid = g
            .add_pass(
                &format!("mip{level}"),
                down,
                Bindings::new()
                    .bind_range("src", pyramid, TextureRange::mip(level - 1))
                    .bind_range("dst", pyramid, TextureRange::mip(level)),
            )
            .unwrap()
            .texture("dst")
            .unwrap();
    }
    let gathered = g.create_buffer("gathered", BufferDesc::array(Element::F32, total));
    let gather = kernel_pass(
        "gather",
        vec![
            Slot::texture("pyramid", Access::Sampled, None, ""),
            Slot::buffer("gathered", Access::StorageWrite, Element::F32, ""),
        ],
        ("gather", "gather"),
        BindingLayout::compute("gather")
            .uniform(2, "params")
            .slot(5, "pyramid")
            .sampler(6, SamplerKind::Nearest)
            .slot(7, "gathered"),
        move |ctx| {
            let desc = match ctx.desc("pyramid")? {
                ResourceDesc::Texture(t) => t.clone(),
                ResourceDesc::Buffer(_) => unreachable!("checked by the contract"),
            };
            let p = ctx.compute("gather")?;
            let mut offset = 0;
            let mut groups = Vec::new();
            for level in 0..desc.mip_levels {
                let (w, h) = desc.mip_size(level);
                let bg = ctx.bind_group(
                    &p,
                    0,
                    &[("params", bytemuck::cast_slice(&params(level, offset)))],
                )?;
                groups.push((bg, (w * h).div_ceil(64)));
                offset += w * h;
            }
            let mut cp = ctx.compute_pass();
            cp.set_pipeline(&p.pipeline);
            for (bg, n) in &groups {
                cp.set_bind_group(0, bg, &[]);
                cp.dispatch_workgroups(*n, 1, 1);
            }
            Ok(())
        },
    );
    add_exported(
        &mut g,
        "gather",
        gather,
        Bindings::new()
            .bind("pyramid", pyramid)
            .bind("gathered", gathered),
        "gathered",
    );
    let compiled = g.compile(&CompileOptions::for_gpu(&gpu)).unwrap();
    let plan = &compiled.plan;
    assert_eq!(plan.order.len(), levels as usize + 1);
    let mip2 = &plan.passes[plan.pass_index("mip2").unwrap()];
    assert_eq!(
        mip2.slots[0].range,
        Some(TextureRange::mip(1).resolve(&desc))
    );
    assert!(dump::to_dot(plan).contains("dst: storage-write [mip 2]"));

    let source = bytemuck::cast_slice(&base);
    let mut exec = support::run_frames(gpu, &compiled, ("source", source), 1);
    let got: Vec<f32> = read_export(&mut exec, "gathered");
    let want: Vec<f32> = cpu_pyramid(&base).concat();
    assert_eq!(got.len(), want.len());
    assert_eq!(got, want);
}

// ---------------------------------------------------------------------------------------
// A buffer cleared and appended to in one pass, used as indirect arguments in that pass
// and by the next; storage and indirect in one dispatch.

#[test]
fn appended_buffer_drives_indirect_dispatches_in_its_own_pass_and_the_next() {
    const N: u32 = 1000;
    let gpu = gpu();
    let mut g = GraphBuilder::new();
    let args = g.create_buffer("args", BufferDesc::array(Element::U32, 4));
    let items = g.create_buffer("items", BufferDesc::array(Element::U32, N as u64));
    let marks = g.create_buffer("marks", BufferDesc::array(Element::U32, N as u64));
    let seen = g.create_buffer("seen", BufferDesc::array(Element::U32, N as u64));
    let append = pass(
        "append",
        vec![
            Slot::buffer("args", Access::ClearedReadWrite, Element::U32, "").also(Access::Indirect),
            Slot::buffer("items", Access::StorageWrite, Element::U32, ""),
            Slot::buffer("marks", Access::ClearedReadWrite, Element::U32, ""),
        ],
        |ctx| {
            let append = BindingLayout::compute("append")
                .uniform(2, "params")
                .slot(8, "args")
                .slot(9, "items");
            let mark = BindingLayout::compute("mark")
                .uniform(2, "params")
                .slot(10, "items")
                .read_only()
                .slot(11, "marks");
            ctx.program(
                "append",
                ProgramDesc::compute(&COMPUTE, "append").layout(append),
            );
            declare(ctx, "mark", "mark", mark)
        },
        |ctx| {
            ctx.clear("args")?;
            ctx.clear("marks")?;
            let append = ctx.compute("append")?;
            let mark = ctx.compute("mark")?;
            let p = params(N, 6);
            let a = ctx.bind_group(&append, 0, &[("params", bytemuck::cast_slice(&p))])?;
            let m = ctx.bind_group(&mark, 0, &[("params", bytemuck::cast_slice(&p))])?;
            let (args, _) = ctx.buffer("args")?;
            let mut cp = ctx.compute_pass();
            cp.set_pipeline(&append.pipeline);
            cp.set_bind_group(0, &a, &[]);
            cp.dispatch_workgroups(N.div_ceil(64), 1, 1);
            cp.set_pipeline(&mark.pipeline);
            cp.set_bind_group(0, &m, &[]);
            cp.dispatch_workgroups_indirect(args, 0);
            Ok(())
        },
    );
    let out = g
        .add_pass(
            "append",
            append,
            Bindings::new()
                .bind("args", args)
                .bind("items", items)
                .bind("marks", marks),
        )
        .unwrap();
    let args = out.buffer("args").unwrap();
    g.export(out.buffer("marks").unwrap());
    let count = kernel_pass(
        "count",
        vec![
            Slot::buffer("args", Access::StorageRead, Element::U32, "").also(Access::Indirect),
            Slot::buffer("seen", Access::ClearedReadWrite, Element::U32, ""),
        ],
        ("count", "count_groups"),
        BindingLayout::compute("count")
            .slot(12, "args")
            .slot(13, "seen"),
        |ctx| {
            ctx.clear("seen")?;
            let (args, _) = ctx.buffer("args")?;
            ctx.dispatch_compute("count", &[], Workgroups::Indirect(args, 0))
        },
    );
    add_exported(
        &mut g,
        "count",
        count,
        Bindings::new().bind("args", args).bind("seen", seen),
        "seen",
    );
    let compiled = g.compile(&CompileOptions::for_gpu(&gpu)).unwrap();
    let plan = &compiled.plan;
    let args_plan = &plan.resources[plan.resource_index("args").unwrap()];
    assert!(args_plan.buffer_usage.contains(
        wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::INDIRECT | wgpu::BufferUsages::COPY_DST
    ));
    assert!(dump::to_dot(plan).contains("args: cleared-read-write+indirect"));

    let mut exec = Executor::new(gpu);
    for _ in 0..2 {
        exec.execute(&compiled, &Imports::new()).unwrap();
    }
    let appended = N.div_ceil(3);
    let marks: Vec<u32> = read_export(&mut exec, "marks");
    for (i, m) in marks.iter().enumerate() {
        assert_eq!(*m, if i % 3 == 0 { 7 } else { 0 }, "mark {i}");
    }
    let seen: Vec<u32> = read_export(&mut exec, "seen");
    for (i, s) in seen.iter().enumerate() {
        let want = if (i as u32) < appended {
            appended * 1000 + i as u32
        } else {
            0
        };
        assert_eq!(*s, want, "group {i}");
    }
}

// ---------------------------------------------------------------------------------------
// Frame data: 100 frames with new values and no recompile; async readback with latency.

/// A pass writing `[frame input value, frame index]` to its `stamp` buffer.
fn stamp_pass() -> impl Pass {
    pass(
        "stamp",
        vec![Slot::buffer(
            "stamp",
            Access::StorageWrite,
            Element::U32,
            "",
        )],
        |ctx| {
            ctx.frame_input("value");
            let layout = BindingLayout::compute("stamp")
                .uniform(2, "params")
                .slot(14, "stamp");
            declare(ctx, "stamp", "write_stamp", layout)
        },
        |ctx| {
            let value = ctx.frame_u32("value")?;
            let frame = ctx.frame_index() as u32;
            dispatch_once(
                ctx,
                "stamp",
                &[("params", bytemuck::cast_slice(&params(value, frame)))],
                [1, 1, 1],
            )
        },
    )
}

fn stamp_graph(latency: u32) -> CompiledGraph {
    let mut g = GraphBuilder::new();
    let stamp = g.create_buffer("stamp", BufferDesc::array(Element::U32, 2));
    let writer = stamp_pass();
    let out = g
        .add_pass("stamp", writer, Bindings::new().bind("stamp", stamp))
        .unwrap();
    let stamp = out.buffer("stamp").unwrap();
    g.export(stamp);
    g.readback("stamp", stamp, None, latency).unwrap();
    g.compile(&CompileOptions::new(wgpu::Features::empty()))
        .unwrap()
}

/// A warmed-up frame of a steady graph: no resource, pipeline or bind group was made.
fn assert_created_nothing(stats: &FrameStats, frame: u32) {
    assert_eq!(
        (
            stats.allocations,
            stats.pipelines_created,
            stats.bind_groups_created
        ),
        (0, 0, 0),
        "frame {frame}"
    );
}

#[test]
fn frame_data_changes_every_frame_without_recompiling_or_allocating() {
    let compiled = stamp_graph(1);
    let mut exec = Executor::new(gpu());
    let mut data = FrameData::new();
    for f in 0..100u32 {
        data.set_u32("value", 7919 * f + 3);
        let stats = exec
            .execute_frame(&compiled, &Imports::new(), &data)
            .unwrap();
        if f > 0 {
            assert_created_nothing(&stats, f);
        }
        if f % 10 == 9 {
            let got: Vec<u32> = read_export(&mut exec, "stamp");
            assert_eq!(got, [7919 * f + 3, f], "frame {f}");
        }
    }
    // A frame without the input is an error naming the pass and the input.
    assert_missing_input(exec.execute(&compiled, &Imports::new()), "stamp", "value");
}

/// `frame` failed for want of frame input `input` of pass `pass`.
fn assert_missing_input(frame: Result<FrameStats>, pass: &str, input: &str) {
    match frame {
        Err(GraphError::MissingFrameInput { pass: p, input: i }) => {
            assert_eq!((p.as_str(), i.as_str()), (pass, input))
        }
        other => panic!("{:?}", other.map(|s| s.frame)),
    }
}

/// Three passes of one stage, each supplied its own frame input for the `value` it
/// reads (`Bindings::input`): the way a stage runs once per view of a frame.
#[test]
fn each_pass_reads_the_frame_input_supplied_for_it() {
    let mut g = GraphBuilder::new();
    for k in 0..3 {
        let stamp = g.create_buffer(&format!("stamp_{k}"), BufferDesc::array(Element::U32, 2));
        let writer = stamp_pass();
        let bindings = Bindings::new()
            .bind("stamp", stamp)
            .input("value", &format!("value_{k}"));
        let out = g.add_pass(&format!("stamp_{k}"), writer, bindings).unwrap();
        g.export(out.buffer("stamp").unwrap());
    }
    let compiled = g
        .compile(&CompileOptions::new(wgpu::Features::empty()))
        .unwrap();
    let inputs: Vec<&[String]> = (compiled.plan.passes.iter())
        .map(|p| p.frame_inputs.as_slice())
        .collect();
    assert_eq!(inputs, [["value_0"], ["value_1"], ["value_2"]]);
    let mut exec = Executor::new(gpu());
    let mut data = FrameData::new();
    for k in 0..3 {
        data.set_u32(&format!("value_{k}"), 100 + k);
    }
    exec.execute_frame(&compiled, &Imports::new(), &data)
        .unwrap();
    for k in 0..3u32 {
        let got: Vec<u32> = read_export(&mut exec, &format!("stamp_{k}"));
        assert_eq!(got, [100 + k, 0], "pass {k}");
    }
    // A frame without one of them names the input supplied, not the one read.
    let mut partial = FrameData::new();
    partial.set_u32("value_0", 1).set_u32("value_1", 2);
    assert_missing_input(
        exec.execute_frame(&compiled, &Imports::new(), &partial),
        "stamp_2",
        "value_2",
    );
}

/// Supplying an input the pass never reads is a compile error naming what it reads.
#[test]
fn supplying_an_input_the_pass_does_not_read_is_refused() {
    let mut g = GraphBuilder::new();
    let stamp = g.create_buffer("stamp", BufferDesc::array(Element::U32, 2));
    let writer = pass(
        "stamp",
        vec![Slot::buffer(
            "stamp",
            Access::StorageWrite,
            Element::U32,
            "",
        )],
        |ctx| {
            ctx.frame_input("value");
            Ok(())
        },
        |_| Ok(()),
    );
    let bindings = Bindings::new().bind("stamp", stamp).input("viwe", "view_0");
    let out = g.add_pass("stamp", writer, bindings).unwrap();
    g.export(out.buffer("stamp").unwrap());
    let Err(e) = g.compile(&CompileOptions::new(wgpu::Features::empty())) else {
        panic!("a graph supplying an input its pass does not read compiled");
    };
    let e = e.to_string();
    assert!(
        e.contains("reads no frame input `viwe` (it reads: value)"),
        "{e}"
    );
}

#[test]
fn readback_of_frame_k_is_taken_at_frame_k_plus_latency_without_waiting() {
    const LATENCY: u32 = 2;
    const FRAMES: u32 = 100;
    let compiled = stamp_graph(LATENCY);
    let mut exec = Executor::new(gpu());
    let mut data = FrameData::new();
    let mut taken: Vec<(u64, u64)> = Vec::new();
    for f in 0..FRAMES {
        data.set_u32("value", 1000 + f);
        exec.execute_frame(&compiled, &Imports::new(), &data)
            .unwrap();
        while let Some(r) = exec.take_readback("stamp").unwrap() {
            let words: Vec<u32> = bytemuck::pod_collect_to_vec(&r.bytes);
            assert_eq!(words, [1000 + r.frame as u32, r.frame as u32]);
            taken.push((r.frame, f as u64));
        }
    }
    assert_eq!(
        exec.blocking_waits, 0,
        "no frame or take waited for the GPU"
    );
    assert_eq!(exec.readbacks_dropped(), 0);
    for &(k, at) in &taken {
        assert!(at >= k + LATENCY as u64, "frame {k} taken at {at}");
    }
    // Before the wait the last `LATENCY` frames are still held back; once `finish` has
    // drained the GPU every frame has come back, in order, the last ones included.
    let before: Vec<u64> = taken.iter().map(|(k, _)| *k).collect();
    assert!(before.iter().all(|&k| k < (FRAMES - LATENCY) as u64));
    exec.finish().unwrap();
    while let Some(r) = exec.take_readback("stamp").unwrap() {
        let words: Vec<u32> = bytemuck::pod_collect_to_vec(&r.bytes);
        assert_eq!(words, [1000 + r.frame as u32, r.frame as u32]);
        taken.push((r.frame, FRAMES as u64));
    }
    let frames: Vec<u64> = taken.iter().map(|(k, _)| *k).collect();
    let want: Vec<u64> = (0..FRAMES as u64).collect();
    assert_eq!(frames, want);
}

// ---------------------------------------------------------------------------------------
// Growth: a size parameter raised at run time.

#[test]
fn raising_a_size_parameter_resizes_transients_and_history_and_frees_the_old_objects() {
    let mut g = GraphBuilder::new();
    g.size_param("slots", 1024);
    let list = g.create_buffer("list", BufferDesc::array_param(Element::U32, "slots"));
    let hist = g.history_buffer("hist", BufferDesc::array_param(Element::U32, "slots"));
    let grow = kernel_pass(
        "grow",
        vec![
            Slot::buffer("list", Access::StorageWrite, Element::U32, ""),
            Slot::buffer("prev", Access::StorageRead, Element::U32, ""),
            Slot::buffer("hist", Access::StorageWrite, Element::U32, ""),
        ],
        ("grow", "grow"),
        BindingLayout::compute("grow")
            .uniform(2, "params")
            .slot(15, "list")
            .slot(16, "prev")
            .slot(17, "hist"),
        |ctx| {
            let (_, bytes) = ctx.buffer("list")?;
            let n = (bytes / 4) as u32;
            let valid = ctx.history_valid("prev")? as u32;
            dispatch_once(
                ctx,
                "grow",
                &[("params", bytemuck::cast_slice(&params(n, valid)))],
                [n.div_ceil(64), 1, 1],
            )
        },
    );
    add_exported(
        &mut g,
        "grow",
        grow,
        Bindings::new()
            .bind("list", list)
            .bind("prev", hist.prev)
            .bind("hist", hist.current),
        "list",
    );
    let mut compiled = g
        .compile(&CompileOptions::new(wgpu::Features::empty()))
        .unwrap();
    let mut exec = Executor::new(gpu());
    for _ in 0..3 {
        exec.execute(&compiled, &Imports::new()).unwrap();
    }
    let small_pool = exec.pool_bytes_held();
    assert_eq!(small_pool, 1024 * 4);
    let hist3: Vec<u32> = read_export(&mut exec, "hist");
    assert_eq!((hist3.len(), hist3[0], hist3[1023]), (1024, 3, 3));

    compiled.set_param("slots", 16384).unwrap();
    assert_eq!(compiled.param("slots"), Some(16384));
    assert_eq!(compiled.plan.bytes_with_reuse, 16384 * 4);
    let stats = exec.execute(&compiled, &Imports::new()).unwrap();
    assert!(stats.allocations > 0);
    let list: Vec<u32> = read_export(&mut exec, "list");
    assert_eq!(list.len(), 16384);
    assert!(list.iter().enumerate().all(|(i, &v)| v == i as u32 * 2 + 1));
    // History was resized and restarted: `prev` held nothing from before the resize.
    let hist: Vec<u32> = read_export(&mut exec, "hist");
    assert_eq!(hist.len(), 16384);
    assert!(hist.iter().all(|&v| v == 1), "{:?}", &hist[..4]);
    assert_eq!(exec.pool_bytes_held(), small_pool + 16384 * 4);
    for _ in 0..4 {
        exec.execute(&compiled, &Imports::new()).unwrap();
    }
    assert_eq!(exec.pool_bytes_held(), 16384 * 4, "the old list was freed");
    let hist: Vec<u32> = read_export(&mut exec, "hist");
    assert!(hist.iter().all(|&v| v == 5));
}

// ---------------------------------------------------------------------------------------
// Immediates, natively and through the uniform fallback.

const IMMEDIATE_SHADER: PassShader = PassShader {
    name: "test::immediates",
    source: r#"
struct Block {
    // Value written to every element.
    value: u32,
    // Elements to write.
    count: u32,
}
#ifdef IMMEDIATES
var<immediate> block: Block;
#else
@group(1) @binding(0) var<uniform> block: Block;
#endif
@group(0) @binding(0) var<storage, read_write> out: array<u32>;

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x < block.count {
        out[id.x] = block.value + id.x;
    }
}
"#,
    file_path: "graph/tests/gpu_features.rs",
    modules: &[],
};

fn run_immediates(features: wgpu::Features) -> (bool, Vec<u32>) {
    let gpu = GpuContext::with_available(features).unwrap();
    let native = gpu.features.contains(wgpu::Features::IMMEDIATES);
    let mut g = GraphBuilder::new();
    let out = g.create_buffer("out", BufferDesc::array(Element::U32, 100));
    let p = pass(
        "imm",
        vec![Slot::buffer("out", Access::StorageWrite, Element::U32, "")],
        |ctx| {
            ctx.program(
                "main",
                ProgramDesc::compute(&IMMEDIATE_SHADER, "main")
                    .layout(BindingLayout::compute("imm").slot(0, "out"))
                    .immediates(8),
            );
            Ok(())
        },
        |ctx| {
            let p = ctx.compute("main")?;
            let imm = ctx.immediates(&p, bytemuck::cast_slice(&[500u32, 100]))?;
            compute_once(ctx, "main", &[], |cp| {
                imm.set_on_compute(cp);
                cp.dispatch_workgroups(2, 1, 1);
            })
        },
    );
    let o = g
        .add_pass("imm", p, Bindings::new().bind("out", out))
        .unwrap();
    g.export(o.buffer("out").unwrap());
    let compiled = g.compile(&CompileOptions::for_gpu(&gpu)).unwrap();
    let mut exec = Executor::new(gpu);
    exec.execute(&compiled, &Imports::new()).unwrap();
    (native, read_export(&mut exec, "out"))
}

#[test]
fn immediates_reach_the_shader_natively_and_through_the_uniform_fallback() {
    let want: Vec<u32> = (0..100).map(|i| 500 + i).collect();
    let (native, got) = run_immediates(wgpu::Features::all());
    eprintln!(
        "immediates: {}",
        if native {
            "native"
        } else {
            "uniform fallback only"
        }
    );
    assert_eq!(got, want, "native = {native}");
    let (native, got) = run_immediates(wgpu::Features::all() - wgpu::Features::IMMEDIATES);
    assert!(!native);
    assert_eq!(got, want, "uniform fallback");
}

// ---------------------------------------------------------------------------------------
// Defects that used to panic or churn.

#[test]
fn an_allocation_the_device_refuses_is_an_error_naming_the_resource() {
    let gpu = gpu();
    let too_big = gpu.device.limits().max_buffer_size + 4096;
    let mut g = GraphBuilder::new();
    let big = g.create_buffer("big", BufferDesc::array(Element::BYTES, too_big));
    let writer = pass(
        "fill",
        vec![Slot::buffer("big", Access::CopyDst, Element::BYTES, "")],
        |_| Ok(()),
        |_| Ok(()),
    );
    add_exported(
        &mut g,
        "fill",
        writer,
        Bindings::new().bind("big", big),
        "big",
    );
    // Options that claim more than the device has, so compile lets the buffer through.
    let generous = wgpu::Limits {
        max_buffer_size: u64::MAX,
        ..gpu.device.limits()
    };
    let compiled = g
        .compile(&CompileOptions::for_gpu(&gpu).with_limits(generous))
        .unwrap();
    let mut exec = Executor::new(gpu);
    match exec.execute(&compiled, &Imports::new()) {
        Err(GraphError::Allocation { resource, message }) => {
            assert!(resource.contains("big"), "{resource}");
            assert!(!message.is_empty());
        }
        other => panic!("{:?}", other.map(|s| s.frame)),
    }
}

fn sampled_import_graph(mips: u32) -> GraphBuilder {
    let mut g = GraphBuilder::new();
    let src = g.import_texture(
        "src",
        TextureDesc::d2(wgpu::TextureFormat::R32Float, 16, 16).with_mips(mips),
        wgpu::TextureUsages::TEXTURE_BINDING,
    );
    let dst = g.create_texture("dst", TextureDesc::d2(wgpu::TextureFormat::R32Float, 8, 8));
    let down = kernel_pass(
        "downsample",
        vec![
            Slot::texture("src", Access::Sampled, None, ""),
            Slot::texture("dst", Access::StorageWrite, None, ""),
        ],
        ("down", "downsample"),
        BindingLayout::compute("downsample")
            .slot(3, "src")
            .slot(4, "dst"),
        |ctx| dispatch_once(ctx, "down", &[], [1, 1, 1]),
    );
    let out = g
        .add_pass(
            "down",
            down,
            Bindings::new()
                .bind_range("src", src, TextureRange::mip(0))
                .bind("dst", dst),
        )
        .unwrap();
    g.export(out.texture("dst").unwrap());
    g
}

fn r32_texture(gpu: &GpuContext, mips: u32) -> wgpu::Texture {
    gpu.device.create_texture(&wgpu::TextureDescriptor {
        label: Some("src"),
        size: wgpu::Extent3d {
            width: 16,
            height: 16,
            depth_or_array_layers: 1,
        },
        mip_level_count: mips,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format: wgpu::TextureFormat::R32Float,
        usage: wgpu::TextureUsages::TEXTURE_BINDING,
        view_formats: &[],
    })
}

/// The one-mip sampled-import graph, compiled, with an executor and a caller texture of
/// `mips` levels to import as `src`.
fn sampled_import_run(mips: u32) -> (CompiledGraph, Executor, wgpu::Texture) {
    let gpu = gpu();
    let texture = r32_texture(&gpu, mips);
    let compiled = sampled_import_graph(1)
        .compile(&CompileOptions::for_gpu(&gpu))
        .unwrap();
    (compiled, Executor::new(gpu), texture)
}

#[test]
fn imported_textures_keep_their_views_and_bind_groups_across_frames() {
    let (compiled, mut exec, texture) = sampled_import_run(1);
    for frame in 0..4 {
        // A fresh `Imports` every frame, as a render loop builds it.
        let stats = exec
            .execute(&compiled, &Imports::new().texture("src", &texture))
            .unwrap();
        if frame > 0 {
            assert_created_nothing(&stats, frame);
        }
    }
}

#[test]
fn an_imported_texture_with_other_mip_counts_is_refused() {
    let (compiled, mut exec, texture) = sampled_import_run(3);
    match exec.execute(&compiled, &Imports::new().texture("src", &texture)) {
        Err(GraphError::ImportMismatch { resource, message }) => {
            assert_eq!(resource, "src");
            assert!(
                message.contains("1 mips") && message.contains("3 mips"),
                "{message}"
            );
        }
        other => panic!("{:?}", other.map(|s| s.frame)),
    }
}

// ---------------------------------------------------------------------------------------
// Texture arrays: each layer written through its own one-layer view.

#[test]
fn layers_of_a_texture_array_are_written_through_their_own_views() {
    const LAYERS: u32 = 3;
    const SIDE: u32 = 8;
    let gpu = gpu();
    let mut g = GraphBuilder::new();
    let desc = TextureDesc::d2(wgpu::TextureFormat::R32Float, SIDE, SIDE).with_layers(LAYERS);
    let mut array = g.create_texture("array", desc);
    for layer in 0..LAYERS {
        let fill = kernel_pass(
            "fill_layer",
            vec![Slot::texture("layer", Access::StorageWrite, None, "")],
            ("fill", "fill_layer"),
            BindingLayout::compute("fill_layer")
                .uniform(2, "params")
                .slot(18, "layer"),
            move |ctx| {
                dispatch_once(
                    ctx,
                    "fill",
                    &[(
                        "params",
                        bytemuck::cast_slice(&params(100 * (layer + 1), 0)),
                    )],
                    [1, 1, 1],
                )
            },
        );
        array = g
            .add_pass(
                &format!("layer{layer}"),
                fill,
                Bindings::new().bind_range("layer", array, TextureRange::layer(layer)),
            )
            .unwrap()
            .texture("layer")
            .unwrap();
    }
    let flat = g.create_buffer(
        "flat",
        BufferDesc::array(Element::F32, (LAYERS * SIDE * SIDE) as u64),
    );
    let flatten = kernel_pass(
        "flatten",
        vec![
            Slot::texture("array", Access::Sampled, None, ""),
            Slot::buffer("flat", Access::StorageWrite, Element::F32, ""),
        ],
        ("flatten", "flatten_layers"),
        BindingLayout::compute("flatten")
            .slot(19, "array")
            .slot(20, "flat"),
        |ctx| dispatch_once(ctx, "flatten", &[], [1, 1, LAYERS]),
    );
    add_exported(
        &mut g,
        "flatten",
        flatten,
        Bindings::new().bind("array", array).bind("flat", flat),
        "flat",
    );
    let compiled = g.compile(&CompileOptions::for_gpu(&gpu)).unwrap();
    let mut exec = Executor::new(gpu);
    exec.execute(&compiled, &Imports::new()).unwrap();
    let got: Vec<f32> = read_export(&mut exec, "flat");
    let want: Vec<f32> = (0..LAYERS * SIDE * SIDE)
        .map(|i| (100 * (i / (SIDE * SIDE) + 1) + i % SIDE) as f32)
        .collect();
    assert_eq!(got, want);
}

// ---------------------------------------------------------------------------------------
// A render pass with a colour and a depth target, ops derived by the compiler.

const DEPTH_SHADER: PassShader = PassShader {
    name: "test::depth",
    source: r#"
// Binding 0: the rectangles' vertices; a larger depth key (`key.x`) is nearer.
#import test::rect_vertices::rect_vertices

struct VOut {
    @builtin(position) pos: vec4<f32>,
    @location(0) @interpolate(flat) id: u32,
}

@vertex
fn vs(@builtin(vertex_index) v: u32) -> VOut {
    let r = rect_vertices[v];
    return VOut(vec4<f32>(r.pos.xy, 1.0 - f32(r.key.x) / 1000.0, 1.0), r.key.y);
}

@fragment
fn fs(in: VOut) -> @location(0) vec4<f32> {
    return vec4<f32>(f32(in.id) / 255.0, 0.0, 0.0, 1.0);
}
"#,
    file_path: "graph/tests/gpu_features.rs",
    modules: &[RECT_VERTICES_WGSL],
};

#[test]
fn a_depth_tested_render_pass_keeps_the_nearest_rectangle() {
    let gpu = gpu();
    let vertices = rect_vertices();
    let count = vertices.len() as u32;
    let mut g = GraphBuilder::new();
    let rects = import_rect_vertices(&mut g, count);
    let color = g.create_texture(
        "color",
        TextureDesc::d2(wgpu::TextureFormat::Rgba8Unorm, W, H),
    );
    let depth = g.create_texture(
        "depth",
        TextureDesc::d2(wgpu::TextureFormat::Depth32Float, W, H),
    );
    let draw = pass(
        "draw",
        vec![
            rects_slot(),
            Slot::texture("color", Access::RenderTarget, None, ""),
            Slot::texture("depth", Access::DepthTarget, None, ""),
        ],
        |ctx| {
            ctx.program(
                "draw",
                ProgramDesc::render(&DEPTH_SHADER, "vs")
                    .fragment("fs")
                    .target(ColorTarget::new("color"))
                    .depth(DepthTarget {
                        target: "depth",
                        compare: wgpu::CompareFunction::LessEqual,
                        write: true,
                    })
                    .primitive(Primitive {
                        cull_mode: Some(wgpu::Face::Back),
                        front_face: wgpu::FrontFace::Cw,
                        unclipped_depth: true,
                        ..Primitive::default()
                    })
                    .layout(BindingLayout::render("draw").slot(0, "rects")),
            );
            Ok(())
        },
        move |ctx| {
            let depth = DepthAttachment {
                target: "depth",
                clear: 1.0,
            };
            let color = [ColorAttachment::new("color")];
            render_once(ctx, "draw", &[], &color, Some(depth), |rp| {
                rp.draw(0..count, 0..1)
            })
        },
    );
    let drawn = g
        .add_pass(
            "draw",
            draw,
            Bindings::new()
                .bind("rects", rects)
                .bind("color", color)
                .bind("depth", depth),
        )
        .unwrap();
    let out = g.create_buffer("out", BufferDesc::array(Element::U32, (W * H) as u64));
    let color = drawn.texture("color").unwrap();
    copy_out(&mut g, "copy", wgpu::TextureFormat::Rgba8Unorm, color, out);
    let compiled = g.compile(&CompileOptions::for_gpu(&gpu)).unwrap();
    let ops = |slot: &str| {
        compiled.plan.passes[0]
            .slots
            .iter()
            .find(|s| s.slot == slot)
            .and_then(|s| s.ops)
            .map(|o| (o.load, o.store))
    };
    assert_eq!(ops("color"), Some((LoadOp::Clear, StoreOp::Store)));
    assert_eq!(ops("depth"), Some((LoadOp::Clear, StoreOp::Discard)));
    let rects = bytemuck::cast_slice(&vertices);
    let mut exec = support::run_frames(gpu, &compiled, ("rects", rects), 1);
    let got: Vec<u32> = read_export(&mut exec, "out");
    let ids: Vec<u32> = got.iter().map(|px| px & 0xff).collect();
    let want: Vec<u32> = cpu_rects()
        .iter()
        .map(|k| (k & 0xffff_ffff) as u32)
        .collect();
    assert_eq!(ids, want);
}
