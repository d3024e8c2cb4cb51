//! The CPU reference every GPU test compares against, and the benchmark's CPU baseline.

/// Prefix sums of `input` and their total, all modulo 2^32.
///
/// Exclusive: `out[i] = input[0] + … + input[i - 1]` (so `out[0] = 0`); inclusive:
/// `out[i] = input[0] + … + input[i]`.
pub fn cpu_scan(input: &[u32], inclusive: bool) -> (Vec<u32>, u32) {
    let mut out = vec![0; input.len()];
    let total = cpu_scan_into(input, &mut out, inclusive);
    (out, total)
}

/// [`cpu_scan`] into a caller's buffer (the benchmark times this, without allocation).
///
/// # Panics
/// When `out` is shorter than `input`.
pub fn cpu_scan_into(input: &[u32], out: &mut [u32], inclusive: bool) -> u32 {
    let mut running = 0u32;
    for (o, &v) in out[..input.len()].iter_mut().zip(input) {
        let next = running.wrapping_add(v);
        *o = if inclusive { next } else { running };
        running = next;
    }
    running
}

#[cfg(test)]
mod tests {
    use super::cpu_scan;

    #[test]
    fn exclusive_and_inclusive_of_a_small_array() {
        assert_eq!(cpu_scan(&[3, 1, 4, 1, 5], false), (vec![0, 3, 4, 8, 9], 14));
        assert_eq!(cpu_scan(&[3, 1, 4, 1, 5], true), (vec![3, 4, 8, 9, 14], 14));
        assert_eq!(cpu_scan(&[], false), (vec![], 0));
    }

    #[test]
    fn sums_wrap_modulo_two_to_the_32() {
        assert_eq!(
            cpu_scan(&[u32::MAX, 2, u32::MAX], false),
            (vec![0, u32::MAX, 1], 0)
        );
        assert_eq!(
            cpu_scan(&[u32::MAX, 2, u32::MAX], true),
            (vec![u32::MAX, 1, 0], 0)
        );
    }
}
