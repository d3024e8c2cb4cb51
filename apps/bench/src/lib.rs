//! `meshlight bench`: named scenarios, a table on stdout and the same rows as JSON.
//!
//! GPU figures come from timestamps on whatever adapter runs the command; only numbers
//! from a real GPU say anything about speed.

pub mod builder;
pub mod html;
pub mod image_metric;
pub mod light_clustering;
pub mod scan_fan;
pub mod virtual_geometry;

use meshlight::graph::synthetic::{NoopPass, random_graph};
use meshlight::graph::*;
use serde::Serialize;
use std::time::Instant;

/// What `meshlight bench` is asked for (its `--help` describes each option).
#[derive(Debug, Clone, Default)]
pub struct BenchOptions {
    /// Scenarios to run, by name ([`ALL`]); empty: all of them.
    pub scenarios: Vec<String>,
    /// Write the rows as JSON here too.
    pub json: Option<std::path::PathBuf>,
    /// Fewer repeats and smaller sizes, for a quick look.
    pub quick: bool,
    /// Meshes the `builder` scenario measures besides the procedural mesh; the first is
    /// also the mesh of the virtual-geometry scenarios.
    pub meshes: Vec<std::path::PathBuf>,
    /// Write the rows as one page of charts here too.
    pub html: Option<std::path::PathBuf>,
    /// Read the rows from these JSON files instead of measuring.
    pub from_json: Vec<std::path::PathBuf>,
}

/// One measured row: what was measured, the value, its unit, and optional context.
#[derive(Clone, Debug, Serialize, serde::Deserialize)]
pub struct Row {
    pub scenario: String,
    pub case: String,
    pub metric: String,
    /// JSON has no NaN or infinity: serde writes a value that is not finite (the PSNR of
    /// two equal images is +∞) as `null`, and `--from-json` reads `null` back as NaN.
    #[serde(deserialize_with = "finite_or_null")]
    pub value: f64,
    pub unit: String,
    /// Value relative to the scenario's baseline measured in the same run, when it has one.
    pub vs_baseline: Option<f64>,
    pub device: String,
}

/// Every scenario, in the order `meshlight bench` runs them.
pub const ALL: &[&str] = &[
    "graph-compile",
    "graph-execute",
    "graph-floor",
    "pool-reuse",
    "render",
    "textured",
    "virtual-geometry",
    "vg-scale",
    "vg-million",
    "vg-stream",
    "vg-shadows",
    "lod-quality",
    "rasterisers",
    "builder",
    "scan-fan",
    "light-clustering",
];

/// Largest `--from-json` file read: a full run's rows are a few hundred kilobytes.
const MAX_ROWS_FILE_BYTES: u64 = 256 << 20;

