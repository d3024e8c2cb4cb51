//! Every implementation on a real Vulkan adapter (lavapipe in CI) against `cpu_scan`.

mod support;
use meshlight_pass_scan_fan::{Subgroups, TileAccess};
use support::*;

/// The counts the issue names, around tile and level boundaries (16,777,217 has its own test).
const COUNTS: [u32; 8] = [0, 1, 255, 256, 257, 65_535, 65_536, 65_537];

#[test]
fn counts_at_chunk_boundaries_match_the_cpu_reference() {
    let mut exec = executor();
    let mut rng = XorShift(0x5eed_0001);
    let input = rng.values(65_537, 1000);
    // 1: a tile is one 256-element chunk, three levels at 65,537; 8: the default
    // 2,048-element tile. Vector tiles (the default) and staged ones.
    Matrix::new(&Implementation::ALL)
        .items(&[1, 8])
        .both_subgroups()
        .access(&[TileAccess::Vector, TileAccess::Staged])
        .each(|case| {
            for count in COUNTS {
                check(&mut exec, &case.count(count), &input);
            }
        });
}

#[test]
fn values_near_u32_max_wrap_modulo_two_to_the_32() {
    let mut exec = executor();
    let input = XorShift(0x5eed_0002).near_max(65_537);
    Matrix::new(&Implementation::ALL)
        .items(&[1])
        .both_subgroups()
        .each(|case| {
            for count in [1, 257, 65_537] {
                check(&mut exec, &case.count(count), &input);
            }
        });
}

#[test]
fn gpu_count_gives_the_cpu_count_result_and_leaves_the_tail() {
    let mut exec = executor();
    const CAPACITY: u32 = 70_000;
    let input = XorShift(0x5eed_0003).values(CAPACITY as usize, u32::MAX);
    Matrix::new(&Implementation::ALL)
        .items(&[1, 8])
        .each(|case| {
            // 0 and 1: below one tile; 65,537: several levels; CAPACITY + 5: clamped.
            for count in [0, 1, 256, 2_049, 65_537, CAPACITY, CAPACITY + 5] {
                let indirect = case.count(CAPACITY).gpu_count(count);
                check(&mut exec, &indirect, &input);
                let direct = case.count(count.min(CAPACITY));
                let a = run(&mut exec, &indirect, &input);
                let b = run(&mut exec, &direct, &input);
                let n = count.min(CAPACITY) as usize;
                assert_eq!(
                    a.output[..n],
                    b.output[..n],
                    "{indirect:?} against {direct:?}"
                );
                assert_eq!(a.total, b.total, "{indirect:?} against {direct:?}");
            }
        });
}

#[test]
fn capacity_below_one_tile_with_a_gpu_count() {
    let mut exec = executor();
    let input = XorShift(0x5eed_0004).values(300, 1 << 20);
    for implementation in Implementation::ALL {
        for count in [0, 7, 300, 1_000] {
            check(
                &mut exec,
                &Case::new(implementation, 300).gpu_count(count),
                &input,
            );
        }
    }
}

/// 16,777,217 elements: with 256-element tiles that is 65,537 workgroups, past the
/// 65,535 per-dimension limit, so the 2-D grid is exercised both directly and indirectly.
/// Each configuration runs once; inclusive and the subgroup switch are covered above.
#[test]
fn sixteen_million_elements() {
    let mut exec = executor();
    let n = 16_777_217;
    let input = XorShift(0x5eed_0005).values(n as usize, 1 << 12);
    use Implementation::{DecoupledLookback, ScanFan, TwoStep};
    for case in [
        Case::new(ScanFan, n).items(1),
        Case::new(ScanFan, n).items(1).gpu_count(n - 3),
        Case::new(ScanFan, n).inclusive(true),
        Case::new(TwoStep, n),
        Case::new(TwoStep, n).inclusive(true),
        // 65,537 tiles of 256: a 2-D grid, and thousands of look-backs in flight.
        Case::new(DecoupledLookback, n).items(1),
        Case::new(DecoupledLookback, n)
            .items(1)
            .inclusive(true)
            .gpu_count(n - 3),
    ] {
        check(&mut exec, &case, &input);
    }
}

