//! `meshlight bench --scenario light-clustering`: the many-lights shape (point lights
//! spread evenly over a sphere around the camera, about 8% of them in view), 1,000 to
//! 1,000,000 lights at 1920 × 1080 on the default 16 × 9 × 24 grid. GPU time of the four
//! stages for both implementations, against the CPU reference of the same assignment
//! measured in the same run, single-threaded and with rayon.

use crate::{Row, median, row};
use glam::Vec3;
use meshlight::gpu_scene::Camera;
use meshlight::shaders::cpu::layout::{ClusterableKind, ClusterableObject, View};
use meshlight_light_clustering::reference::{cpu_assign, cpu_assign_parallel};
use meshlight_light_clustering::{Clusterer, ClusteringSettings, ClusteringSource};
use std::collections::BTreeMap;
use std::time::Instant;

const SCENARIO: &str = "light-clustering";
/// Radius of the sphere the lights lie on, and each light's range.
const SPHERE_RADIUS: f32 = 150.0;
const LIGHT_RANGE: f32 = 4.0;
/// Vertical field of view: about 8% of the sphere's lights in a 16:9 view.
const FOV_Y_DEGREES: f32 = 48.0;
pub const VIEWPORT: [u32; 2] = [1920, 1080];

/// `n` point lights on a Fibonacci sphere around the origin, and a camera at its centre.
pub fn many_lights(n: usize) -> (View, Vec<ClusterableObject>) {
    let golden = std::f32::consts::PI * (3.0 - 5f32.sqrt());
    let lights = (0..n)
        .map(|i| {
            let y = 1.0 - 2.0 * (i as f32 + 0.5) / n as f32;
            let r = (1.0 - y * y).max(0.0).sqrt();
            let a = golden * i as f32;
            let p = Vec3::new(r * a.cos(), y, r * a.sin()) * SPHERE_RADIUS;
            let hue = i as f32 / n as f32;
            ClusterableObject {
                position_range: [p.x, p.y, p.z, LIGHT_RANGE],
                direction_cos_angle: [0.0, -1.0, 0.0, 1.0],
                color_intensity: [hue, 1.0 - hue, 0.5, 1.0],
                kind: ClusterableKind::PointLight as u32,
                ..ClusterableObject::default()
            }
        })
        .collect();
    let camera = Camera::perspective(
        Vec3::ZERO,
        Vec3::new(0.3, 0.1, -1.0),
        FOV_Y_DEGREES.to_radians(),
        0.1,
    );
    (camera.view(VIEWPORT, 0, None), lights)
}

/// Medians per timed unit (batches in `frame` timing, passes in `passes` timing) and of
/// the frame total of the four stages, in ms; readbacks left out.
struct GpuRun {
    passes: Vec<(String, f64)>,
    total_ms: f64,
    /// From the first stage's start to the last one's end, gaps between passes included.
    span_ms: f64,
    visible: u32,
    entries: u32,
    device: String,
}

