//! The benchmark runs end to end (on lavapipe: that it works, not how fast).

use meshlight_bench::scan_fan as bench;
use meshlight_testing::executor;

#[test]
fn benchmark_rows_cover_every_implementation_and_size() {
    let mut exec = executor();
    if !exec.gpu.features.contains(wgpu::Features::TIMESTAMP_QUERY) {
        panic!("this adapter has no TIMESTAMP_QUERY; the benchmark needs it (lavapipe has it)");
    }
    let sizes = [1 << 12, 70_001];
    let rows = bench::run(&mut exec, &sizes, 3).expect("benchmark");
    assert_eq!(rows.len(), sizes.len() * 10);
    for size in sizes {
        for name in [
            "scan_fan",
            "two_step",
            "decoupled_lookback",
            "scan_fan/staged",
            "scan_fan/vector4",
            "scan_fan/vector16",
            "decoupled_lookback/staged",
            "decoupled_lookback/vector8",
            "decoupled_lookback/vector16",
            "decoupled_lookback/serial",
        ] {
            let row = rows
                .iter()
                .find(|r| r.elements == size && r.implementation == name)
                .expect("a row per size and implementation");
            assert!(
                row.gpu_ms > 0.0
                    && row.gb_per_s.is_finite()
                    && row.copy_gb_per_s > 0.0
                    && row.copy_command_gb_per_s > 0.0
                    && row.cpu_ms >= 0.0,
                "{row:?}"
            );
            assert!((row.ratio_to_copy - row.gb_per_s / row.copy_gb_per_s).abs() < 1e-9);
        }
    }
    let table = bench::table(&rows);
    assert_eq!(table.lines().count(), rows.len() + 1);
}
