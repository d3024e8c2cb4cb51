//! `meshlight::dispatch`: workgroup counts past the per-dimension limit as a 2-D grid.

/// `n` workgroups as `[x, y, 1]` under `max_per_dimension` (the WGSL `fold_dispatch`):
/// `x = min(n, m)`, `y = ceil(n / x)` capped at `m`; `[0, 0, 1]` for none.
pub fn fold_dispatch(n: u32, max_per_dimension: u32) -> [u32; 3] {
    let m = max_per_dimension.max(1);
    let x = n.min(m);
    let y = if x == 0 { 0 } else { n.div_ceil(x).min(m) };
    [x, y, 1]
}

/// The linear index of workgroup `wg` in a grid `x_size` workgroups wide.
pub fn linear_workgroup(wg: [u32; 3], x_size: u32) -> u32 {
    wg[1] * x_size + wg[0]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_workgroup_below_the_count_has_one_index_under_the_limit() {
        for m in [1u32, 3, 7, 65_535] {
            for n in [0u32, 1, 2, m, m + 1, 3 * m + 2, 100_000] {
                let [x, y, z] = fold_dispatch(n, m);
                assert!(x <= m && y <= m && z == 1, "{n} under {m}");
                if n <= m.saturating_mul(m) {
                    assert!(x as u64 * y as u64 >= n as u64, "{n} under {m}");
                }
                let mut seen = vec![false; n as usize];
                for wy in 0..y {
                    for wx in 0..x {
                        let i = linear_workgroup([wx, wy, 0], x);
                        if i < n {
                            assert!(!std::mem::replace(&mut seen[i as usize], true));
                        }
                    }
                }
                if n <= m.saturating_mul(m) {
                    assert!(seen.iter().all(|&s| s), "{n} under {m}");
                }
            }
        }
    }
}