pub fn run(args: &BenchOptions) -> std::result::Result<(), Box<dyn std::error::Error>> {
    let scenarios: Vec<String> = if args.scenarios.is_empty() {
        ALL.iter().map(|s| s.to_string()).collect()
    } else {
        args.scenarios.clone()
    };
    // Output paths are checked before any scenario runs, not after minutes of work.
    for path in args.json.iter().chain(&args.html) {
        meshlight_output::check_output_path(path)?;
    }
    let mut rows = Vec::new();
    for path in &args.from_json {
        let bytes = meshlight::scene::input::read_file(path, MAX_ROWS_FILE_BYTES)?;
        let text = String::from_utf8(bytes).map_err(|_| {
            format!(
                "{}: not UTF-8 text; give a file `--json` wrote",
                path.display()
            )
        })?;
        let read: Vec<Row> = serde_json::from_str(&text).map_err(|e| {
            format!(
                "{}: not a list of bench rows ({e}); give a file `--json` wrote",
                path.display()
            )
        })?;
        rows.extend(read);
    }
    let scenarios = if args.from_json.is_empty() {
        scenarios
    } else {
        Vec::new()
    };
    for s in &scenarios {
        let new = match s.as_str() {
            "graph-compile" => graph_compile(args.quick),
            "graph-execute" => graph_execute(args.quick)?,
            "graph-floor" => graph_floor(args.quick)?,
            "pool-reuse" => pool_reuse(),
            "render" => render(args.quick)?,
            "textured" => crate::virtual_geometry::textured(args.quick)?,
            "virtual-geometry" => crate::virtual_geometry::lattice(args.quick, &args.meshes)?,
            "rasterisers" => crate::virtual_geometry::rasterisers(args.quick, &args.meshes)?,
            "vg-scale" => crate::virtual_geometry::scale(args.quick, &args.meshes)?,
            "vg-million" => crate::virtual_geometry::million(args.quick, &args.meshes)?,
            "vg-stream" => crate::virtual_geometry::stream(args.quick, &args.meshes)?,
            "vg-shadows" => crate::virtual_geometry::shadows(args.quick, &args.meshes)?,
            "lod-quality" => crate::virtual_geometry::lod_quality(args.quick, &args.meshes)?,
            "builder" => builder(args.quick, &args.meshes)?,
            "scan-fan" => scan_fan(args.quick)?,
            "light-clustering" => crate::light_clustering::run(args.quick)?,
            other => {
                return Err(
                    format!("unknown scenario `{other}`; known: {}", ALL.join(", ")).into(),
                );
            }
        };
        for r in &new {
            println!(
                "{:<14} {:<28} {:<22} {:>14.3} {:<10} {}",
                r.scenario,
                r.case,
                r.metric,
                r.value,
                r.unit,
                r.vs_baseline
                    .map(|b| format!("×{b:.2} vs baseline"))
                    .unwrap_or_default()
            );
        }
        rows.extend(new);
    }
    if let Some(path) = &args.json {
        meshlight_output::write_file(path, serde_json::to_string_pretty(&rows)?.as_bytes())?;
    }
    if let Some(path) = &args.html {
        meshlight_output::write_file(path, crate::html::page("meshlight bench", &rows).as_bytes())?;
        println!("charts: {}", path.display());
    }
    Ok(())
}

/// Reads a row's value as `--json` wrote it: a number, or `null` for one that was not
/// finite.
fn finite_or_null<'de, D: serde::Deserializer<'de>>(d: D) -> Result<f64, D::Error> {
    Ok(<Option<f64> as serde::Deserialize>::deserialize(d)?.unwrap_or(f64::NAN))
}

pub(crate) fn row(
    scenario: &str,
    case: String,
    metric: &str,
    value: f64,
    unit: &str,
    device: &str,
) -> Row {
    Row {
        scenario: scenario.into(),
        case,
        metric: metric.into(),
        value,
        unit: unit.into(),
        vs_baseline: None,
        device: device.into(),
    }
}

pub(crate) fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn graph_compile(quick: bool) -> Vec<Row> {
    let mut rows = Vec::new();
    for n in [10usize, 100, 1000] {
        let reps = if quick { 5 } else { 30 };
        let times: Vec<f64> = (0..reps)
            .map(|i| {
                let g = random_graph(n, 0x5eed + i as u64);
                let t = Instant::now();
                let c = g
                    .compile(&CompileOptions::new(wgpu::Features::empty()))
                    .expect("compiles");
                let dt = t.elapsed().as_secs_f64() * 1e3;
                std::hint::black_box(c.plan.order.len());
                dt
            })
            .collect();
        rows.push(row(
            "graph-compile",
            format!("{n} passes"),
            "compile time (median)",
            median(times),
            "ms",
            "cpu",
        ));
    }
    rows
}

