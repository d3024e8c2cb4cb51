//! `meshlight::occlusion` in Rust: the sphere's screen rectangle, the pyramid level and
//! the conservative test, mirrored operation for operation in f32, plus a reference
//! depth pyramid built by the rule the WGSL module reads it with.

use super::matrix::mat_vec;

/// `OCCLUSION_MARGIN_PX`.
pub const MARGIN_PX: f32 = 1.0;
/// `OCCLUSION_RADIUS_SLACK`.
pub const RADIUS_SLACK: f32 = 1e-5;
/// `OCCLUSION_DEPTH_SLACK`.
pub const DEPTH_SLACK: f32 = 1.0 + 1.0 / 256.0;

/// `OcclusionRect`.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct OcclusionRect {
    /// Whether the sphere can be tested: every corner in front of the near plane and the
    /// rectangle wholly on the screen. Untestable spheres are kept.
    pub testable: bool,
    /// Inclusive pixel range: x0, y0, x1, y1.
    pub pixels: [u32; 4],
    /// The sphere's nearest NDC depth (reverse-Z: the largest), compared with the pyramid.
    pub depth: f32,
    /// The rectangle before the margin and the on-screen check (`lo.x, lo.y, hi.x,
    /// hi.y` in pixels; 0 when a corner was not in front of the near plane), so a test
    /// can tell how near a decision came to flipping.
    pub screen: [f32; 4],
}

/// `occlusion_rect`.
pub fn occlusion_rect(
    view_projection: &[[f32; 4]; 4],
    viewport: [f32; 2],
    center: [f32; 3],
    radius: f32,
) -> OcclusionRect {
    let mut rect = OcclusionRect::default();
    let largest = center[0].abs().max(center[1].abs().max(center[2].abs()));
    let r = radius + RADIUS_SLACK * (largest + radius);
    let c = mat_vec(view_projection, [center[0], center[1], center[2], 1.0]);
    let axis = |a: usize| view_projection[a].map(|v| v * r);
    let (ex, ey, ez) = (axis(0), axis(1), axis(2));
    let mut lo = [f32::MAX; 2];
    let mut hi = [-f32::MAX; 2];
    let mut depth = 0.0f32;
    for k in 0..8u32 {
        let pick = |e: [f32; 4], bit: u32| {
            if k & bit != 0 { e } else { e.map(|v| -v) }
        };
        let (x, y, z) = (pick(ex, 1), pick(ey, 2), pick(ez, 4));
        let clip: [f32; 4] = std::array::from_fn(|i| c[i] + x[i] + y[i] + z[i]);
        if !(clip[3] > 0.0 && clip[2] < clip[3]) {
            return rect;
        }
        let ndc = [clip[0] / clip[3], clip[1] / clip[3], clip[2] / clip[3]];
        let screen = [
            (ndc[0] * 0.5 + 0.5) * viewport[0],
            (0.5 - ndc[1] * 0.5) * viewport[1],
        ];
        for a in 0..2 {
            lo[a] = lo[a].min(screen[a]);
            hi[a] = hi[a].max(screen[a]);
        }
        depth = depth.max(ndc[2]);
    }
    rect.screen = [lo[0], lo[1], hi[0], hi[1]];
    rect.depth = depth;
    let lo = lo.map(|v| v - MARGIN_PX);
    let hi = hi.map(|v| v + MARGIN_PX);
    if !(lo[0] >= 0.0 && lo[1] >= 0.0 && hi[0] < viewport[0] && hi[1] < viewport[1]) {
        return rect;
    }
    rect.testable = true;
    rect.pixels = [lo[0] as u32, lo[1] as u32, hi[0] as u32, hi[1] as u32];
    rect
}

/// `occlusion_level`.
pub fn occlusion_level(pixels: [u32; 4]) -> u32 {
    let extent = (pixels[2] - pixels[0]).max(pixels[3] - pixels[1]).max(1);
    31 - extent.leading_zeros()
}

/// A depth pyramid by the rule of `meshlight::occlusion`: level `L` is
/// `ceil(W / 2^(L+1)) × ceil(H / 2^(L+1))`, each texel the minimum (farthest) depth of
/// the source pixels it covers, down to 1 × 1. The one CPU pyramid: the `depth_pyramid`
/// stage is compared with it exactly, and the culling references test against it.
///
/// Depths are reverse-Z and never negative (the rasterisers clamp them), so the float
/// minimum taken here is the shader's minimum of their bits, and every texel is exactly
/// one of the source depths.
#[derive(Clone, Debug, PartialEq)]
pub struct DepthPyramid {
    /// Per level: width, height, texels row by row.
    pub levels: Vec<(u32, u32, Vec<f32>)>,
}

