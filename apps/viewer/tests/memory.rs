//! Many frames of the viewer (window, overlay, scripted camera) leave the memory that
//! meshlight, wgpu and egui hold where it was after the warm-up, and the graph's GPU pool
//! unchanged.
//!
//! The process's resident size is no measure of that on lavapipe: Mesa's software driver
//! `malloc`s about a mebibyte a frame of its own (glibc's bytes in use grow by that much
//! while Rust's stay put), with or without a window, timing or checked mode. So this
//! binary counts Rust's allocations with the viewer's `CountingAllocator`, as `meshlight`
//! does, and holds them to a few hundred KiB over the run; the driver's share and the
//! resident size are printed, not checked. The warm-up fills the overlay's chart
//! (`HISTORY` frames), which is the last thing to grow. On the GPU machine the same
//! figures over 10,000 frames are in docs/BENCHMARKS.md (`view --offscreen`).
//!
//! Prints the figures and the CPU time per frame with and without the overlay (nothing
//! here is timed). `MESHLIGHT_VIEWER_FRAMES` sets the measured frames (600).

mod common;

use meshlight_viewer::offscreen::CountingAllocator;
use meshlight_viewer::viewer::{HISTORY, resident_kib};

#[global_allocator]
static ALLOCATOR: CountingAllocator = CountingAllocator;

/// Frames before measuring: the chart's history filled, and some.
const WARM_UP: u64 = HISTORY as u64 + 60;
/// What Rust's heap may differ by between the first sample and any later one.
const MARGIN_KIB: i64 = 256;

/// (Rust's heap, the C heap in use, resident), in KiB.
fn sample() -> (i64, i64, i64) {
    let heap = meshlight_viewer::offscreen::heap_kib().expect("glibc's mallinfo");
    let rust = meshlight_viewer::offscreen::rust_heap_kib().expect("counted allocations");
    let resident = resident_kib().expect("/proc/self/statm");
    (rust as i64, heap as i64, resident as i64)
}

#[test]
fn many_frames_leave_meshlights_memory_where_it_was() {
    let _x = common::xvfb();
    let frames: u64 = std::env::var("MESHLIGHT_VIEWER_FRAMES")
        .ok()
        .and_then(|n| n.parse().ok())
        .unwrap_or(600);

    let mut o = common::small_options();
    o.orbit_frames = Some(500);
    let (_event_loop, mut v) = common::windowed(o);
    v.run_frames(WARM_UP).expect("warm-up");
    v.renderer.executor.finish().expect("finish");
    let pool = |v: &meshlight_viewer::Viewer| v.last_stats.as_ref().map(|s| s.pool_bytes_held);
    let pool_before = pool(&v);
    let first = sample();
    let mut samples = vec![first];
    let start = std::time::Instant::now();
    let step = (frames / 6).max(1);
    let mut run = 0;
    while run < frames {
        let n = step.min(frames - run);
        v.run_frames(n).expect("frames");
        v.renderer.executor.finish().expect("finish");
        run += n;
        samples.push(sample());
    }
    let seconds = start.elapsed().as_secs_f64();
    let mean = |v: &meshlight_viewer::Viewer, f: fn(&meshlight_viewer::FrameTime) -> f32| {
        v.times.iter().map(f).sum::<f32>() / v.times.len().max(1) as f32
    };
    let (cpu_on, overlay_on) = (mean(&v, |t| t.cpu_ms), mean(&v, |t| t.overlay_ms));
    let pool_after = pool(&v);
    v.overlay_on = false;
    v.run_frames(HISTORY as u64).expect("frames");
    let cpu_off = mean(&v, |t| t.cpu_ms);

    let last = *samples.last().expect("samples");
    let per_frame = |a: i64, b: i64| (b - a) as f64 / frames as f64;
    eprintln!(
        "viewer: {frames} frames in {seconds:.1} s after {WARM_UP}; Rust's heap {} → {} KiB; the driver's (C heap less Rust's) {} → {} KiB ({:.1} KiB a frame); resident {} → {} KiB ({:.1} KiB a frame); CPU per frame {cpu_on:.2} ms with the overlay (of which the overlay {overlay_on:.2} ms), {cpu_off:.2} ms without",
        first.0,
        last.0,
        first.1 - first.0,
        last.1 - last.0,
        per_frame(first.1 - first.0, last.1 - last.0),
        first.2,
        last.2,
        per_frame(first.2, last.2),
    );
    let rust: Vec<i64> = samples.iter().map(|s| s.0).collect();
    assert!(
        rust.iter().all(|&r| (r - first.0).abs() <= MARGIN_KIB),
        "Rust's heap moved by more than {MARGIN_KIB} KiB over {frames} frames (KiB, every {step} frames): {rust:?}"
    );
    assert_eq!(
        pool_before, pool_after,
        "the graph's GPU pool changed size after the warm-up"
    );
}