fn graph_execute(quick: bool) -> std::result::Result<Vec<Row>, Box<dyn std::error::Error>> {
    let adapter = GpuAdapter::select()?;
    let device = adapter.info().name;
    let mut rows = Vec::new();
    for n in [10usize, 100] {
        let compiled = random_graph(n, 7).compile(&CompileOptions::for_adapter(&adapter))?;
        let gpu = GpuContext::with_available(compiled.plan.enabled_features)?;
        let out = gpu.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("out"),
            size: 64,
            usage: wgpu::BufferUsages::STORAGE,
            mapped_at_creation: false,
        });
        let mut exec = Executor::new(gpu);
        let imports = Imports::new().buffer("out", &out);
        for timing in [false, true] {
            exec.gpu_timing = timing;
            exec.execute(&compiled, &imports)?;
            let frames = if quick { 20 } else { 200 };
            let mut record = Vec::new();
            let mut frame = Vec::new();
            let mut without_submit = Vec::new();
            for _ in 0..frames {
                let s = exec.execute(&compiled, &imports)?;
                record.push(s.passes.iter().map(|p| p.cpu_record_us).sum::<f64>() / n as f64);
                frame.push(s.cpu_frame_us / n as f64);
                without_submit.push((s.cpu_frame_us - s.cpu_submit_us) / n as f64);
            }
            exec.finish()?;
            let case = format!(
                "{n} passes, timestamps {}",
                if timing { "on" } else { "off" }
            );
            for (metric, values) in [
                ("CPU per pass (frame)", frame),
                ("CPU per pass (no submit)", without_submit),
                ("CPU per pass (record)", record),
            ] {
                rows.push(row(
                    "graph-execute",
                    case.clone(),
                    metric,
                    median(values),
                    "µs",
                    &device,
                ));
            }
        }
    }
    rows.extend(frames_in_flight(quick)?);
    Ok(rows)
}

/// Whether the CPU records ahead while the GPU works: the virtual-geometry frame of a
/// small field of procedural meshes with the camera moving every frame, run back to back,
/// against the same frames each waited for (the behaviour before timestamps and readbacks
/// went through rings), measured in the same run.
fn frames_in_flight(quick: bool) -> std::result::Result<Vec<Row>, Box<dyn std::error::Error>> {
    use meshlight_virtual_geometry::{FrameSettings, GraphSource, Renderer, scenes};
    let segments = if quick { 32 } else { 128 };
    let asset = scenes::load_asset(std::path::Path::new("procedural"), segments)?;
    let placed = scenes::field(
        meshlight::gpu_scene::SceneData::new(Default::default()),
        &asset,
        16,
    )?;
    let (width, height) = (1280, 720);
    let mut renderer = Renderer::new(
        placed.data,
        FrameSettings::new(width, height),
        &GraphSource::Shipped,
    )?;
    let device = renderer.adapter.clone();
    let base = placed.camera;
    // The camera slides a little every frame: the view is frame data, nothing recompiles.
    let camera = |f: u32| {
        let mut c = base;
        c.position += glam::Vec3::X * (f as f32 * 0.01);
        c
    };
    // Warm up, and let any list grow to what the view needs.
    renderer.render_still(&camera(0))?;
    let frames = if quick { 20 } else { 100 };
    let case = format!("virtual geometry, 16 meshes {width}x{height}, {frames} frames");

    let start = Instant::now();
    for f in 0..frames {
        renderer.frame(&camera(f))?;
        renderer.executor.finish()?;
    }
    let waited = start.elapsed().as_secs_f64() * 1e3 / frames as f64;
    renderer.executor.take_gpu_timings()?;

    let start = Instant::now();
    let mut most_in_flight = 0;
    // Of the wall time, what the executor spends in `execute_frame` and in its submit.
    let (mut executor_ms, mut submit_ms) = (Vec::new(), Vec::new());
    let (mut finish_ms, mut records_ms) = (Vec::new(), Vec::new());
    let mut record_us: std::collections::BTreeMap<String, Vec<f64>> = Default::default();
    for f in 0..frames {
        let s = renderer.frame(&camera(f))?;
        most_in_flight = most_in_flight.max(s.frames_in_flight);
        executor_ms.push(s.cpu_frame_us / 1e3);
        submit_ms.push(s.cpu_submit_us / 1e3);
        finish_ms.push(s.cpu_finish_us / 1e3);
        records_ms.push(s.passes.iter().map(|p| p.cpu_record_us).sum::<f64>() / 1e3);
        for p in &s.passes {
            record_us
                .entry(p.name.clone())
                .or_default()
                .push(p.cpu_record_us);
        }
    }
    renderer.executor.finish()?;
    let overlapped = start.elapsed().as_secs_f64() * 1e3 / frames as f64;
    let gpu_ms: Vec<f64> = renderer
        .executor
        .take_gpu_timings()?
        .iter()
        .map(|t| t.total_us / 1e3)
        .collect();

    let mut rows = vec![
        row(
            "graph-execute",
            case.clone(),
            "wall per frame, each frame waited for",
            waited,
            "ms",
            &device,
        ),
        row(
            "graph-execute",
            case.clone(),
            "wall per frame, frames back to back",
            overlapped,
            "ms",
            &device,
        ),
        row(
            "graph-execute",
            case.clone(),
            "most frames in flight",
            most_in_flight as f64,
            "frames",
            &device,
        ),
    ];
    rows[1].vs_baseline = Some(waited / overlapped);
    if !gpu_ms.is_empty() {
        rows.push(row(
            "graph-execute",
            case.clone(),
            "GPU per frame (timestamps)",
            median(gpu_ms),
            "ms",
            &device,
        ));
    }
    for (metric, values) in [
        ("CPU execute_frame per frame", executor_ms),
        ("CPU queue.submit per frame", submit_ms),
        ("CPU encoder.finish per frame", finish_ms),
        ("CPU records of all passes per frame", records_ms),
    ] {
        rows.push(row(
            "graph-execute",
            case.clone(),
            metric,
            median(values),
            "ms",
            &device,
        ));
    }
    for (pass, values) in record_us {
        let metric = format!("CPU record {pass}");
        rows.push(row(
            "graph-execute",
            case.clone(),
            &metric,
            median(values),
            "µs",
            &device,
        ));
    }
    Ok(rows)
}

