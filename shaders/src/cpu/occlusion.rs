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
    pub testable: bool,
    /// Inclusive pixel range: x0, y0, x1, y1.
    pub pixels: [u32; 4],
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
/// the source pixels it covers, down to 1 × 1.
#[derive(Clone, Debug, PartialEq)]
pub struct DepthPyramid {
    /// Per level: width, height, texels row by row.
    pub levels: Vec<(u32, u32, Vec<f32>)>,
}

impl DepthPyramid {
    /// The pyramid of a `width × height` reverse-Z depth image (row-major).
    pub fn from_depth(width: u32, height: u32, depth: &[f32]) -> Self {
        assert_eq!(depth.len(), (width * height) as usize, "depth image size");
        let mut levels = Vec::new();
        let mut level = 0u32;
        loop {
            let span = 2u32 << level;
            let (w, h) = (width.div_ceil(span), height.div_ceil(span));
            let mut texels = vec![f32::MAX; (w * h) as usize];
            for y in 0..height {
                for x in 0..width {
                    let t = &mut texels[((y / span) * w + x / span) as usize];
                    *t = t.min(depth[(y * width + x) as usize]);
                }
            }
            levels.push((w, h, texels));
            if w == 1 && h == 1 {
                return Self { levels };
            }
            level += 1;
        }
    }

    /// Texel `(x, y)` of `level`.
    pub fn texel(&self, level: u32, x: u32, y: u32) -> f32 {
        let (w, _, texels) = &self.levels[level as usize];
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
