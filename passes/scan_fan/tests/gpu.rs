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