/// A graph shaped like one virtual-geometry frame, to show what slot reuse saves.
pub fn sample_frame_graph(width: u32, height: u32) -> GraphBuilder {
    let px = width as u64 * height as u64;
    let mut g = GraphBuilder::new();
    let usage = wgpu::BufferUsages::STORAGE;
    g.import_buffer("scene", BufferDesc::array(Element::U32, 1 << 20), usage);
    g.import_buffer("image", BufferDesc::array(Element::U32, px), usage);
    /// One pass of the sample frame: what it reads, and what it writes with its size in u32s
    /// (0 for a resource declared elsewhere).
    struct Stage {
        pass: &'static str,
        reads: Vec<&'static str>,
        writes: Vec<(&'static str, u64)>,
    }
    let stage = |pass, reads: &[&'static str], writes: &[(&'static str, u64)]| Stage {
        pass,
        reads: reads.to_vec(),
        writes: writes.to_vec(),
    };
    let stages = [
        stage("fill_clusters", &["scene"], &[("clusters", 1 << 20)]),
        stage(
            "cull_first",
            &["clusters"],
            &[("candidates", 1 << 20), ("dispatch_first", 4)],
        ),
        stage(
            "raster_first",
            &["candidates", "dispatch_first"],
            &[("visbuffer", px * 2)],
        ),
        stage("depth_pyramid", &["visbuffer"], &[("pyramid", px / 3)]),
        stage(
            "cull_second",
            &["clusters", "pyramid"],
            &[("second", 1 << 19), ("dispatch_second", 4)],
        ),
        stage(
            "raster_second",
            &["second", "dispatch_second", "visbuffer"],
            &[("visbuffer2", px * 2)],
        ),
        stage("material_depth", &["visbuffer2"], &[("material", px)]),
        stage("resolve", &["visbuffer2", "material"], &[("image", 0)]),
    ];
    for Stage {
        pass,
        reads,
        writes,
    } in stages
    {
        let mut slots: Vec<Slot> = reads
            .iter()
            .map(|r| Slot::buffer(r, Access::StorageRead, Element::U32, ""))
            .collect();
        for (w, words) in writes {
            if words > 0 {
                g.create_buffer(w, BufferDesc::array(Element::U32, words));
            }
            slots.push(Slot::buffer(w, Access::StorageWrite, Element::U32, ""));
        }
        g.add_pass(pass, NoopPass { slots }, Bindings::new())
            .expect("sample graph is well-formed");
    }
    g
}