/// The single-pass scan around its tile boundaries and at 2^20: tile sizes, both modes,
/// the subgroup look-back and the one-lane one, staged and direct tiles, the count from
/// the CPU and from the GPU; many tiles, so workgroups really do wait on each other's
/// published totals.
#[test]
fn decoupled_lookback_at_tile_boundaries_and_two_to_the_20() {
    let mut exec = executor();
    let n = 1 << 20;
    let input = XorShift(0x5eed_0007).values(n as usize, u32::MAX);
    for (items, subgroups, access) in [
        (1, Subgroups::Auto, TileAccess::Staged),
        (4, Subgroups::Off, TileAccess::Staged),
        (16, Subgroups::Auto, TileAccess::Direct),
        (8, Subgroups::Off, TileAccess::Direct),
    ] {
        let tile = 256 * items;
        Matrix::new(&[Implementation::DecoupledLookback])
            .items(&[items])
            .subgroups(&[subgroups])
            .access(&[access])
            .each(|case| {
                for count in [1, tile - 1, tile, tile + 1, 5 * tile + 3, n] {
                    check(&mut exec, &case.count(count), &input);
                    check(&mut exec, &case.count(n).gpu_count(count), &input);
                }
            });
    }
}

/// Direct tile access (each lane its own run) in the fan scans, at the counts around
/// tile and level boundaries, both modes, with a GPU count too.
#[test]
fn direct_tile_access_matches_the_cpu_reference() {
    let mut exec = executor();
    let input = XorShift(0x5eed_0009).values(70_000, u32::MAX);
    Matrix::new(&[Implementation::ScanFan, Implementation::TwoStep])
        .items(&[1, 8, 16])
        .access(&[TileAccess::Direct])
        .each(|case| {
            for count in COUNTS {
                check(&mut exec, &case.count(count), &input);
            }
            check(&mut exec, &case.count(70_000).gpu_count(65_537), &input);
        });
}

/// The tile counter and flags are cleared every frame: a second frame of the same graph
/// must give the same result, not wait on flags left from the first or start past tile 0.
#[test]
fn decoupled_lookback_runs_frame_after_frame() {
    let mut exec = executor();
    let n = 100_000u32;
    let input = XorShift(0x5eed_0008).values(n as usize, 1000);
    let (expected, total) = meshlight_pass_scan_fan::cpu_scan(&input, false);
    let case = Case::new(Implementation::DecoupledLookback, n).items(2);
    let compiled = graph(&exec, &case);
    for frame_index in 0..3 {
        let got = frame(&mut exec, &compiled, &case, &input);
        assert!(
            got.output == expected,
            "frame {frame_index}: output differs from the CPU"
        );
        assert_eq!(got.total, total, "frame {frame_index}");
    }
}

#[test]
fn random_sizes_values_and_options() {
    use proptest::prelude::*;
    use proptest::test_runner::{Config, TestRunner};
    let exec = std::cell::RefCell::new(executor());
    let strategy = (
        1u32..300_000,
        any::<u64>(),
        prop::sample::select(Implementation::ALL.to_vec()),
        any::<bool>(),
        any::<bool>(),
        prop::sample::select(vec![1u32, 2, 4, 8, 16]),
        any::<bool>(),
        any::<bool>(),
    );
    let mut runner = TestRunner::new(Config {
        cases: 24,
        failure_persistence: None,
        ..Config::default()
    });
    runner
        .run(
            &strategy,
            |(count, seed, which, inclusive, subgroups_off, items, near_max, direct)| {
                let mut rng = XorShift(seed | 1);
                let input = if near_max {
                    rng.near_max(count as usize)
                } else {
                    rng.values(count as usize, u32::MAX)
                };
                let implementation = which;
                let subgroups = if subgroups_off {
                    Subgroups::Off
                } else {
                    Subgroups::Auto
                };
                let access = if direct {
                    TileAccess::Direct
                } else {
                    TileAccess::Staged
                };
                let case = Case::new(implementation, count)
                    .inclusive(inclusive)
                    .subgroups(subgroups)
                    .items(items)
                    .access(access);
                check(&mut exec.borrow_mut(), &case, &input);
                Ok(())
            },
        )
        .unwrap();
}

