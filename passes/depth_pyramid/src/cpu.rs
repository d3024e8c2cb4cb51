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
        let [w, h] = self.extent.level_size(level);
        assert!(
            x < w && y < h,
            "texel ({x}, {y}) outside level {level}'s {w} × {h}"
        );
        self.levels[level as usize][(y * w + x) as usize]
    }
}

impl Pyramid {
    /// A conservative depth for the pixel rectangle `[x0, x1] × [y0, y1]` (inclusive, in
    /// source pixels, clamped to the image): the min of the at most 2 × 2 texels of the
    /// lowest level where the rectangle spans at most two texels a side. Their footprints
    /// cover the rectangle, so this is never nearer than any pixel in it; and since the
    /// rectangle lies in the image, those texels lie inside the level. One way to read
    /// the pyramid for an occlusion test; the tests use it to show both properties.
    pub fn farthest_under(&self, [x0, y0]: [u32; 2], [x1, y1]: [u32; 2]) -> f32 {
        let top = self.extent.mip_levels - 1;
        let level = (0..=top)
            .find(|&l| {
                (x1 >> (l + 1)) - (x0 >> (l + 1)) <= 1 && (y1 >> (l + 1)) - (y0 >> (l + 1)) <= 1
            })
            .unwrap_or(top);
        let shift = level + 1;
        let mut m = f32::INFINITY;
        for y in (y0 >> shift)..=(y1 >> shift) {
            for x in (x0 >> shift)..=(x1 >> shift) {
                m = m.min(self.texel(level, x, y));
            }
        }
        m
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

    /// `w × h` visibility values from an xorshift seeded by `seed`: about one in
    /// `empty_every` empty, the rest at random depths, with random cluster ids when
    /// `random_ids` (else id 0).
    fn random_visibility(
        w: u32,
        h: u32,
        seed: u64,
        empty_every: u64,
        random_ids: bool,
    ) -> Vec<u64> {
        let mut s = seed | 1;
        (0..w * h)
            .map(|_| {
                s ^= s << 13;
                s ^= s >> 7;
                s ^= s << 17;
                let id = if random_ids { s as u32 } else { 0 };
                if s.is_multiple_of(empty_every) {
                    0
                } else {
                    value((s >> 40) as f32 / (1u64 << 24) as f32, id)
                }
            })
            .collect()
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
            let vis = random_visibility(w, h, seed, 9, true);
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

        /// A rectangle read through the pyramid is never nearer than its farthest pixel,
        /// and the texels it reads are inside their level (`texel` would index past the
        /// level otherwise and panic).
        #[test]
        fn a_rectangle_read_is_conservative(
            w in 1u32..300,
            h in 1u32..300,
            corners in any::<[u32; 4]>(),
            seed in any::<u64>(),
        ) {
            let vis = random_visibility(w, h, seed, 50, false);
            let p = build(&vis, w, h);
            let [a, b, c, d] = corners;
            let (xa, xb) = (a % w, b % w);
            let (ya, yb) = (c % h, d % h);
            let (x0, x1, y0, y1) = (xa.min(xb), xa.max(xb), ya.min(yb), ya.max(yb));
            let got = p.farthest_under([x0, y0], [x1, y1]);
            let mut farthest = f32::INFINITY;
            for y in y0..=y1 {
                for x in x0..=x1 {
                    farthest = farthest.min(depth(vis[(y * w + x) as usize]));
                }
            }
            prop_assert!(got <= farthest, "{w}×{h} [{x0}, {x1}] × [{y0}, {y1}]: {got} > {farthest}");
            // And exactly the min over the footprints of the texels read: the smallest
            // aligned square blocks of 2^(L+1) pixels, at most 2 × 2 of them, that hold
            // the rectangle.
            let shift = (1..=p.extent.mip_levels)
                .find(|&s| (x1 >> s) - (x0 >> s) <= 1 && (y1 >> s) - (y0 >> s) <= 1)
                .unwrap_or(p.extent.mip_levels);
            let mut covered = f32::INFINITY;
            for y in (y0 >> shift << shift)..(((y1 >> shift) + 1) << shift).min(h) {
                for x in (x0 >> shift << shift)..(((x1 >> shift) + 1) << shift).min(w) {
                    covered = covered.min(depth(vis[(y * w + x) as usize]));
                }
            }
            prop_assert_eq!(got.to_bits(), covered.to_bits());
        }
    }
}
