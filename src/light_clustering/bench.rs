//! `meshlight bench --scenario light-clustering`: the many-lights shape (point lights
//! spread evenly over a sphere around the camera, about 8% of them in view), 1,000 to
//! 1,000,000 lights at 1920 × 1080 on the default 16 × 9 × 24 grid. GPU time of the four
//! stages for both implementations, against the CPU reference of the same assignment
//! measured in the same run, single-threaded and with rayon.

use super::reference::{cpu_assign, cpu_assign_parallel};
use super::{Clusterer, ClusteringSettings, ClusteringSource, Implementation, ScanImplementation};
use crate::bench::{Row, median, row};
use glam::Vec3;
use meshlight_gpu_scene::Camera;
use meshlight_shaders::cpu::layout::{ClusterableKind, ClusterableObject, View};
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

/// Per-pass medians and the median frame total of the four stages, in ms.
struct GpuRun {
    passes: Vec<(String, f64)>,
    total_ms: f64,
    visible: u32,
    entries: u32,
    device: String,
}

fn measure_gpu(
    view: &View,
    lights: &[ClusterableObject],
    implementation: Implementation,
    scan: ScanImplementation,
    one_command_buffer: bool,
    frames: u32,
) -> Result<GpuRun, Box<dyn std::error::Error>> {
    let settings = ClusteringSettings {
        implementation,
        scan,
        ..ClusteringSettings::new(VIEWPORT, lights.len() as u64)
    };
    let mut clusterer = Clusterer::new(settings, &ClusteringSource::Code)?;
    clusterer.executor.one_command_buffer = one_command_buffer;
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
    for t in &timings {
        let mut total = 0.0;
        for (name, us) in t.passes.iter().filter(|(n, _)| !n.starts_with("readback:")) {
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

pub fn run(quick: bool) -> Result<Vec<Row>, Box<dyn std::error::Error>> {
    let counts: &[usize] = if quick {
        &[1_000, 10_000]
    } else {
        &[1_000, 100_000, 1_000_000]
    };
    let frames = if quick { 5 } else { 50 };
    let mut rows = Vec::new();
    for &n in counts {
        let (view, lights) = many_lights(n);
        let settings = ClusteringSettings::new(VIEWPORT, n as u64);
        let repeats = if n >= 1_000_000 { 5 } else { 21 };
        let (serial_ms, want) = time_ms(repeats, || cpu_assign(&view, &settings, &lights));
        let (parallel_ms, _) = time_ms(repeats, || cpu_assign_parallel(&view, &settings, &lights));
        let case = format!("{n} lights");
        let (compute, raster) = (Implementation::Compute, Implementation::Raster);
        let (fan, lookback) = (
            ScanImplementation::ScanFan,
            ScanImplementation::DecoupledLookback,
        );
        let variants = [
            (compute, fan, false, ""),
            (raster, fan, false, ""),
            (compute, lookback, false, " + decoupled_lookback scan"),
            (compute, fan, true, ", one command buffer"),
            (
                compute,
                lookback,
                true,
                " + decoupled_lookback scan, one command buffer",
            ),
        ];
        for (implementation, scan, one_buffer, suffix) in variants {
            let gpu = measure_gpu(&view, &lights, implementation, scan, one_buffer, frames)?;
            let case = format!("{case}, {}{suffix}", implementation.name());
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
