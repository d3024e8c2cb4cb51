//! The CPU reference every GPU test compares against, and the benchmark's CPU baseline.

/// Prefix sums of `input` and their total, all modulo 2^32.
///
/// Exclusive: `out[i] = input[0] + … + input[i - 1]` (so `out[0] = 0`); inclusive:
/// `out[i] = input[0] + … + input[i]`.
pub fn cpu_scan(input: &[u32], inclusive: bool) -> (Vec<u32>, u32) {
    let mut out = Vec::with_capacity(input.len());
    let mut running = 0u32;
    for &v in input {
        if inclusive {
            running = running.wrapping_add(v);
            out.push(running);
        } else {
            out.push(running);
            running = running.wrapping_add(v);
        }
    }
    (out, running)
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
        assert_eq!(cpu_scan(&[u32::MAX, 2, u32::MAX], false), (vec![0, u32::MAX, 1], 0));
        assert_eq!(cpu_scan(&[u32::MAX, 2, u32::MAX], true), (vec![u32::MAX, 1, 0], 0));
    }
}
