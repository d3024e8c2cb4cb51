//! Many frames of the viewer (window, overlay, scripted camera) grow the process's
//! memory no more than the renderer alone does over as many frames.
//!
//! The bare renderer's resident size grows by itself on lavapipe (about 0.9 MiB a frame
//! on Mesa 22.3, with or without a window, timing or checked mode; the time goes to
//! `queue.submit`, and the growth with it). The viewer is held to that rate, measured
//! first in the same process over 300 frames, plus 8 MiB over the whole run. On
//! lavapipe the rate's own noise (a few per cent of it) hides a leak of the viewer's
//! smaller than about 50 KiB a frame; on a driver whose frames do not grow the rate is
//! 0, and a leak of 4 KiB a frame fails.
//!
//! Prints the figures and the CPU time per frame with and without the overlay (nothing
//! here is timed). `MESHLIGHT_VIEWER_FRAMES` sets the viewer's frame count (2,000).

mod common;

use meshlight_viewer::viewer::resident_kib;

fn rss() -> i64 {
    resident_kib().expect("/proc/self/statm") as i64
}

/// Frames of the bare renderer the growth rate is measured over, after as many to warm up.
const BASELINE_FRAMES: u64 = 300;
const WARM_UP: u64 = 300;
const MARGIN_KIB: f64 = 8.0 * 1024.0;

#[test]
fn many_frames_grow_memory_no_more_than_the_renderer() {
    let x = common::xvfb();
    common::use_display(&x);
    let frames: u64 = std::env::var("MESHLIGHT_VIEWER_FRAMES")
        .ok()
        .and_then(|n| n.parse().ok())
        .unwrap_or(2_000);

    let rate = {
        let (mut r, camera) = common::bare_renderer();
        for _ in 0..WARM_UP {
            r.frame(&camera).expect("frame");
        }
        r.executor.finish().expect("finish");
        let before = rss();
        for _ in 0..BASELINE_FRAMES {
            r.frame(&camera).expect("frame");
        }
        r.executor.finish().expect("finish");
        (rss() - before).max(0) as f64 / BASELINE_FRAMES as f64
    };

    let mut o = common::small_options();
    o.orbit_frames = Some(500);
    let (_event_loop, mut v) = common::windowed(o);
    v.run_frames(WARM_UP).expect("warm-up");
    v.renderer.executor.finish().expect("finish");
    let before = rss();
    let start = std::time::Instant::now();
    v.run_frames(frames).expect("frames");
    v.renderer.executor.finish().expect("finish");
    let seconds = start.elapsed().as_secs_f64();
    let grown = rss() - before;
    let mean = |v: &meshlight_viewer::Viewer, f: fn(&meshlight_viewer::FrameTime) -> f32| {
        v.times.iter().map(f).sum::<f32>() / v.times.len().max(1) as f32
    };
    let (cpu_on, overlay_on) = (mean(&v, |t| t.cpu_ms), mean(&v, |t| t.overlay_ms));
    v.overlay_on = false;
    v.run_frames(meshlight_viewer::viewer::HISTORY as u64)
        .expect("frames");
    let cpu_off = mean(&v, |t| t.cpu_ms);
    let allowed = rate * frames as f64 + MARGIN_KIB;
    eprintln!(
        "bare renderer: {rate:.1} KiB a frame over {BASELINE_FRAMES} frames; viewer: {frames} frames in {seconds:.1} s, RSS {before} KiB → {} KiB ({grown:+} KiB, {:.1} KiB a frame, {allowed:.0} KiB allowed); CPU per frame {cpu_on:.2} ms with the overlay (of which the overlay {overlay_on:.2} ms), {cpu_off:.2} ms without",
        before + grown,
        grown as f64 / frames as f64
    );
    assert!(
        (grown as f64) <= allowed,
        "the viewer's RSS grew by {grown} KiB over {frames} frames, more than the renderer's own {rate:.1} KiB a frame plus {MARGIN_KIB} KiB"
    );
}