/// The depth of a visibility value: its high 32 bits as an f32 (0, the far plane, for an
/// empty pixel).
pub fn visibility_depth(value: u64) -> f32 {
    f32::from_bits((value >> 32) as u32)
}

impl DepthPyramid {
    /// The pyramid of a `width × height` reverse-Z depth image (row-major): level 0 from
    /// 2 × 2 source pixels, each level above from the 2 × 2 texels below it that exist.
    pub fn from_depth(width: u32, height: u32, depth: &[f32]) -> Self {
        assert_eq!(depth.len(), (width * height) as usize, "depth image size");
        let mut levels: Vec<(u32, u32, Vec<f32>)> = Vec::new();
        let mut below_size = [width, height];
        loop {
            let size = below_size.map(|side| side.div_ceil(2));
            let below = levels.last().map_or(depth, |(_, _, texels)| texels);
            let texels = reduce(below, below_size, size);
            levels.push((size[0], size[1], texels));
            if size == [1, 1] {
                return Self { levels };
            }
            below_size = size;
        }
    }

    /// The pyramid of the first `width × height` values of a visibility target (row-major,
    /// the depth in each value's high 32 bits), as the `depth_pyramid` stage builds it.
    pub fn from_visibility(visibility: &[u64], width: u32, height: u32) -> Self {
        let pixels = (width * height) as usize;
        assert!(
            visibility.len() >= pixels,
            "{} visibility values for {width} × {height}",
            visibility.len()
        );
        let depth: Vec<f32> = visibility[..pixels]
            .iter()
            .map(|&v| visibility_depth(v))
            .collect();
        Self::from_depth(width, height, &depth)
    }

    /// The size of `level`: `[width, height]`.
    pub fn level_size(&self, level: u32) -> [u32; 2] {
        let (w, h, _) = &self.levels[level as usize];
        [*w, *h]
    }

    /// Texel `(x, y)` of `level`; a coordinate past the level's size panics, so a reader
    /// that strays outside a level is caught rather than handed the next row's texel.
    pub fn texel(&self, level: u32, x: u32, y: u32) -> f32 {
        let (w, h, texels) = &self.levels[level as usize];
        assert!(
            x < *w && y < *h,
            "texel ({x}, {y}) outside level {level}'s {w} × {h}"
        );
        texels[(y * w + x) as usize]
    }

    /// `pyramid_farthest`.
    pub fn farthest(&self, pixels: [u32; 4]) -> f32 {
        let level = occlusion_level(pixels);
        if level as usize >= self.levels.len() {
            return 0.0;
        }
        let shift = level + 1;
        let lo = [pixels[0] >> shift, pixels[1] >> shift];
        let hi = [pixels[2] >> shift, pixels[3] >> shift];
        let mut farthest = f32::MAX;
        for y in lo[1]..=hi[1] {
            for x in lo[0]..=hi[0] {
                farthest = farthest.min(self.texel(level, x, y));
            }
        }
        farthest
    }

    /// `sphere_occluded`.
    pub fn occludes(&self, rect: &OcclusionRect) -> bool {
        rect.testable && rect.depth * DEPTH_SLACK < self.farthest(rect.pixels)
    }
}