/// The registry builds every implementation from a pipeline file, and swapping the
/// `implementation` line gives the same result.
#[test]
fn pipeline_file_builds_every_implementation() {
    use meshlight_graph::file::{Registry, parse_pipeline};
    use meshlight_graph::*;
    use meshlight_testing::{frames::filled, run_graph};
    let mut registry = Registry::new();
    meshlight_pass_scan_fan::register(&mut registry);
    let n = 5_000u32;
    let input = XorShift(0x5eed_0006).values(n as usize, 100);
    let (expected, total) = meshlight_pass_scan_fan::cpu_scan(&input, true);
    let mut exec = executor();
    for implementation in ["scan_fan", "two_step", "decoupled_lookback"] {
        let text = format!(
            r#"
[[resource]]
name = "counts"
kind = "imported"
buffer = {{ element = "u32", count = {n} }}
usage = ["STORAGE", "COPY_SRC", "COPY_DST"]
[[resource]]
name = "offsets"
kind = "exported"
buffer = {{ element = "u32", count = {n} }}
[[resource]]
name = "total"
kind = "exported"
buffer = {{ element = "u32", count = 1 }}
[[pass]]
name = "scan"
stage = "scan_fan"
implementation = "{implementation}"
params = {{ count = {n}, inclusive = true, subgroups = "off", items_per_thread = 4 }}
bind = {{ input = "counts", output = "offsets" }}
"#
        );
        let g = parse_pipeline(&text, "inline.toml", &registry).unwrap();
        let counts = filled("counts", Element::U32, &input);
        let frame = FrameData::new();
        let [offsets, got_total] =
            run_graph(&mut exec, g, &[counts], &["offsets", "total"], &frame)
                .unwrap()
                .try_into()
                .unwrap();
        let offsets: Vec<u32> = bytemuck::pod_collect_to_vec(&offsets);
        let got_total: Vec<u32> = bytemuck::pod_collect_to_vec(&got_total);
        assert_eq!(offsets, expected, "{implementation}");
        assert_eq!(got_total[0], total, "{implementation}");
    }
}

/// Vector tiles (16-byte words held in registers) in every implementation: counts that are
/// and are not multiples of 4 around word, tile and level boundaries (a partial last word
/// goes through the u32 view), capacities under 4 (the staged kernels run), every
/// `items_per_thread` (below 4 a lane's one word is narrower), both modes, subgroups on and
/// off, a GPU count that leaves a partial word, and `scan_fan`'s one-workgroup walk of up
/// to four tiles (`4 × tile`) and the fan just past it.
#[test]
fn vector_tile_access_matches_the_cpu_reference() {
    let mut exec = executor();
    let input = XorShift(0x5eed_000a).values(140_000, u32::MAX);
    Matrix::new(&Implementation::ALL)
        .items(&[1, 2, 4, 8, 16, 32])
        .both_subgroups()
        .each(|case| {
            let tile = case.options.tile();
            for count in [
                0,
                1,
                3,
                4,
                5,
                7,
                tile - 1,
                tile + 2,
                3 * tile + 1,
                4 * tile,
                4 * tile + 1,
                131_075,
            ] {
                check(&mut exec, &case.count(count), &input);
            }
            if case.options.subgroups == Subgroups::Auto {
                for count in [0, 2, 6, tile + 3, 131_073] {
                    check(&mut exec, &case.count(131_075).gpu_count(count), &input);
                }
            }
        });
}