fn measure_gpu(
    view: &View,
    lights: &[ClusterableObject],
    implementation: &str,
    scan: &str,
    timing: meshlight::graph::TimingMode,
    frames: u32,
) -> Result<GpuRun, Box<dyn std::error::Error>> {
    let settings = ClusteringSettings {
        implementation: Some(implementation.into()),
        scan: Some(scan.into()),
        ..ClusteringSettings::new(VIEWPORT, lights.len() as u64)
    };
    let mut clusterer = Clusterer::new(settings, &ClusteringSource::Code)?;
    clusterer.executor.timing = timing;
    let still = clusterer.cluster_still(view, lights)?;
    clusterer.executor.take_gpu_timings()?;
    for _ in 0..frames {
        clusterer.frame(view, lights)?;
    }
    clusterer.executor.finish()?;
    let timings = clusterer.executor.take_gpu_timings()?;
    let device = clusterer.executor.gpu.info.name.clone();
    if timings.is_empty() {
        return Err(format!("{device} has no GPU timestamps; nothing to measure").into());
    }
    let mut per_pass: BTreeMap<String, Vec<f64>> = BTreeMap::new();
    let mut order = Vec::new();
    let mut totals = Vec::new();
    let mut spans = Vec::new();
    // A unit is a readback when every pass in it is one (a batch of readbacks, or one).
    let plan = &clusterer.compiled.plan;
    let is_readback = |mode: meshlight::graph::TimingMode, unit: usize, name: &str| match mode {
        meshlight::graph::TimingMode::Frame => plan.batches.get(unit).is_some_and(|b| {
            b.passes
                .iter()
                .all(|&p| plan.passes[p].stage == meshlight::graph::READBACK_STAGE)
        }),
        _ => name.starts_with("readback:"),
    };
    for t in &timings {
        let kept: Vec<usize> = (0..t.passes.len())
            .filter(|&u| !is_readback(t.mode, u, &t.passes[u].0))
            .collect();
        let stages: Vec<[f64; 2]> = kept.iter().map(|&u| t.intervals[u]).collect();
        if let (Some(first), Some(last)) = (stages.first(), stages.last()) {
            spans.push((last[1] - first[0]) / 1e3);
        }
        let mut total = 0.0;
        for (name, us) in kept.iter().map(|&u| &t.passes[u]) {
            if !per_pass.contains_key(name) {
                order.push(name.clone());
            }
            per_pass.entry(name.clone()).or_default().push(us / 1e3);
            total += us / 1e3;
        }
        totals.push(total);
    }
    Ok(GpuRun {
        passes: order
            .into_iter()
            .map(|n| {
                let v = per_pass.remove(&n).unwrap_or_default();
                (n, median(v))
            })
            .collect(),
        total_ms: median(totals),
        span_ms: median(spans),
        visible: still.counts.visible.iter().sum(),
        entries: still.counts.entries_needed,
        device,
    })
}

/// The median of `repeats` timed calls, after one untimed call that warms the caches
/// and rayon's thread pool.
fn time_ms<T>(repeats: u32, mut f: impl FnMut() -> T) -> (f64, T) {
    f();
    let mut times = Vec::new();
    let mut last = None;
    for _ in 0..repeats {
        let start = Instant::now();
        last = Some(f());
        times.push(start.elapsed().as_secs_f64() * 1e3);
    }
    (median(times), last.expect("at least one repeat"))
}

/// The floor the stages stand on: four passes of one one-thread dispatch each
/// (`remap_dispatch`, reading one word and writing three), timed like the clustering. Returns the median per pass and
/// the median span of the four.
fn pass_floor(frames: u32) -> Result<(f64, f64, String), Box<dyn std::error::Error>> {
    use meshlight::graph::*;
    let gpu = GpuContext::with_available(wgpu::Features::all())?;
    let device = gpu.info.name.clone();
    let mut g = GraphBuilder::new();
    let usage = wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST;
    let count = g.import_buffer("seed", BufferDesc::array(Element::U32, 4), usage);
    for i in 0..4 {
        let args = g.create_buffer(
            &format!("args{i}"),
            BufferDesc::array(Element::DISPATCH_ARGS, 1),
        );
        let pass = meshlight::remap_dispatch::RemapDispatch {
            count_word: 0,
            max_per_dimension: None,
        };
        let out = g.add_pass(
            &format!("one_thread_{i}"),
            pass,
            Bindings::new().bind("count", count).bind("args", args),
        )?;
        g.export(out.buffer("args")?);
    }
    let compiled = g.compile(&CompileOptions::for_gpu(&gpu))?;
    let seed = gpu.buffer_with_data(
        "seed",
        &[7, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0],
        usage,
    );
    let mut exec = Executor::new(gpu);
    let imports = Imports::new().buffer("seed", &seed);
    for _ in 0..frames {
        exec.execute_frame(&compiled, &imports, &FrameData::new())?;
    }
    exec.finish()?;
    let timings = exec.take_gpu_timings()?;
    let spans: Vec<f64> = timings
        .iter()
        .filter_map(|t| Some((t.intervals.last()?[1] - t.intervals.first()?[0]) / 1e3))
        .collect();
    let span = median(spans);
    Ok((span / 4.0, span, device))
}