/// Each texel of a `size` level: the min of the 2 × 2 texels of `below` under it, those
/// that exist.
fn reduce(below: &[f32], [bw, bh]: [u32; 2], [w, h]: [u32; 2]) -> Vec<f32> {
    let mut out = Vec::with_capacity((w * h) as usize);
    for y in 0..h {
        for x in 0..w {
            let mut m = f32::MAX;
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn levels_halve_rounding_up_down_to_one_texel() {
        let p = DepthPyramid::from_depth(37, 23, &vec![0.5; 37 * 23]);
        let sizes: Vec<(u32, u32)> = p.levels.iter().map(|(w, h, _)| (*w, *h)).collect();
        assert_eq!(sizes, [(19, 12), (10, 6), (5, 3), (3, 2), (2, 1), (1, 1)]);
        assert_eq!(DepthPyramid::from_depth(1, 1, &[0.25]).levels.len(), 1);
    }

    #[test]
    fn a_texel_holds_the_farthest_depth_of_its_clipped_footprint() {
        // 5 × 3: the last column and row of level 0 cover one pixel and one row.
        let depth: Vec<f32> = (0..15).map(|i| 1.0 - i as f32 / 16.0).collect();
        let p = DepthPyramid::from_depth(5, 3, &depth);
        assert_eq!(p.texel(0, 0, 0), depth[6]);
        assert_eq!(p.texel(0, 2, 0), depth[9]);
        assert_eq!(p.texel(0, 2, 1), depth[14]);
        assert_eq!(p.texel(2, 0, 0), depth[14]);
    }

    #[test]
    fn the_level_fits_the_rectangle_in_two_by_two_texels() {
        for x0 in 0..40u32 {
            for extent in 0..70u32 {
                let pixels = [x0, 3, x0 + extent, 3 + extent / 2];
                let l = occlusion_level(pixels);
                let s = l + 1;
                assert!(
                    (pixels[2] >> s) - (pixels[0] >> s) <= 1,
                    "{pixels:?} level {l}"
                );
                // One level finer would not always do.
                if l > 0 {
                    assert!(
                        extent >= 1 << l,
                        "{pixels:?} level {l} is coarser than needed"
                    );
                }
            }
        }
    }

    #[test]
    fn a_sphere_behind_a_wall_is_occluded_and_one_in_front_is_not() {
        // Looking down -z from the origin; a wall at depth 0.5 fills the screen.
        let vp = glam_free_perspective(1.0, 0.1);
        let p = DepthPyramid::from_depth(64, 64, &vec![0.5; 64 * 64]);
        // Reverse-Z infinite: depth = near / distance, so the wall is at distance 0.2.
        let behind = occlusion_rect(&vp, [64.0, 64.0], [0.0, 0.0, -2.0], 0.1);
        assert!(behind.testable && p.occludes(&behind), "{behind:?}");
        let in_front = occlusion_rect(&vp, [64.0, 64.0], [0.0, 0.0, -0.18], 0.01);
        assert!(in_front.testable && !p.occludes(&in_front), "{in_front:?}");
        // Crossing the near plane, or partly off the screen: never testable.
        assert!(!occlusion_rect(&vp, [64.0, 64.0], [0.0, 0.0, -0.12], 0.05).testable);
        assert!(!occlusion_rect(&vp, [64.0, 64.0], [2.0, 0.0, -2.0], 0.1).testable);
        // A hole of one empty pixel under the rectangle keeps the sphere.
        let mut holed = vec![0.5; 64 * 64];
        holed[32 * 64 + 32] = 0.0;
        assert!(!DepthPyramid::from_depth(64, 64, &holed).occludes(&behind));
    }

    fn value(depth: f32, payload: u32) -> u64 {
        (depth.to_bits() as u64) << 32 | payload as u64
    }

    #[test]
    fn a_small_visibility_target_by_hand() {
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
        let p = DepthPyramid::from_visibility(&vis, 3, 5);
        assert_eq!(p.levels.len(), 3);
        assert_eq!(p.levels[0].2, vec![0.25, 0.0, 0.1, 0.3, 0.2, 1.0]);
        assert_eq!(p.levels[1].2, vec![0.0, 0.2]);
        assert_eq!(p.levels[2].2, vec![0.0]);
        assert_eq!(p.level_size(0), [2, 3]);
        assert_eq!(p.texel(0, 1, 2), 1.0);
    }

    #[test]
    #[should_panic(expected = "outside level 0")]
    fn a_texel_past_its_level_is_refused() {
        // Level 0 of 5 × 3 is 3 × 2: (3, 0) would be (0, 1) read as a flat index.
        DepthPyramid::from_depth(5, 3, &[0.5; 15]).texel(0, 3, 0);
    }

    /// `w × h` visibility values drawn from `seed`: about one in `empty_every` empty, the
    /// rest at random depths in [0, 1), with random cluster ids when `random_ids`.
    fn random_visibility(
        w: u32,
        h: u32,
        seed: u64,
        empty_every: u32,
        random_ids: bool,
    ) -> Vec<u64> {
        let mut rng = super::super::rng::Rng(seed | 1);
        (0..w * h)
            .map(|_| {
                let id = if random_ids { rng.next_u64() as u32 } else { 0 };
                if rng.below(empty_every) == 0 {
                    0
                } else {
                    value(rng.unit(), id)
                }
            })
            .collect()
    }

    /// Texel `(x, y)` of `level` straight from the rule: the min depth over source pixels
    /// `[x·2^(L+1), (x+1)·2^(L+1)) × [y·2^(L+1), (y+1)·2^(L+1))` clipped to the image.
    fn footprint_min(vis: &[u64], width: u32, height: u32, level: u32, x: u32, y: u32) -> f32 {
        let side = 2u64 << level;
        let xs = (x as u64 * side)..((x as u64 + 1) * side).min(width as u64);
        let ys = (y as u64 * side)..((y as u64 + 1) * side).min(height as u64);
        let mut m = f32::MAX;
        for sy in ys {
            for sx in xs.clone() {
                m = m.min(visibility_depth(vis[(sy * width as u64 + sx) as usize]));
            }
        }
        m
    }

    proptest::proptest! {
        #![proptest_config(proptest::prelude::ProptestConfig::with_cases(64))]
        /// The level-by-level reduction is the rule: every texel is the min over its
        /// clipped footprint, down to one texel.
        #[test]
        fn levels_equal_the_footprint_rule(
            w in 1u32..70,
            h in 1u32..70,
            seed in proptest::prelude::any::<u64>(),
        ) {
            let vis = random_visibility(w, h, seed, 9, true);
            let p = DepthPyramid::from_visibility(&vis, w, h);
            for level in 0..p.levels.len() as u32 {
                let [lw, lh] = p.level_size(level);
                proptest::prop_assert_eq!([lw, lh], [w.div_ceil(2 << level), h.div_ceil(2 << level)]);
                for y in 0..lh {
                    for x in 0..lw {
                        let want = footprint_min(&vis, w, h, level, x, y);
                        proptest::prop_assert_eq!(p.texel(level, x, y).to_bits(), want.to_bits());
                    }
                }
            }
            proptest::prop_assert_eq!(p.levels.last().map(|l| l.2.len()), Some(1));
        }

        /// A rectangle read through the pyramid (`pyramid_farthest`) is never nearer than
        /// its farthest pixel, reads only texels inside their level (`texel` panics
        /// otherwise), and is exactly the min over the aligned blocks of its level that
        /// hold the rectangle.
        #[test]
        fn a_rectangle_read_is_conservative(
            w in 1u32..300,
            h in 1u32..300,
            corners in proptest::prelude::any::<[u32; 4]>(),
            seed in proptest::prelude::any::<u64>(),
        ) {
            let vis = random_visibility(w, h, seed, 50, false);
            let p = DepthPyramid::from_visibility(&vis, w, h);
            let [a, b, c, d] = corners;
            let (xa, xb) = (a % w, b % w);
            let (ya, yb) = (c % h, d % h);
            let (x0, x1, y0, y1) = (xa.min(xb), xa.max(xb), ya.min(yb), ya.max(yb));
            let got = p.farthest([x0, y0, x1, y1]);
            let depth = |x: u32, y: u32| visibility_depth(vis[(y * w + x) as usize]);
            let mut farthest = f32::MAX;
            for y in y0..=y1 {
                for x in x0..=x1 {
                    farthest = farthest.min(depth(x, y));
                }
            }
            proptest::prop_assert!(got <= farthest, "{w}×{h} [{x0}, {x1}] × [{y0}, {y1}]: {got} > {farthest}");
            let shift = occlusion_level([x0, y0, x1, y1]) + 1;
            let mut covered = f32::MAX;
            for y in (y0 >> shift << shift)..(((y1 >> shift) + 1) << shift).min(h) {
                for x in (x0 >> shift << shift)..(((x1 >> shift) + 1) << shift).min(w) {
                    covered = covered.min(depth(x, y));
                }
            }
            proptest::prop_assert_eq!(got.to_bits(), covered.to_bits());
        }
    }

    /// A reverse-Z infinite perspective (column-major), square aspect.
    fn glam_free_perspective(fov_y: f32, near: f32) -> [[f32; 4]; 4] {
        let f = 1.0 / (fov_y / 2.0).tan();
        [
            [f, 0.0, 0.0, 0.0],
            [0.0, f, 0.0, 0.0],
            [0.0, 0.0, 0.0, -1.0],
            [0.0, 0.0, near, 0.0],
        ]
    }
}
