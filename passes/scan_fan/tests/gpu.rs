//! Both implementations on a real Vulkan adapter (lavapipe in CI) against `cpu_scan`.

mod support;
use meshlight_pass_scan_fan::Subgroups;
use support::*;

/// The counts the issue names, around tile and level boundaries (16,777,217 has its own test).
const COUNTS: [u32; 8] = [0, 1, 255, 256, 257, 65_535, 65_536, 65_537];

#[test]
fn counts_at_chunk_boundaries_match_the_cpu_reference() {
    let mut exec = executor();
    let mut rng = XorShift(0x5eed_0001);
    let input = rng.values(65_537, 1000);
    for implementation in Implementation::BOTH {
        // 1: a tile is one 256-element Hillis–Steele chunk, three levels at 65,537;
        // 8: the default 2,048-element tile.
        for items in [1, 8] {
            for inclusive in [false, true] {
                for subgroups in [Subgroups::Auto, Subgroups::Off] {
                    for count in COUNTS {
                        let case = Case::new(implementation, count).items(items).inclusive(inclusive).subgroups(subgroups);
                        check(&mut exec, &case, &input);
                    }
                }
            }
        }
    }
}

#[test]
fn values_near_u32_max_wrap_modulo_two_to_the_32() {
    let mut exec = executor();
    let input = XorShift(0x5eed_0002).near_max(65_537);
    for implementation in Implementation::BOTH {
        for inclusive in [false, true] {
            for subgroups in [Subgroups::Auto, Subgroups::Off] {
                for count in [1, 257, 65_537] {
                    let case = Case::new(implementation, count).items(1).inclusive(inclusive).subgroups(subgroups);
                    check(&mut exec, &case, &input);
                }
            }
        }
    }
}

#[test]
fn gpu_count_gives_the_cpu_count_result_and_leaves_the_tail() {
    let mut exec = executor();
    const CAPACITY: u32 = 70_000;
    let input = XorShift(0x5eed_0003).values(CAPACITY as usize, u32::MAX);
    for implementation in Implementation::BOTH {
        for items in [1, 8] {
            for inclusive in [false, true] {
                // 0 and 1: below one tile; 65,537: several levels; CAPACITY + 5: clamped.
                for count in [0, 1, 256, 2_049, 65_537, CAPACITY, CAPACITY + 5] {
                    let indirect = Case::new(implementation, CAPACITY).items(items).inclusive(inclusive).gpu_count(count);
                    check(&mut exec, &indirect, &input);
                    let direct = Case::new(implementation, count.min(CAPACITY)).items(items).inclusive(inclusive);
                    let a = run(&mut exec, &indirect, &input);
                    let b = run(&mut exec, &direct, &input);
                    let n = count.min(CAPACITY) as usize;
                    assert_eq!(a.output[..n], b.output[..n], "{indirect:?} against {direct:?}");
                    assert_eq!(a.total, b.total, "{indirect:?} against {direct:?}");
                }
            }
        }
    }
}

#[test]
fn capacity_below_one_tile_with_a_gpu_count() {
    let mut exec = executor();
    let input = XorShift(0x5eed_0004).values(300, 1 << 20);
    for implementation in Implementation::BOTH {
        for count in [0, 7, 300, 1_000] {
            check(&mut exec, &Case::new(implementation, 300).gpu_count(count), &input);
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
    check(&mut exec, &Case::new(Implementation::ScanFan, n).items(1), &input);
    check(&mut exec, &Case::new(Implementation::ScanFan, n).items(1).gpu_count(n - 3), &input);
    check(&mut exec, &Case::new(Implementation::ScanFan, n).inclusive(true), &input);
    check(&mut exec, &Case::new(Implementation::TwoStep, n), &input);
}
