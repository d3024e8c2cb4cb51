//! The reference: the pyramid by the footprint rule, which the GPU tests compare with
//! exactly.
//!
//! Depths are compared as their bits, as the shader compares them: the rasterisers store
//! clamped non-negative depths, whose bits order like the floats, so every texel is
//! exactly one of the source depths.

use crate::extent::{PyramidExtent, pyramid_extent};

/// The depth of a visibility value: its high 32 bits as an f32 (0 for an empty pixel).
pub fn depth(value: u64) -> f32 {
    f32::from_bits((value >> 32) as u32)
}

/// A pyramid on the CPU: `levels[L]` holds level `L` row-major, `level_size(L)` of it.
#[derive(Clone, Debug, PartialEq)]
pub struct Pyramid {
    pub extent: PyramidExtent,
    pub levels: Vec<Vec<f32>>,
}

impl Pyramid {
    /// Texel `(x, y)` of level `level`.
    pub fn texel(&self, level: u32, x: u32, y: u32) -> f32 {
        let [w, _] = self.extent.level_size(level);
        self.levels[level as usize][(y * w + x) as usize]
    }
}

/// The pyramid of a `width × height` visibility target (`visibility` row-major, at least
/// `width × height` values): level 0 from 2 × 2 source pixels, each level above from the
/// 2 × 2 texels below it that exist.
pub fn build(visibility: &[u64], width: u32, height: u32) -> Pyramid {
    assert!(
        visibility.len() as u64 >= width as u64 * height as u64,
        "{} visibility values for {width} × {height}",
        visibility.len()
    );
    let extent = pyramid_extent(width, height);
    let bits: Vec<u32> = visibility[..(width * height) as usize]
        .iter()
        .map(|v| (v >> 32) as u32)
        .collect();
    let mut levels: Vec<Vec<u32>> = Vec::with_capacity(extent.mip_levels as usize);
    let mut below = (bits, [width, height]);
    for level in 0..extent.mip_levels {
        let size = extent.level_size(level);
        let reduced = reduce(&below.0, below.1, size);
        levels.push(reduced.clone());
        below = (reduced, size);
    }
    Pyramid {
        extent,
        levels: levels
            .into_iter()
            .map(|l| l.into_iter().map(f32::from_bits).collect())
            .collect(),
    }
}

/// Each texel of a `size` level: the min of the 2 × 2 texels of `below` under it, those
/// that exist.
fn reduce(below: &[u32], [bw, bh]: [u32; 2], [w, h]: [u32; 2]) -> Vec<u32> {
    let mut out = Vec::with_capacity((w * h) as usize);
    for y in 0..h {
        for x in 0..w {
            let mut m = u32::MAX;
            for sy in 2 * y..(2 * y + 2).min(bh) {
                for sx in 2 * x..(2 * x + 2).min(bw) {
                    m = m.min(below[(sy * bw + sx) as usize]);
                }
            }
            out.push(m);
        }
    }
    out
}

/// Texel `(x, y)` of level `level` straight from the rule: the min depth over source
/// pixels `[x·2^(L+1), (x+1)·2^(L+1)) × [y·2^(L+1), (y+1)·2^(L+1))` clipped to the image.
/// Slow; it checks [`build`].
pub fn footprint_min(
    visibility: &[u64],
    width: u32,
    height: u32,
    level: u32,
    x: u32,
    y: u32,
) -> f32 {
    let side = 2u64 << level;
    let xs = (x as u64 * side)..((x as u64 + 1) * side).min(width as u64);
    let ys = (y as u64 * side)..((y as u64 + 1) * side).min(height as u64);
    let mut m = u32::MAX;
    for sy in ys {
        for sx in xs.clone() {
            m = m.min((visibility[(sy * width as u64 + sx) as usize] >> 32) as u32);
        }
    }
    f32::from_bits(m)
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    fn value(depth: f32, payload: u32) -> u64 {
        (depth.to_bits() as u64) << 32 | payload as u64
    }

    #[test]
    fn a_small_image_by_hand() {
        // 3 × 5, reverse-Z depths; 0 marks an empty pixel.
        #[rustfmt::skip]
        let depths = [
            0.5, 0.25, 0.75,
            0.5, 0.5,  0.0,
            0.9, 0.8,  0.7,
            0.6, 0.1,  0.3,
            0.4, 0.2,  1.0,
        ];
        let vis: Vec<u64> = depths.iter().map(|&d| value(d, 7)).collect();
        let p = build(&vis, 3, 5);
        assert_eq!(p.extent.mip_levels, 3);
        assert_eq!(p.levels[0], vec![0.25, 0.0, 0.1, 0.3, 0.2, 1.0]);
        assert_eq!(p.levels[1], vec![0.0, 0.2]);
        assert_eq!(p.levels[2], vec![0.0]);
        assert_eq!(p.texel(0, 1, 2), 1.0);
    }

    #[test]
    fn one_pixel_is_its_own_pyramid() {
        let p = build(&[value(0.375, 1)], 1, 1);
        assert_eq!(p.levels, vec![vec![0.375]]);
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(64))]
        /// The level-by-level reduction is the rule: every texel is the min over its
        /// clipped footprint.
        #[test]
        fn levels_equal_the_footprint_rule(
            w in 1u32..70,
            h in 1u32..70,
            seed in any::<u64>(),
        ) {
            let mut s = seed | 1;
            let vis: Vec<u64> = (0..w * h)
                .map(|_| {
                    s ^= s << 13;
                    s ^= s >> 7;
                    s ^= s << 17;
                    if s % 9 == 0 { 0 } else { value((s >> 40) as f32 / (1u64 << 24) as f32, s as u32) }
                })
                .collect();
            let p = build(&vis, w, h);
            for level in 0..p.extent.mip_levels {
                let [lw, lh] = p.extent.level_size(level);
                for y in 0..lh {
                    for x in 0..lw {
                        let want = footprint_min(&vis, w, h, level, x, y);
                        prop_assert_eq!(p.texel(level, x, y).to_bits(), want.to_bits());
                    }
                }
            }
            prop_assert_eq!(p.levels.last().map(Vec::len), Some(1));
        }
    }
}
