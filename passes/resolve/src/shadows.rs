//! The sun's shadow in the resolve: the cascades' depth maps (slot `shadow_maps`) and
//! the frame input `shadows` ([`ShadowParams`]), read only where both are given.
//!
//! A shaded pixel picks the first cascade whose slice of the camera's view reaches its
//! view-space depth ([`cascade_index`]), moves its surface point along the normal by
//! `normal_offset` (a cascade's texels are world-sized, so a fixed count of texels is a
//! fixed share of the acne band) and towards the light by `depth_bias`, and compares it
//! with the 4 × 4 texels around it, weighted `(1 − f, 1, 1, f) / 3` on each axis: nine
//! bilinear comparisons one texel apart, a 3 × 3 tent, so a shadow's edge ramps over
//! three texels instead of stepping. That costs 16 loads of one cache line or two; a
//! wider kernel (PCSS, a Poisson disc) would soften more and cost more, and is left to a
//! pipeline that wants it. Points outside every cascade, and texels off the map, are lit.
//!
//! [`shadow_factor`] is the reference the GPU test compares with; shade.wgsl multiplies
//! the sun's term by it, and the `shadow` view shows it over each cascade's colour.

use crate::cpu::PixelSurface;
use glam::{Mat4, Vec2, Vec3, Vec4};
use meshlight_gpu_scene::cascades::{Cascade, MAX_CASCADES};
use meshlight_shaders::cpu::layout::View;

/// The frame input resolve reads the cascades from, beside the slot `shadow_maps`.
pub const SHADOWS_INPUT: &str = "shadows";
/// The slot of the cascades' depth maps.
pub const SHADOW_MAPS: &str = "shadow_maps";

/// Colours of the `shadow` view per cascade, nearest first (shadows.wgsl's
/// `CASCADE_COLORS` in shade.wgsl); pixels past the last cascade are grey.
pub const CASCADE_COLORS: [Vec3; 4] = [
    Vec3::new(0.95, 0.35, 0.3),
    Vec3::new(0.35, 0.85, 0.4),
    Vec3::new(0.35, 0.55, 1.0),
    Vec3::new(0.95, 0.8, 0.3),
];
/// The `shadow` view's colour past the last cascade.
pub const NO_CASCADE_COLOR: Vec3 = Vec3::new(0.6, 0.6, 0.6);

meshlight_shaders::uniform_block! {
    /// The frame input `shadows`, as shadows.wgsl reads it.
    pub struct ShadowParams as "Shadows" in "resolve::shadow_params" {
        /// World to the clip space of cascade 0 (a), 1, 2, 3 (its view's `view_projection`).
        pub cascade_a: [[f32; 4]; 4],
        /// See `cascade_a`.
        pub cascade_b: [[f32; 4]; 4],
        /// See `cascade_a`.
        pub cascade_c: [[f32; 4]; 4],
        /// See `cascade_a`.
        pub cascade_d: [[f32; 4]; 4],
        /// Where each cascade's slice ends: the camera's view-space depth.
        pub splits: [f32; 4],
        /// How far each cascade moves a receiver along its normal, world units.
        pub normal_offset: [f32; 4],
        /// How far each cascade moves a receiver towards the light, in its depth units.
        pub depth_bias: [f32; 4],
        /// Cascades in use, at most 4.
        pub count: u32,
        /// Texels along each side of every map.
        pub resolution: u32,
        /// Unused; the block is whole 16-byte rows.
        pub pad_a: u32,
        /// Unused.
        pub pad_b: u32,
    }
}

impl ShadowParams {
    /// The parameters of `cascades` (at most [`MAX_CASCADES`], all of `resolution`):
    /// `normal_bias` and `depth_bias` are in texels of each cascade.
    pub fn new(cascades: &[Cascade], resolution: u32, normal_bias: f32, depth_bias: f32) -> Self {
        let mut p = Self {
            count: cascades.len().min(MAX_CASCADES as usize) as u32,
            resolution,
            ..Self::default()
        };
        for (k, c) in cascades.iter().take(MAX_CASCADES as usize).enumerate() {
            *p.cascade_mut(k) = c.view.view_projection;
            p.splits[k] = c.far;
            p.normal_offset[k] = normal_bias * c.texel_size;
            // An orthographic projection's depth changes by |z_axis.z| per world unit
            // along the light.
            p.depth_bias[k] = depth_bias * c.texel_size * c.view.projection[2][2].abs();
        }
        p
    }

