//! Resampling to a square power-of-two size and the mip chain, both in linear light for
//! sRGB colour, so that a checkerboard's mips are the grey its texels average to rather
//! than the darker grey that averaging the encoded values gives.

use super::{ColorSpace, Image};

/// The sRGB transfer function's inverse, for one 8-bit value: linear light in 0..=1.
pub fn to_linear(v: u8) -> f32 {
    srgb_to_linear(v as f32 / 255.0)
}

/// The sRGB transfer function's inverse: an encoded value in 0..=1 (clamped) to linear
/// light.
pub fn srgb_to_linear(c: f32) -> f32 {
    let c = c.clamp(0.0, 1.0);
    if c <= 0.04045 {
        c / 12.92
    } else {
        ((c + 0.055) / 1.055).powf(2.4)
    }
}

/// Linear light in 0..=1 to the nearest 8-bit sRGB value.
pub fn from_linear(l: f32) -> u8 {
    let l = l.clamp(0.0, 1.0);
    let c = if l <= 0.003_130_8 {
        l * 12.92
    } else {
        1.055 * l.powf(1.0 / 2.4) - 0.055
    };
    (c * 255.0).round() as u8
}

/// An image's texels as filterable values: colour in linear light for sRGB, all four
/// channels in 0..=1.
fn to_float(image: &Image, space: ColorSpace) -> Vec<[f32; 4]> {
    let lut: Vec<f32> = match space {
        ColorSpace::Srgb => (0..=255u8).map(to_linear).collect(),
        ColorSpace::Linear => (0..=255u8).map(|v| v as f32 / 255.0).collect(),
    };
    image
        .rgba
        .chunks_exact(4)
        .map(|p| {
            [
                lut[p[0] as usize],
                lut[p[1] as usize],
                lut[p[2] as usize],
                p[3] as f32 / 255.0,
            ]
        })
        .collect()
}

fn to_image(width: u32, height: u32, texels: &[[f32; 4]], space: ColorSpace) -> Image {
    let unorm = |v: f32| (v.clamp(0.0, 1.0) * 255.0).round() as u8;
    let colour = |v: f32| match space {
        ColorSpace::Srgb => from_linear(v),
        ColorSpace::Linear => unorm(v),
    };
    Image {
        width,
        height,
        rgba: texels
            .iter()
            .flat_map(|t| [colour(t[0]), colour(t[1]), colour(t[2]), unorm(t[3])])
            .collect(),
    }
}

/// One axis resampled from `from` to `to` texels with a tent filter as wide as the
/// larger of one source texel and the output's texel spacing (bilinear when
/// enlarging, an area-weighted average when shrinking), wrapping at the edges as a
/// repeating texture does. `get(k)` is source texel `k` of the line.
fn resample_line(from: usize, to: usize, get: impl Fn(usize) -> [f32; 4]) -> Vec<[f32; 4]> {
    let scale = from as f32 / to as f32;
    let radius = scale.max(1.0);
    (0..to)
        .map(|o| {
            let centre = (o as f32 + 0.5) * scale - 0.5;
            let (lo, hi) = (
                (centre - radius).floor() as i64,
                (centre + radius).ceil() as i64,
            );
            let (mut sum, mut weight) = ([0f32; 4], 0f32);
            for k in lo..=hi {
                let w = 1.0 - (k as f32 - centre).abs() / radius;
                if w <= 0.0 {
                    continue;
                }
                let t = get(k.rem_euclid(from as i64) as usize);
                for c in 0..4 {
                    sum[c] += t[c] * w;
                }
                weight += w;
            }
            sum.map(|s| s / weight)
        })
        .collect()
}

/// `image` resampled to `size × size` (a power of two), filtered in linear light for
/// sRGB; returned as it is when it already has that size.
pub fn resample_square(image: &Image, size: u32, space: ColorSpace) -> Image {
    if image.width == size && image.height == size {
        return image.clone();
    }
    let (w, h, s) = (image.width as usize, image.height as usize, size as usize);
    let src = to_float(image, space);
    // Rows first (w → s), then columns (h → s).
    let mut rows = vec![[0f32; 4]; s * h];
    for y in 0..h {
        let line = resample_line(w, s, |x| src[y * w + x]);
        rows[y * s..(y + 1) * s].copy_from_slice(&line);
    }
    let mut out = vec![[0f32; 4]; s * s];
    for x in 0..s {
        let column = resample_line(h, s, |y| rows[y * s + x]);
        for (y, t) in column.into_iter().enumerate() {
            out[y * s + x] = t;
        }
    }
    to_image(size, size, &out, space)
}