fn pool_reuse() -> Vec<Row> {
    let plan = sample_frame_graph(1920, 1080)
        .compile(&CompileOptions::new(wgpu::Features::empty()))
        .expect("compiles")
        .plan;
    let mib = |b: u64| b as f64 / (1u64 << 20) as f64;
    let mut with = row(
        "pool-reuse",
        "sample frame 1920x1080".into(),
        "transient bytes, reuse",
        mib(plan.bytes_with_reuse),
        "MiB",
        "cpu",
    );
    with.vs_baseline = Some(plan.bytes_with_reuse as f64 / plan.bytes_without_reuse as f64);
    vec![
        row(
            "pool-reuse",
            "sample frame 1920x1080".into(),
            "transient bytes, no reuse",
            mib(plan.bytes_without_reuse),
            "MiB",
            "cpu",
        ),
        with,
    ]
}

fn render(quick: bool) -> std::result::Result<Vec<Row>, Box<dyn std::error::Error>> {
    crate::virtual_geometry::default_scene(quick)
}

fn builder(
    quick: bool,
    files: &[std::path::PathBuf],
) -> std::result::Result<Vec<Row>, Box<dyn std::error::Error>> {
    let segments = if quick {
        64
    } else {
        meshlight::scene::DEFAULT_SEGMENTS
    };
    let mut meshes = Vec::new();
    for f in files {
        let name = f.file_stem().map_or_else(
            || f.display().to_string(),
            |s| s.to_string_lossy().into_owned(),
        );
        meshes.push((name, meshlight::scene::load::load_mesh(f)?));
    }
    meshes.push((
        format!("procedural {segments}"),
        meshlight::scene::procedural_mesh(segments),
    ));
    let dir = std::env::temp_dir().join("meshlight-bench");
    std::fs::create_dir_all(&dir)?;
    let repeats = if quick { 1 } else { 5 };
    let mut results = Vec::new();
    for (name, mesh) in &meshes {
        results.push(crate::builder::builder_scenario(name, mesh, repeats, &dir)?);
    }
    println!("{}", crate::builder::format_table(&results));
    let mut rows = Vec::new();
    for b in &results {
        let case = || b.name.clone();
        let mut r = row(
            "builder",
            case(),
            "input triangles/s",
            b.triangles_per_second(),
            "tri/s",
            "cpu",
        );
        r.vs_baseline = Some(b.triangles_per_second() / b.clod_triangles_per_second());
        rows.push(r);
        rows.push(row(
            "builder",
            case(),
            "build wall time",
            b.build_seconds,
            "s",
            "cpu",
        ));
        rows.push(row(
            "builder",
            case(),
            "clod_build wall time (baseline)",
            b.clod_seconds,
            "s",
            "cpu",
        ));
        rows.push(row(
            "builder",
            case(),
            "bytes per LOD-0 triangle",
            b.bytes_per_lod0_triangle,
            "B",
            "cpu",
        ));
        rows.push(row(
            "builder",
            case(),
            "asset load from page cache",
            b.load_bytes_per_second / 1e9,
            "GB/s",
            "cpu",
        ));
    }
    Ok(rows)
}