pub fn run(quick: bool) -> Result<Vec<Row>, Box<dyn std::error::Error>> {
    let counts: &[usize] = if quick {
        &[1_000, 10_000]
    } else {
        &[1_000, 100_000, 1_000_000]
    };
    let frames = if quick { 5 } else { 50 };
    let mut rows = Vec::new();
    let (per_pass, span, device) = pass_floor(frames)?;
    rows.push(row(
        SCENARIO,
        "floor: 4 passes of a 1-thread dispatch".into(),
        "GPU per pass",
        per_pass,
        "ms",
        &device,
    ));
    rows.push(row(
        SCENARIO,
        "floor: 4 passes of a 1-thread dispatch".into(),
        "GPU span of the 4",
        span,
        "ms",
        &device,
    ));
    for &n in counts {
        let (view, lights) = many_lights(n);
        let settings = ClusteringSettings::new(VIEWPORT, n as u64);
        let repeats = if n >= 1_000_000 { 5 } else { 21 };
        let (serial_ms, want) = time_ms(repeats, || cpu_assign(&view, &settings, &lights));
        let (parallel_ms, _) = time_ms(repeats, || cpu_assign_parallel(&view, &settings, &lights));
        let case = format!("{n} lights");
        let (compute, raster) = ("compute", "raster");
        let (fan, lookback) = ("scan_fan", "decoupled_lookback");
        use meshlight::graph::TimingMode::{Frame, Passes};
        // `frame` timing (one pair per batch) gives the figures; the per-pass profile comes
        // from `passes` timing, which adds a pair, and its serialisation, per pass.
        let variants = [
            (compute, fan, Frame, ""),
            (raster, fan, Frame, ""),
            (compute, lookback, Frame, " + decoupled_lookback scan"),
            (compute, fan, Passes, ", per-pass profile (passes timing)"),
        ];
        for (implementation, scan, timing, suffix) in variants {
            let gpu = measure_gpu(&view, &lights, implementation, scan, timing, frames)?;
            let case = format!("{case}, {implementation}{suffix}");
            let mut total = row(
                SCENARIO,
                case.clone(),
                "GPU clustering",
                gpu.total_ms,
                "ms",
                &gpu.device,
            );
            total.vs_baseline = Some(parallel_ms / gpu.total_ms);
            rows.push(total);
            rows.push(row(
                SCENARIO,
                case.clone(),
                "GPU span, first stage's start to last stage's end",
                gpu.span_ms,
                "ms",
                &gpu.device,
            ));
            for (name, ms) in &gpu.passes {
                rows.push(row(
                    SCENARIO,
                    case.clone(),
                    &format!("GPU {name}"),
                    *ms,
                    "ms",
                    &gpu.device,
                ));
            }
            rows.push(row(
                SCENARIO,
                case.clone(),
                "lights in view",
                f64::from(gpu.visible),
                "lights",
                &gpu.device,
            ));
            let mut entries = row(
                SCENARIO,
                case,
                "list entries (GPU)",
                f64::from(gpu.entries),
                "entries",
                &gpu.device,
            );
            entries.vs_baseline =
                Some(f64::from(gpu.entries) / f64::from(want.lists.needed.max(1)));
            rows.push(entries);
        }
        let threads = rayon::current_num_threads();
        rows.push(row(
            SCENARIO,
            case.clone(),
            "CPU reference, 1 thread",
            serial_ms,
            "ms",
            "cpu",
        ));
        rows.push(row(
            SCENARIO,
            case.clone(),
            &format!("CPU reference, {threads} threads (baseline)"),
            parallel_ms,
            "ms",
            "cpu",
        ));
        rows.push(row(
            SCENARIO,
            case,
            "list entries (CPU)",
            f64::from(want.lists.needed),
            "entries",
            "cpu",
        ));
    }
    Ok(rows)
}
