//! The pyramid's shape: level sizes by the footprint rule, the mip count, and the
//! texture that holds them.
//!
//! Level `L` of a `W × H` source is `ceil(W / 2^(L+1)) × ceil(H / 2^(L+1))`: every level
//! rounds up, so no source pixel is ever left out. wgpu's mip chain rounds down
//! (`max(1, w >> L)`), so a texture of the level-0 size would be too small from the
//! first odd level on (37 × 23: level 0 is 19 × 12, level 1 must be 10 × 6, mip 1 of a
//! 19 × 12 texture is 9 × 6). [`texture_desc`] therefore pads the texture to the smallest
//! size whose rounded-down mips hold every level; the texels past a level's size are
//! never written and never part of any footprint.

use meshlight_graph::prelude::*;

/// The pyramid's format: one depth per texel.
pub const FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::R32Float;

/// The largest source side the pass takes: 128 tiles of 128 pixels, which the one
/// workgroup of the top step reduces in one block (levels 7 to 13).
pub const MAX_SIDE: u32 = 16_384;

/// Source pixels per tile side: one workgroup reduces a tile into levels 0 to 6.
pub const TILE: u32 = 128;

/// Levels one workgroup produces from its 128 × 128 input: 64 × 64 texels down to 1.
pub const BLOCK_LEVELS: u32 = 7;

/// The most levels a pyramid has (a [`MAX_SIDE`] source): the single pass binds a view
/// of each.
pub const MAX_LEVELS: u32 = 2 * BLOCK_LEVELS;

/// Level 0's size and the number of levels of the pyramid of a `W × H` source.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct PyramidExtent {
    /// `ceil(W / 2)`.
    pub width: u32,
    /// `ceil(H / 2)`.
    pub height: u32,
    /// `1 + ceil(log2(max(width, height)))`: levels down to and including 1 × 1.
    pub mip_levels: u32,
}

/// The pyramid of a `width × height` source (sides of 0 count as 1).
pub fn pyramid_extent(width: u32, height: u32) -> PyramidExtent {
    let half = |side: u32| side.max(1).div_ceil(2);
    let (w, h) = (half(width), half(height));
    let largest = w.max(h);
    // ceil(log2(n)) for n ≥ 1: the bits of n - 1.
    let mip_levels = 1 + (32 - (largest - 1).leading_zeros());
    PyramidExtent {
        width: w,
        height: h,
        mip_levels,
    }
}

impl PyramidExtent {
    /// The size of level `level`: `ceil(width / 2^level) × ceil(height / 2^level)`,
    /// which is `ceil(W / 2^(level+1)) × ceil(H / 2^(level+1))` of the source.
    pub fn level_size(&self, level: u32) -> [u32; 2] {
        let side = |s: u32| ((s - 1) >> level.min(31)) + 1;
        [side(self.width), side(self.height)]
    }

    /// Texels of every level together.
    pub fn texels(&self) -> u64 {
        (0..self.mip_levels)
            .map(|l| {
                let [w, h] = self.level_size(l);
                w as u64 * h as u64
            })
            .sum()
    }

    /// The texture's size: per side the smallest `T` with `max(1, T >> L)` at least the
    /// level's side for every level, so wgpu's rounded-down mips hold the rounded-up
    /// levels. Level 0's side where rounding down never loses a texel (a power of two:
    /// 32 stays 32), under twice it otherwise (1,120 → 2,048, 630 → 1,024).
    pub fn texture_size(&self) -> [u32; 2] {
        let padded = |side: u32| {
            (0..self.mip_levels)
                .map(|l| {
                    let level = ((side - 1) >> l) + 1;
                    if level > 1 { level << l } else { 1 }
                })
                .max()
                .unwrap_or(1)
                .max(side)
        };
        [padded(self.width), padded(self.height)]
    }
}