fn scan_fan(quick: bool) -> std::result::Result<Vec<Row>, GraphError> {
    let gpu = GpuContext::with_available(wgpu::Features::all())?;
    let device = gpu.info.name.clone();
    let mut exec = Executor::new(gpu);
    let sizes: Vec<u64> = if quick {
        vec![1 << 20, 1 << 22]
    } else {
        crate::scan_fan::SIZES.to_vec()
    };
    let rows = crate::scan_fan::run(&mut exec, &sizes, if quick { 3 } else { 10 })?;
    println!("{}", crate::scan_fan::table(&rows));
    let mut out = Vec::new();
    for r in rows {
        let case = format!("{} 2^{}", r.implementation, r.elements.trailing_zeros());
        out.push(row(
            "scan-fan",
            case.clone(),
            "elements/s",
            r.elements_per_s,
            "elem/s",
            &device,
        ));
        let mut gb = row(
            "scan-fan",
            case.clone(),
            "GB/s (8 B/elem)",
            r.gb_per_s,
            "GB/s",
            &device,
        );
        gb.vs_baseline = Some(r.ratio_to_copy);
        out.push(gb);
        out.push(row(
            "scan-fan",
            case.clone(),
            "compute copy GB/s (baseline)",
            r.copy_gb_per_s,
            "GB/s",
            &device,
        ));
        out.push(row(
            "scan-fan",
            case.clone(),
            "copy_buffer_to_buffer GB/s (for comparison)",
            r.copy_command_gb_per_s,
            "GB/s",
            &device,
        ));
        out.push(row(
            "scan-fan",
            case.clone(),
            "GPU time",
            r.gpu_ms * 1e3,
            "µs",
            &device,
        ));
        let mut cpu = row("scan-fan", case, "CPU prefix sum", r.cpu_ms, "ms", "cpu");
        cpu.vs_baseline = Some(r.cpu_ms / r.gpu_ms);
        out.push(cpu);
    }
    Ok(out)
}

/// The one-thread step of `graph-floor`: each dispatch reads what the one before wrote.
const FLOOR_WGSL: &str = "
// The counter every step increments: read-write, so each dispatch depends on the last.
@group(0) @binding(0) var<storage, read_write> counter: array<u32>;

@compute @workgroup_size(1)
fn step() {
    counter[0] = counter[0] + 1u;
}
";

static FLOOR_SHADER: PassShader = PassShader {
    name: "bench::floor_step",
    source: FLOOR_WGSL,
    file_path: "apps/bench/src/lib.rs",
    modules: &[],
};

/// A graph pass that dispatches one thread of `FLOOR_WGSL` on its `counter` slot.
struct FloorStep;

impl Pass for FloorStep {
    fn implementation(&self) -> Implementation {
        Implementation::new(
            "one_thread",
            StageContract {
                stage: "floor_step",
                slots: vec![Slot::buffer(
                    "counter",
                    Access::StorageReadWrite,
                    Element::U32,
                    "incremented by each step",
                )],
            },
        )
    }
    fn setup(&self, ctx: &mut SetupContext) -> Result<()> {
        ctx.program(
            "step",
            ProgramDesc::compute(&FLOOR_SHADER, "step")
                .layout(BindingLayout::compute("floor_step").slot(0, "counter")),
        );
        Ok(())
    }
    fn record(&self, ctx: &mut RecordContext<'_>) -> Result<()> {
        ctx.dispatch_compute("step", &[], Workgroups::Direct([1, 1, 1]))
    }
}

