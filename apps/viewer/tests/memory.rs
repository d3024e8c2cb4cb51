//! Many frames with the overlay on do not grow the process's memory. Prints the resident
//! size before and after, and the CPU time per frame with and without the overlay
//! (figures only: nothing here is timed). `MESHLIGHT_VIEWER_FRAMES` sets the count.

mod common;

fn rss_kib() -> u64 {
    let statm = std::fs::read_to_string("/proc/self/statm").expect("/proc/self/statm");
    let pages: u64 = statm
        .split_whitespace()
        .nth(1)
        .and_then(|p| p.parse().ok())
        .expect("resident pages");
    pages * 4
}

fn mean_cpu_ms(v: &meshlight_viewer::Viewer) -> f32 {
    v.times.iter().map(|t| t.cpu_ms).sum::<f32>() / v.times.len().max(1) as f32
}

#[test]
fn many_frames_do_not_grow_memory() {
    let x = common::xvfb();
    common::use_display(&x);
    let frames: u64 = std::env::var("MESHLIGHT_VIEWER_FRAMES")
        .ok()
        .and_then(|n| n.parse().ok())
        .unwrap_or(2_000);
    let mut o = common::small_options();
    o.orbit_frames = Some(500);
    let (_event_loop, mut v) = common::windowed(o);
    v.run_frames(300).expect("warm-up");
    let before = rss_kib();
    let start = std::time::Instant::now();
    v.run_frames(frames).expect("frames");
    let seconds = start.elapsed().as_secs_f64();
    let after = rss_kib();
    let with_overlay = mean_cpu_ms(&v);
    v.overlay_on = false;
    v.run_frames(crate::HISTORY_FRAMES).expect("frames");
    let without = mean_cpu_ms(&v);
    eprintln!(
        "{frames} frames in {seconds:.1} s: RSS {before} KiB before, {after} KiB after ({:+} KiB); CPU per frame {with_overlay:.2} ms with the overlay, {without:.2} ms without",
        after as i64 - before as i64
    );
    // Allocator noise and driver caches settle within the warm-up; a leak of even 1 KiB
    // a frame would pass 2 MiB here.
    assert!(
        after <= before + 2 * 1024,
        "RSS grew from {before} KiB to {after} KiB over {frames} frames"
    );
}

const HISTORY_FRAMES: u64 = meshlight_viewer::viewer::HISTORY as u64;