/// The texture to declare for the pyramid of a `width × height` visibility target:
/// [`FORMAT`], [`PyramidExtent::texture_size`], [`PyramidExtent::mip_levels`] mips, one
/// layer. The pass checks the texture bound to its `pyramid` slot against exactly this.
///
/// Read level `L` at texels inside [`PyramidExtent::level_size`]`(L)` only: a texture
/// mip may be larger (padding), and its texels past the level are not written.
/// `textureDimensions` gives the padded size, not the level's.
pub fn texture_desc(width: u32, height: u32) -> TextureDesc {
    let extent = pyramid_extent(width, height);
    let [w, h] = extent.texture_size();
    TextureDesc::d2(FORMAT, w, h).with_mips(extent.mip_levels)
}

/// Tiles of [`TILE`] × [`TILE`] pixels covering the source: the first step's grid.
pub fn tile_grid(width: u32, height: u32) -> [u32; 2] {
    [width.max(1).div_ceil(TILE), height.max(1).div_ceil(TILE)]
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The rule spelled directly: ceil(W / 2^(L+1)) × ceil(H / 2^(L+1)), levels until
    /// both sides are 1.
    fn levels_by_rule(w: u32, h: u32) -> Vec<[u32; 2]> {
        let mut levels = Vec::new();
        for l in 0.. {
            let d = 2u64 << l;
            let size = [(w as u64).div_ceil(d) as u32, (h as u64).div_ceil(d) as u32];
            levels.push(size);
            if size == [1, 1] {
                break;
            }
        }
        levels
    }

    #[test]
    fn extents_follow_the_rule() {
        assert_eq!(
            pyramid_extent(1, 1),
            PyramidExtent {
                width: 1,
                height: 1,
                mip_levels: 1
            }
        );
        assert_eq!(pyramid_extent(3, 5).mip_levels, 3); // 2×3, 1×2, 1×1
        assert_eq!(pyramid_extent(2240, 1260).mip_levels, 12);
        assert_eq!(pyramid_extent(64, 64).mip_levels, 6);
        assert_eq!(pyramid_extent(65, 33).mip_levels, 7);
        let sides = (1..=300).chain([1023, 1024, 1025, 1260, 2240, 4095, 16_383, 16_384]);
        for w in sides.clone().step_by(7) {
            for h in sides.clone().step_by(11) {
                let e = pyramid_extent(w, h);
                let want = levels_by_rule(w, h);
                assert_eq!(e.mip_levels as usize, want.len(), "{w}×{h}");
                for (l, size) in want.iter().enumerate() {
                    assert_eq!(e.level_size(l as u32), *size, "{w}×{h} level {l}");
                }
            }
        }
        assert_eq!(pyramid_extent(MAX_SIDE, MAX_SIDE).mip_levels, MAX_LEVELS);
    }

    #[test]
    fn the_texture_holds_every_level_and_is_the_smallest_that_does() {
        for w in (1..=700).chain([1120, 1260, 2240, 3840, 16_384]) {
            for h in [1, 2, 3, 5, 23, 33, 64, 158, 630, 1260] {
                let e = pyramid_extent(w, h);
                let desc = texture_desc(w, h);
                assert_eq!(desc.format, FORMAT);
                assert_eq!(desc.mip_levels, e.mip_levels);
                // wgpu accepts this many mips for the size.
                let full = 32 - desc.width.max(desc.height).leading_zeros();
                assert!(desc.mip_levels <= full, "{w}×{h}: {desc:?}");
                let [tw, th] = e.texture_size();
                for l in 0..e.mip_levels {
                    let (mw, mh) = desc.mip_size(l);
                    let [lw, lh] = e.level_size(l);
                    assert!(mw >= lw && mh >= lh, "{w}×{h} level {l}: mip {mw}×{mh}");
                }
                // One texel less on a padded side leaves some level out.
                for (side, smaller) in [(e.width, tw), (e.height, th)] {
                    if smaller > side {
                        let t = smaller - 1;
                        let fits = (0..e.mip_levels).all(|l| {
                            let level = ((side - 1) >> l) + 1;
                            (t >> l).max(1) >= level
                        });
                        assert!(!fits, "{w}×{h}: {t} would do");
                    }
                }
            }
        }
        let d = texture_desc(2240, 1260);
        assert_eq!((d.width, d.height, d.mip_levels), (2048, 1024, 12));
        let d = texture_desc(64, 64);
        assert_eq!((d.width, d.height, d.mip_levels), (32, 32, 6));
    }
}