/// GPU µs of `n` dependent one-thread dispatches in one raw wgpu compute pass with one
/// timestamp pair around them: the floor a graph's pass boundary is measured against.
fn raw_floor(
    gpu: &GpuContext,
    counter: &wgpu::Buffer,
    n: usize,
    frames: usize,
) -> std::result::Result<f64, Box<dyn std::error::Error>> {
    let device = &gpu.device;
    let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some("floor step (raw)"),
        source: wgpu::ShaderSource::Wgsl(FLOOR_WGSL.into()),
    });
    let pipeline = device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
        label: Some("floor step (raw)"),
        layout: None,
        module: &module,
        entry_point: Some("step"),
        compilation_options: Default::default(),
        cache: None,
    });
    let group = device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some("floor step (raw)"),
        layout: &pipeline.get_bind_group_layout(0),
        entries: &[wgpu::BindGroupEntry {
            binding: 0,
            resource: counter.as_entire_binding(),
        }],
    });
    let queries = device.create_query_set(&wgpu::QuerySetDescriptor {
        label: Some("floor (raw)"),
        ty: wgpu::QueryType::Timestamp,
        count: 2,
    });
    let resolve = device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("floor resolve"),
        size: 16,
        usage: wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC,
        mapped_at_creation: false,
    });
    let period = gpu.queue.get_timestamp_period() as f64;
    let mut times = Vec::with_capacity(frames);
    for _ in 0..frames + 1 {
        let mut encoder = device.create_command_encoder(&Default::default());
        {
            let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("floor (raw)"),
                timestamp_writes: Some(wgpu::ComputePassTimestampWrites {
                    query_set: &queries,
                    beginning_of_pass_write_index: Some(0),
                    end_of_pass_write_index: Some(1),
                }),
            });
            for _ in 0..n {
                pass.set_pipeline(&pipeline);
                pass.set_bind_group(0, &group, &[]);
                pass.dispatch_workgroups(1, 1, 1);
            }
        }
        encoder.resolve_query_set(&queries, 0..2, &resolve, 0);
        gpu.queue.submit([encoder.finish()]);
        let ticks: Vec<u64> = bytemuck::pod_collect_to_vec(&gpu.read_buffer(&resolve, 0, 16)?);
        times.push(ticks[1].saturating_sub(ticks[0]) as f64 * period / 1e3);
    }
    // The first frame builds the pipeline's driver state; leave it out.
    times.remove(0);
    Ok(median(times))
}