/// A texture's levels, finest first: level `k` is `(size >> k)²`, down to 1 × 1.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct MipChain {
    /// The levels, each a square image.
    pub levels: Vec<Image>,
}

impl MipChain {
    /// Side of level 0.
    pub fn size(&self) -> u32 {
        self.levels.first().map_or(0, |l| l.width)
    }

    /// Bytes of every level together (RGBA8).
    pub fn bytes(&self) -> u64 {
        self.levels.iter().map(|l| l.rgba.len() as u64).sum()
    }
}

/// The mip chain of a square power-of-two image: each level the 2 × 2 average of the
/// one above, in linear light for sRGB.
///
/// # Panics
/// When `image` is not square with a power-of-two side (use [`resample_square`]).
pub fn mip_chain(image: &Image, space: ColorSpace) -> MipChain {
    assert!(
        image.width == image.height && image.width.is_power_of_two(),
        "mip_chain takes a square power-of-two image, not {} × {}",
        image.width,
        image.height
    );
    let mut levels = vec![image.clone()];
    let mut texels = to_float(image, space);
    let mut size = image.width as usize;
    while size > 1 {
        let half = size / 2;
        let mut next = vec![[0f32; 4]; half * half];
        for y in 0..half {
            for x in 0..half {
                let mut sum = [0f32; 4];
                for (dx, dy) in [(0, 0), (1, 0), (0, 1), (1, 1)] {
                    let t = texels[(2 * y + dy) * size + 2 * x + dx];
                    for c in 0..4 {
                        sum[c] += t[c];
                    }
                }
                next[y * half + x] = sum.map(|s| s * 0.25);
            }
        }
        levels.push(to_image(half as u32, half as u32, &next, space));
        texels = next;
        size = half;
    }
    MipChain { levels }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn srgb_round_trips_every_value() {
        for v in 0..=255u8 {
            assert_eq!(from_linear(to_linear(v)), v);
        }
        assert!((to_linear(188) - 0.5).abs() < 0.005);
    }

    /// A black and white checkerboard averages to linear 0.5: sRGB 188, not 128.
    #[test]
    fn a_checkerboard_mips_to_the_grey_of_its_light() {
        let mut image = Image::filled(4, 4, [0, 0, 0, 255]);
        for y in 0..4 {
            for x in 0..4 {
                if (x + y) % 2 == 0 {
                    let at = (y * 4 + x) * 4;
                    image.rgba[at..at + 3].copy_from_slice(&[255; 3]);
                }
            }
        }
        let chain = mip_chain(&image, ColorSpace::Srgb);
        assert_eq!(chain.levels.len(), 3);
        assert_eq!(chain.levels[1].texel(0, 0), [188, 188, 188, 255]);
        assert_eq!(chain.levels[2].texel(0, 0), [188, 188, 188, 255]);
        let data = mip_chain(&image, ColorSpace::Linear);
        assert_eq!(data.levels[2].texel(0, 0), [128, 128, 128, 255]);
        assert_eq!(chain.bytes(), (16 + 4 + 1) * 4);
    }

    #[test]
    fn resampling_keeps_a_flat_image_flat_and_an_exact_size_untouched() {
        let flat = Image::filled(3, 5, [10, 200, 30, 40]);
        let square = resample_square(&flat, 8, ColorSpace::Srgb);
        assert_eq!((square.width, square.height), (8, 8));
        assert!(square.rgba.chunks_exact(4).all(|p| p == [10, 200, 30, 40]));
        let exact = Image::filled(4, 4, [1, 2, 3, 4]);
        assert_eq!(resample_square(&exact, 4, ColorSpace::Linear), exact);
        // Shrinking 4 → 1 averages all four columns of a ramp.
        let mut ramp = Image::filled(4, 1, [0, 0, 0, 255]);
        for x in 0..4 {
            ramp.rgba[x * 4] = (x * 80) as u8;
        }
        let one = resample_square(&ramp, 1, ColorSpace::Linear);
        assert_eq!(one.texel(0, 0)[0], 120);
    }
}
