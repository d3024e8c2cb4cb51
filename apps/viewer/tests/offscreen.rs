//! The viewer without a display: frames drawn into a texture, timed, memory sampled. It is
//! what `meshlight view --offscreen` runs on a GPU server; here on lavapipe, that it
//! works and its figures are consistent, not how fast anything is.

mod common;

use meshlight_viewer::offscreen::{CountingAllocator, run_offscreen};

#[global_allocator]
static ALLOCATOR: CountingAllocator = CountingAllocator;

#[test]
fn offscreen_runs_time_the_overlay_and_sample_memory() {
    // Unlit, so the two runs' images below compare exactly.
    let (mut with, report) =
        run_offscreen(common::unlit_options(), 2, 6, 2).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!((report.warmup, report.frames), (2, 6));
    assert_eq!(with.frames, 8);
    assert!(report.wall_ms > 0.0 && report.cpu_ms > 0.0, "{report:?}");
    assert!(
        report.cpu_ms >= report.graph_ms + report.overlay_ms,
        "{report:?}"
    );
    assert!(
        report.overlay_ms > 0.0,
        "the overlay was not drawn: {report:?}"
    );
    let frames: Vec<u64> = report.memory.iter().map(|m| m.frame).collect();
    assert_eq!(frames, [2, 4, 6, 8]);
    assert!(
        report
            .memory
            .iter()
            .all(|m| m.resident_kib > 0 && m.pool_bytes > 0)
    );
    // This binary counts Rust's allocations (as `meshlight` does): they are part of the
    // C allocator's bytes in use, which include the driver's.
    for m in &report.memory {
        let (heap, rust) = (
            m.heap_kib.expect("glibc"),
            m.rust_heap_kib.expect("counted"),
        );
        assert!(rust > 0 && rust <= heap, "{m:?}");
    }
    let text = report.text();
    assert!(
        text.contains("overlay_ms ") && text.contains("memory frame 8 "),
        "{text}"
    );

    let mut options = common::unlit_options();
    options.no_overlay = true;
    let (mut without, bare) = run_offscreen(options, 2, 4, 4).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(bare.overlay_ms, 0.0, "{bare:?}");
    // The graph's image is the same with the overlay or without: it is drawn over the
    // window's copy, never into the frame.
    let a = with.read_image().expect("image").2;
    let b = without.read_image().expect("image").2;
    assert_eq!(common::differing(&a, &b, 0), 0);
}