/// What a graph pass boundary costs against wgpu's own floor: N dependent one-thread
/// passes through the graph (default `frame` timing: one timestamp pair around the batch),
/// against the same dispatches in one raw compute pass, same run; and, for context, the
/// graph with batching off (a compute pass per pass) and in `passes` timing mode.
fn graph_floor(quick: bool) -> std::result::Result<Vec<Row>, Box<dyn std::error::Error>> {
    let adapter = GpuAdapter::select()?;
    let device_name = adapter.info().name;
    let frames = if quick { 10 } else { 100 };
    let mut rows = Vec::new();
    let gpu = GpuContext::with_available(wgpu::Features::all())?;
    if !gpu.features.contains(wgpu::Features::TIMESTAMP_QUERY) {
        return Err("graph-floor needs TIMESTAMP_QUERY".into());
    }
    let usage = wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC;
    let counter = gpu.buffer_with_data("floor counter", &[0u8; 16], usage);
    let raw_counter = gpu.buffer_with_data("floor counter (raw)", &[0u8; 16], usage);
    let inside = gpu
        .features
        .contains(wgpu::Features::TIMESTAMP_QUERY_INSIDE_PASSES);
    let mut exec = Executor::new(gpu);
    let mut dispatched = 0u64;
    for n in [1usize, 16, 256] {
        let raw = raw_floor(&exec.gpu, &raw_counter, n, frames)? / n as f64;
        let mut g = GraphBuilder::new();
        g.import_buffer("counter", BufferDesc::array(Element::U32, 4), usage);
        for i in 0..n {
            g.add_pass(&format!("step{i}"), FloorStep, Bindings::new())?;
        }
        let compiled = g.compile(&CompileOptions::for_gpu(&exec.gpu))?;
        if compiled.plan.batches.len() != 1 {
            return Err(format!(
                "{n} floor steps planned as {} batches, not one",
                compiled.plan.batches.len()
            )
            .into());
        }
        let imports = Imports::new().buffer("counter", &counter);
        let case = format!("{n} dependent passes");
        rows.push(Row {
            vs_baseline: Some(1.0),
            ..row(
                "graph-floor",
                case.clone(),
                "GPU per pass, raw compute pass",
                raw,
                "µs",
                &device_name,
            )
        });
        // (metric, timing, batching, per-pass stamps inside the shared pass)
        let mut arrangements = vec![
            (
                "GPU per pass, graph (frame timing)",
                TimingMode::Frame,
                true,
                true,
            ),
            (
                "GPU per pass, graph unbatched",
                TimingMode::Frame,
                false,
                true,
            ),
            (
                "GPU per pass, graph (passes timing, a compute pass each)",
                TimingMode::Passes,
                true,
                false,
            ),
        ];
        if inside {
            arrangements.push((
                "GPU per pass, graph (passes timing, stamps inside the batch)",
                TimingMode::Passes,
                true,
                true,
            ));
        }
        for (metric, mode, batching, stamp_inside) in arrangements {
            exec.timing = mode;
            exec.batching = batching;
            exec.stamp_inside_passes = stamp_inside;
            exec.execute(&compiled, &imports)?;
            exec.finish()?;
            exec.take_gpu_timings()?;
            dispatched += n as u64;
            let mut record = Vec::new();
            let mut cpu_frame = Vec::new();
            for _ in 0..frames {
                let s = exec.execute(&compiled, &imports)?;
                exec.finish()?;
                dispatched += n as u64;
                record.push(s.passes.iter().map(|p| p.cpu_record_us).sum::<f64>() / n as f64);
                cpu_frame.push(s.cpu_frame_us / n as f64);
            }
            let taken = exec.take_gpu_timings()?;
            let gpu: Vec<f64> = taken.iter().map(|t| t.frame_us / n as f64).collect();
            if gpu.is_empty() {
                return Err(format!("no GPU timings came back ({metric}, {n} passes)").into());
            }
            let per_pass = median(gpu);
            rows.push(Row {
                vs_baseline: Some(per_pass / raw),
                ..row(
                    "graph-floor",
                    case.clone(),
                    metric,
                    per_pass,
                    "µs",
                    &device_name,
                )
            });
            if mode == TimingMode::Frame && batching {
                rows.push(row(
                    "graph-floor",
                    case.clone(),
                    "CPU record per pass (graph)",
                    median(record),
                    "µs",
                    &device_name,
                ));
                rows.push(row(
                    "graph-floor",
                    case.clone(),
                    "CPU frame per pass (graph)",
                    median(cpu_frame),
                    "µs",
                    &device_name,
                ));
            }
        }
    }
    exec.timing = TimingMode::Frame;
    exec.batching = true;
    exec.stamp_inside_passes = true;
    let got: Vec<u32> = bytemuck::pod_collect_to_vec(&exec.gpu.read_buffer(&counter, 0, 4)?);
    if got[0] as u64 != dispatched {
        return Err(format!(
            "the graph's steps counted {} dispatches of {dispatched}: some did not run",
            got[0]
        )
        .into());
    }
    Ok(rows)
}

#[cfg(test)]
mod tests {
    use super::Row;

    /// What `--json` writes for a value that is not finite, `--from-json` reads back.
    #[test]
    fn a_value_that_is_not_finite_survives_the_json_as_not_a_number() {
        let mut r = super::row("s", "c".into(), "m", f64::INFINITY, "dB", "d");
        let mut rows = vec![r.clone()];
        r.value = 1.5;
        rows.push(r);
        let text = serde_json::to_string(&rows).unwrap();
        assert!(text.contains("\"value\":null"), "{text}");
        let read: Vec<Row> = serde_json::from_str(&text).unwrap();
        assert!(read[0].value.is_nan());
        assert_eq!(read[1].value, 1.5);
        assert!(serde_json::from_str::<Vec<Row>>(&text.replace("1.5", "\"x\"")).is_err());
    }
}