    /// World to cascade `k`'s clip space.
    pub fn cascade(&self, k: usize) -> Mat4 {
        Mat4::from_cols_array_2d(match k {
            0 => &self.cascade_a,
            1 => &self.cascade_b,
            2 => &self.cascade_c,
            _ => &self.cascade_d,
        })
    }

    fn cascade_mut(&mut self, k: usize) -> &mut [[f32; 4]; 4] {
        match k {
            0 => &mut self.cascade_a,
            1 => &mut self.cascade_b,
            2 => &mut self.cascade_c,
            _ => &mut self.cascade_d,
        }
    }

    /// Words of `shadow_maps` the cascades fill.
    pub fn map_words(&self) -> u64 {
        u64::from(self.count) * u64::from(self.resolution) * u64::from(self.resolution)
    }
}

/// The cascades as the CPU reference reads them: the parameters and the maps.
#[derive(Clone, Copy, Debug)]
pub struct ShadowFrame<'a> {
    /// The frame input.
    pub params: &'a ShadowParams,
    /// The `shadow_maps` slot's words.
    pub maps: &'a [u32],
}

/// shadows.wgsl's `cascade_index`: the first cascade whose slice reaches `world`'s
/// view-space depth, `count` past the last.
pub fn cascade_index(params: &ShadowParams, view: &View, world: Vec3) -> u32 {
    let depth = -(Mat4::from_cols_array_2d(&view.view) * world.extend(1.0)).z;
    (0..params.count)
        .find(|&k| depth <= params.splits[k as usize])
        .unwrap_or(params.count)
}

/// shadows.wgsl's `shadow_factor`: the share of the sun reaching `world` (normal `n`).
pub fn shadow_factor(shadows: &ShadowFrame, view: &View, world: Vec3, n: Vec3) -> f32 {
    let s = shadows.params;
    let k = cascade_index(s, view, world);
    if k >= s.count {
        return 1.0;
    }
    let kk = k as usize;
    let p = world + n * s.normal_offset[kk];
    let clip = s.cascade(kk) * p.extend(1.0);
    let ndc = clip.truncate() / clip.w;
    let res = s.resolution as f32;
    let texel = Vec2::new(ndc.x * 0.5 + 0.5, 0.5 - ndc.y * 0.5) * res - Vec2::splat(0.5);
    let base = texel.floor();
    let f = texel - base;
    let receiver = ndc.z + s.depth_bias[kk];
    let wx = [1.0 - f.x, 1.0, 1.0, f.x];
    let wy = [1.0 - f.y, 1.0, 1.0, f.y];
    let r = s.resolution as i32;
    let lit_texel = |x: i32, y: i32| -> f32 {
        if x < 0 || y < 0 || x >= r || y >= r {
            return 1.0;
        }
        let i = (k * s.resolution * s.resolution) as usize + (y * r + x) as usize;
        let stored = f32::from_bits(shadows.maps.get(i).copied().unwrap_or(0));
        if stored <= receiver { 1.0 } else { 0.0 }
    };
    let mut lit = 0.0;
    for (j, wy) in wy.iter().enumerate() {
        let mut row = 0.0;
        for (i, wx) in wx.iter().enumerate() {
            row += wx * lit_texel(base.x as i32 + i as i32 - 1, base.y as i32 + j as i32 - 1);
        }
        lit += wy * row;
    }
    lit / 9.0
}

/// shade.wgsl's `shadow_color`: the cascade's colour (grey past the last), dimmed where
/// the sun does not reach, over a floor of 0.3 so the shapes stay readable.
pub fn shadow_color(shadows: &ShadowFrame, view: &View, p: &PixelSurface) -> Vec3 {
    let k = cascade_index(shadows.params, view, p.world);
    let tint = CASCADE_COLORS
        .get(k as usize)
        .filter(|_| k < shadows.params.count)
        .copied()
        .unwrap_or(NO_CASCADE_COLOR);
    tint * (0.3 + 0.7 * shadow_factor(shadows, view, p.world, p.n))
}

/// The clip-space point of `world` in cascade `k` (for tests that place a receiver).
pub fn cascade_clip(params: &ShadowParams, k: usize, world: Vec3) -> Vec4 {
    params.cascade(k) * world.extend(1.0)
}
