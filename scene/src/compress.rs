//! Vertex compression: positions on one mesh-wide grid, bit-packed per meshlet at the
//! fewest bits per axis; octahedral normals in 2 × [`NORMAL_BITS`] snorm; UVs as
//! per-meshlet offsets on a mesh-wide grid over the mesh's UV rectangle.
//!
//! One grid for the whole mesh is what keeps LOD cuts watertight after quantisation:
//! a vertex shared by two meshlets decodes to bit-identical positions in both.

use glam::{Vec2, Vec3};

/// Bits per axis of the position grid when the DAG gives nothing to derive them from (a
/// mesh of one meshlet has no simplified level): a step of 1/65535 of the largest extent.
pub const FALLBACK_POSITION_BITS: u32 = 16;
/// The automatic grid keeps the quantisation error at most this share of the LOD-0
/// error. LOD 0 is first drawn where its parent's error projects to the pixel threshold,
/// so there its vertices sit within an eighth of a pixel of the originals: quantisation
/// never decides which LOD is drawn, and one bit fewer would already allow a quarter.
pub const AUTO_ERROR_SHARE: f32 = 1.0 / 8.0;
/// The grid and the packed deltas are decoded with 32-bit integer maths and `f32`, which
/// is exact up to 2^24 steps.
pub const MAX_POSITION_BITS: u32 = 24;
/// Fewer bits than this put a 16-cell grid over the whole mesh: nothing drawable, so a
/// smaller request is a mistake worth refusing.
pub const MIN_POSITION_BITS: u32 = 4;

/// The mesh-wide position grid: `position = origin + step * q`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Quantization {
    /// Grid point 0: the smallest corner of the mesh's bounds.
    pub origin: Vec3,
    /// Distance between neighbouring grid points, the same on every axis so that the
    /// error bound is one number.
    pub step: f32,
    /// Bits per axis: grid coordinates run from 0 to `2^bits - 1`.
    pub bits: u32,
}

impl Quantization {
    /// A grid of `bits` per axis over the largest extent of the bounds.
    pub fn new(min: Vec3, max: Vec3, bits: u32) -> Self {
        let extent = (max - min).max_element();
        let cells = ((1u64 << bits) - 1) as f32;
        // A point mesh or a flat mesh still needs a non-zero step, and a tiny extent one
        // that does not underflow.
        let step = if extent > 0.0 {
            (extent / cells).max(f32::MIN_POSITIVE)
        } else {
            1.0
        };
        Self {
            origin: min,
            step,
            bits,
        }
    }

    /// The nearest grid point to `p`, clamped into the grid.
    pub fn quantize(&self, p: Vec3) -> [u32; 3] {
        let max = ((1u64 << self.bits) - 1) as f32;
        ((p - self.origin) / self.step)
            .round()
            .clamp(Vec3::ZERO, Vec3::splat(max))
            .to_array()
            .map(|c| c as u32)
    }

    /// The position of grid point `q`, computed as the shaders compute it.
    pub fn dequantize(&self, q: [u32; 3]) -> Vec3 {
        self.origin + Vec3::new(q[0] as f32, q[1] as f32, q[2] as f32) * self.step
    }

    /// Largest distance between a point and its decoded grid point.
    pub fn max_error(&self) -> f32 {
        self.step * 0.5 * 3f32.sqrt()
    }
}

/// Bits per axis of the mesh-wide position grid: fixed, or derived from the LOD errors.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum PositionBits {
    /// The fewest bits whose quantisation error is at most [`AUTO_ERROR_SHARE`] of the
    /// LOD-0 error (see [`auto_position_bits`]).
    #[default]
    Auto,
    /// This many bits, from [`MIN_POSITION_BITS`] to [`MAX_POSITION_BITS`]: for
    /// comparing encodings, or a grid shared by several assets.
    Fixed(u32),
}

impl std::str::FromStr for PositionBits {
    type Err = String;

    fn from_str(s: &str) -> Result<Self, String> {
        if s == "auto" {
            return Ok(Self::Auto);
        }
        match s.parse::<u32>() {
            Ok(b) if (MIN_POSITION_BITS..=MAX_POSITION_BITS).contains(&b) => Ok(Self::Fixed(b)),
            _ => Err(format!(
                "`{s}` is not a position precision: give `auto` or a number of bits from \
                 {MIN_POSITION_BITS} to {MAX_POSITION_BITS}"
            )),
        }
    }
}

impl std::fmt::Display for PositionBits {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Self::Auto => f.write_str("auto"),
            Self::Fixed(b) => write!(f, "{b}"),
        }
    }
}

/// The grid for a mesh of largest extent `extent` whose LOD-0 meshlets are replaced at
/// `lod0_errors` (each LOD-0 meshlet's parent error: the error of the first coarser
/// version, below which LOD 0 is what is drawn).
///
/// The reference is the 10th percentile of those errors, not the minimum, so a few
/// groups in flat regions do not drive the grid to its finest; errors below a millionth
/// of the extent are rounding noise of flat regions and are ignored. The grid's worst
/// error (half a step diagonally) is then kept at most [`AUTO_ERROR_SHARE`] of it.
pub fn auto_position_bits(extent: f32, lod0_errors: &[f32]) -> u32 {
    let mut errors: Vec<f32> = lod0_errors
        .iter()
        .copied()
        .filter(|e| e.is_finite() && *e > extent * 1e-6)
        .collect();
    if errors.is_empty() || extent <= 0.0 {
        return FALLBACK_POSITION_BITS;
    }
    errors.sort_unstable_by(f32::total_cmp);
    let reference = errors[errors.len() / 10];
    let step = reference * AUTO_ERROR_SHARE / (0.5 * 3f32.sqrt());
    let cells = (extent / step).ceil() as f64 + 1.0;
    (cells.log2().ceil() as u32).clamp(MIN_POSITION_BITS, MAX_POSITION_BITS)
}

/// Bits needed to store values `0..=range`.
pub fn bits_for(range: u32) -> u32 {
    32 - range.leading_zeros()
}

/// Appends `value` (at most 32 bits wide, `bits` ≤ 32) to a little-endian bitstream.
pub struct BitWriter<'a> {
    words: &'a mut Vec<u32>,
    bit: u32,
}

impl<'a> BitWriter<'a> {
    /// A writer appending to `words` from a fresh word on.
    pub fn new(words: &'a mut Vec<u32>) -> Self {
        Self { words, bit: 0 }
    }

    /// Appends the low `bits` of `value`, straddling into a new word where needed.
    pub fn put(&mut self, value: u32, bits: u32) {
        if bits == 0 {
            return;
        }
        if self.bit == 0 {
            self.words.push(0);
        }
        let last = self.words.len() - 1;
        self.words[last] |= value << self.bit;
        let room = 32 - self.bit;
        if bits > room {
            self.words.push(value >> room);
            self.bit = bits - room;
        } else {
            self.bit = (self.bit + bits) % 32;
        }
    }
}

/// The 57 bits of a little-endian bitstream (as bytes) from bit `at` on, zeros past the
/// end: one unaligned read that holds a whole vertex's grid offsets or a triangle record,
/// where [`get_bits`] reads a field at a time. Fields are then masked out of it.
#[inline(always)]
pub fn bit_window(bytes: &[u8], at: usize) -> u64 {
    let i = at / 8;
    let word = match bytes.get(i..i + 8) {
        Some(b) => u64::from_le_bytes(b.try_into().expect("eight bytes")),
        None => {
            let mut b = [0u8; 8];
            let tail = bytes.get(i..).unwrap_or(&[]);
            b[..tail.len()].copy_from_slice(tail);
            u64::from_le_bytes(b)
        }
    };
    word >> (at % 8)
}

/// The lowest `bits` set (all of them from 64 on).
#[inline(always)]
pub fn low_bits(bits: u32) -> u64 {
    1u64.checked_shl(bits).map_or(u64::MAX, |b| b - 1)
}

/// Reads `bits` at `bit_offset` of a little-endian bitstream; `None` past the end.
pub fn get_bits(words: &[u32], bit_offset: usize, bits: u32) -> Option<u32> {
    if bits == 0 {
        return Some(0);
    }
    let word = bit_offset / 32;
    let shift = (bit_offset % 32) as u32;
    let lo = (*words.get(word)? as u64) >> shift;
    let value = if shift + bits > 32 {
        lo | ((*words.get(word + 1)? as u64) << (32 - shift))
    } else {
        lo
    };
    Some((value & ((1u64 << bits) - 1)) as u32)
}

/// Bits per component of an octahedral normal. Measured worst distance of a decoded
/// unit normal from the original over a dense sphere of directions
/// (`normal_bits_meet_the_precision_bound`, precise encoding): 12 bits 6.8e-4, 11 bits
/// 1.35e-3, 10 bits 2.7e-3 (0.16°), 9 bits 5.4e-3. The bound the tests hold decoded
/// normals to is [`NORMAL_ERROR_BOUND`]: a change of n·l of at most 0.003, under one
/// 8-bit step of linear light, where gltfpack's default (8 bits) moves normals by 0.6°.
/// 10 bits is the fewest that meet it; 12 bits cost 0.7 bytes more per LOD-0 triangle
/// on Spot and Beast.
/// In an asset each meshlet stores its normals as offsets from their smallest
/// components, at the bits their range needs (see [`crate::asset::format`]).
pub const NORMAL_BITS: u32 = 10;

/// Largest distance of a decoded unit normal from the original (see [`NORMAL_BITS`]).
pub const NORMAL_ERROR_BOUND: f32 = 3e-3;

/// Octahedral mapping of a unit vector to two signed components in `-max..=max`, with
/// `max = 2^(bits-1) - 1`.
///
/// Of the four grid points around the exact mapping, the one that decodes closest to
/// `n` is kept ("precise" octahedral encoding, Cigolle et al. 2014): rounding each
/// component on its own can be up to twice as far off.
pub fn encode_octahedral(n: Vec3, bits: u32) -> [i32; 2] {
    let n = n / (n.x.abs() + n.y.abs() + n.z.abs());
    let mut o = Vec2::new(n.x, n.y);
    if n.z < 0.0 {
        o = (Vec2::ONE - Vec2::new(o.y, o.x).abs()) * Vec2::new(sign(o.x), sign(o.y));
    }
    let max = ((1i32 << (bits - 1)) - 1) as f32;
    let target = n.normalize_or(Vec3::Z);
    let (fx, fy) = ((o.x * max).floor(), (o.y * max).floor());
    let mut best = (f32::INFINITY, [0, 0]);
    for (dx, dy) in [(0.0, 0.0), (1.0, 0.0), (0.0, 1.0), (1.0, 1.0)] {
        let c = [
            (fx + dx).clamp(-max, max) as i32,
            (fy + dy).clamp(-max, max) as i32,
        ];
        let error = (decode_octahedral(c, bits) - target).length_squared();
        if error < best.0 {
            best = (error, c);
        }
    }
    best.1
}

/// Inverse of [`encode_octahedral`]. Components out of range give some unit vector (or
/// NaN for a damaged asset), never a panic.
pub fn decode_octahedral(c: [i32; 2], bits: u32) -> Vec3 {
    let max = ((1i32 << (bits - 1)) - 1) as f32;
    let (x, y) = (
        (c[0] as f32 / max).clamp(-1.0, 1.0),
        (c[1] as f32 / max).clamp(-1.0, 1.0),
    );
    let z = 1.0 - x.abs() - y.abs();
    let t = (-z).max(0.0);
    let x = x + if x >= 0.0 { -t } else { t };
    let y = y + if y >= 0.0 { -t } else { t };
    Vec3::new(x, y, z).normalize()
}

fn sign(v: f32) -> f32 {
    if v >= 0.0 { 1.0 } else { -1.0 }
}

/// Codes per axis of a mesh's UV grid: a code is below this, where an f32 still holds
/// every integer exactly, so the GPU's `f32(code)` is the code itself.
pub const UV_GRID_CODES: u32 = 1 << 24;

/// Most bits of a meshlet's UV offset per component.
pub const UV_MAX_BITS: u32 = 16;

/// Largest shift of a meshlet's UV offsets: 16 bits shifted by 8 span the grid.
pub const UV_MAX_SHIFT: u32 = 8;

/// The code of a mesh's largest UV: what a meshlet spanning the whole rectangle reaches
/// with the largest shift, below [`UV_GRID_CODES`].
pub const UV_LARGEST_CODE: u32 = ((1 << UV_MAX_BITS) - 1) << UV_MAX_SHIFT;

/// The coarsest UV step a meshlet is stored at when its offsets fit [`UV_MAX_BITS`]
/// (in UV units, 2^-15): an eighth of a texel of a 4,096² texture, the largest the
/// renderer uploads, and a thirty-second of a texel of a 1,024² one. gltfpack's default
/// (12 bits over the mesh's UV range) is a whole texel of a 4,096² texture over a unit
/// map. Finer steps only cost bits.
pub const UV_STEP_TARGET: f32 = 1.0 / 32768.0;

/// Texture coordinates on a mesh-wide grid of [`UV_GRID_CODES`] codes per axis over the
/// mesh's UV rectangle. A meshlet's UV block starts with one word per component, its
/// smallest code (low 24 bits) and a shift (high 8 bits); each vertex then stores
/// offsets from those codes, in units of `2^shift` codes, at the meshlet's bits per
/// component ([`UvBlock::bits`], 1 to [`UV_MAX_BITS`]).
///
/// Why not 16 bits over the whole mesh: a tiling map spans many UV units, and 65,536
/// steps over 64 repeats are a step of a whole texel of a 1,024² texture. Why not the
/// grid's full precision everywhere: [`UV_STEP_TARGET`] over a meshlet's part of the map
/// takes fewer bits than the grid's step over it, though less than one would hope on
/// atlas-mapped meshes (Spot, Beast), whose meshlets often straddle a seam and so span
/// far-apart charts. A meshlet spanning the whole map shifts until 16 bits reach, up to
/// [`UV_MAX_SHIFT`], where its LOD error is larger.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct UvQuantization {
    /// The smallest UV of the mesh per component: code 0.
    pub min: [f32; 2],
    /// UV distance per code per component (0 for a mesh without UVs).
    pub step: [f32; 2],
}

/// One meshlet's encoded UVs.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct UvBlock {
    /// Per component, the smallest code (low 24 bits) and the shift (high 8 bits): the
    /// block's first two payload words.
    pub origin: [u32; 2],
    /// Bits of each vertex's offset per component, 1 to [`UV_MAX_BITS`] (kept in the
    /// meshlet record, so the payload's layout follows from the record alone).
    pub bits: [u32; 2],
    /// Each vertex's offsets from `origin`, in units of `2^shift` codes.
    pub offsets: Vec<[u32; 2]>,
}

impl UvQuantization {
    /// The grid over the rectangle `uvs` span.
    pub fn new(uvs: &[[f32; 2]]) -> Self {
        if uvs.is_empty() {
            return Self {
                min: [0.0; 2],
                step: [0.0; 2],
            };
        }
        let (lo, hi) = uvs.iter().fold(
            (Vec2::splat(f32::INFINITY), Vec2::splat(f32::NEG_INFINITY)),
            |(lo, hi), &u| (lo.min(Vec2::from(u)), hi.max(Vec2::from(u))),
        );
        // The whole rectangle fits one meshlet's offsets at the largest shift.
        let step = ((hi - lo) / UV_LARGEST_CODE as f32).max(Vec2::splat(f32::MIN_POSITIVE));
        Self {
            min: lo.to_array(),
            step: step.to_array(),
        }
    }

    /// The grid code of `uv` per component.
    pub fn code(&self, uv: [f32; 2]) -> [u32; 2] {
        [0, 1].map(|k| {
            if self.step[k] == 0.0 {
                0
            } else {
                // In f64: at 2^24 codes an f32 quotient would be off by a code.
                ((f64::from(uv[k]) - f64::from(self.min[k])) / f64::from(self.step[k]))
                    .round()
                    .clamp(0.0, f64::from(UV_LARGEST_CODE)) as u32
            }
        })
    }

    /// The largest shift whose step is at most [`UV_STEP_TARGET`] on component `k` (a
    /// thousandth over it allowed: a unit rectangle's grid step is 2^-24 and a hair).
    fn target_shift(&self, k: usize) -> u32 {
        let target = f64::from(UV_STEP_TARGET) * 1.001;
        (0..=UV_MAX_SHIFT)
            .rev()
            .find(|&s| f64::from(self.step[k]) * f64::from(1u32 << s) <= target)
            .unwrap_or(0)
    }

    /// A meshlet's UV block: per component, the coarsest step down to the grid's that
    /// keeps [`UV_STEP_TARGET`], or the finest whose offsets fit [`UV_MAX_BITS`] where
    /// that target needs more; then the fewest bits that hold the offsets.
    pub fn encode_meshlet(&self, uvs: impl Iterator<Item = [f32; 2]> + Clone) -> UvBlock {
        let (lo, hi) =
            uvs.clone()
                .map(|uv| self.code(uv))
                .fold(([u32::MAX; 2], [0u32; 2]), |(lo, hi), c| {
                    (
                        [lo[0].min(c[0]), lo[1].min(c[1])],
                        [hi[0].max(c[0]), hi[1].max(c[1])],
                    )
                });
        let origin = [0, 1].map(|k| lo[k].min(hi[k]));
        let largest = (1u32 << UV_MAX_BITS) - 1;
        let rounded = |span: u32, s: u32| (span + ((1 << s) >> 1)) >> s;
        let shift = [0, 1].map(|k| {
            let fits = (0..=UV_MAX_SHIFT)
                .find(|&s| rounded(hi[k] - origin[k], s) <= largest)
                .unwrap_or(UV_MAX_SHIFT);
            fits.max(self.target_shift(k))
        });
        let bits = [0, 1].map(|k| bits_for(rounded(hi[k] - origin[k], shift[k])).max(1));
        let offsets = uvs
            .map(|uv| {
                let c = self.code(uv);
                [0, 1].map(|k| rounded(c[k] - origin[k], shift[k]).min((1 << bits[k]) - 1))
            })
            .collect();
        UvBlock {
            origin: [0, 1].map(|k| origin[k] | (shift[k] << 24)),
            bits,
            offsets,
        }
    }

    /// The UV of a vertex's `offset` [`Self::encode_meshlet`] wrote, with its meshlet's
    /// `origin` words, computed as the GPU does.
    pub fn decode(&self, origin: [u32; 2], offset: [u32; 2]) -> [f32; 2] {
        [0, 1].map(|k| {
            let shift = (origin[k] >> 24) & 31;
            let code = (origin[k] & 0xff_ffff).wrapping_add(offset[k] << shift);
            self.min[k] + code as f32 * self.step[k]
        })
    }
}

/// A vertex colour as the asset stores it, one word: red, green and blue as 8-bit sRGB
/// (the encoding colour textures use, so dark gradients keep their steps), alpha as
/// 8-bit linear, red in the low byte. `c` is linear RGBA, clamped to 0..1.
pub fn encode_color(c: [f32; 4]) -> u32 {
    let [r, g, b] = [c[0], c[1], c[2]].map(|v| crate::texture::from_linear(v) as u32);
    let a = (c[3].clamp(0.0, 1.0) * 255.0).round() as u32;
    r | (g << 8) | (b << 16) | (a << 24)
}

/// Linear RGBA of a word [`encode_color`] wrote, as the resolve decodes it.
pub fn decode_color(word: u32) -> [f32; 4] {
    let byte = |k: u32| (word >> (8 * k)) as u8;
    [
        crate::texture::to_linear(byte(0)),
        crate::texture::to_linear(byte(1)),
        crate::texture::to_linear(byte(2)),
        byte(3) as f32 / 255.0,
    ]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn auto_bits_follow_the_reference_error() {
        // Extent 1, reference 0.01: step ≤ 0.01 / 8 / 0.866 = 1.44e-3, 694 cells → 10 bits.
        assert_eq!(auto_position_bits(1.0, &[0.01f32; 20]), 10);
        // Ten times finer detail: 6,929 cells → 13 bits.
        assert_eq!(auto_position_bits(1.0, &[0.001f32; 20]), 13);
        // The 10th percentile, not the minimum: one tiny error does not matter.
        let mut mixed = vec![0.01f32; 20];
        mixed[0] = 1e-5;
        assert_eq!(auto_position_bits(1.0, &mixed), 10);
        // Flat-region noise and roots are ignored; nothing left falls back.
        assert_eq!(
            auto_position_bits(1.0, &[1e-9, f32::INFINITY]),
            FALLBACK_POSITION_BITS
        );
        assert_eq!(auto_position_bits(1.0, &[]), FALLBACK_POSITION_BITS);
        // The finest detail not taken for noise stays within what the decoder handles.
        assert_eq!(auto_position_bits(1.0, &[2e-6; 20]), 22);
        assert!(auto_position_bits(1.0, &[1.01e-6; 20]) <= MAX_POSITION_BITS);
        assert_eq!(auto_position_bits(1.0, &[10.0; 20]), MIN_POSITION_BITS);
    }

    /// The figures quoted at [`NORMAL_BITS`], and the bound it is chosen for.
    #[test]
    fn normal_bits_meet_the_precision_bound() {
        let worst = |bits: u32| {
            let mut worst = 0.0f32;
            let steps = 400;
            for i in 0..=steps {
                for j in 0..2 * steps {
                    let theta = std::f32::consts::PI * i as f32 / steps as f32;
                    let phi = std::f32::consts::PI * j as f32 / steps as f32;
                    let n = Vec3::new(
                        theta.sin() * phi.cos(),
                        theta.sin() * phi.sin(),
                        theta.cos(),
                    );
                    let d = decode_octahedral(encode_octahedral(n, bits), bits);
                    worst = worst.max((d - n).length());
                }
            }
            worst
        };
        let measured: Vec<(u32, f32)> = [9, 10, 11, 12, 16].map(|b| (b, worst(b))).to_vec();
        assert!(worst(NORMAL_BITS) <= NORMAL_ERROR_BOUND, "{measured:?}");
        assert!(
            worst(NORMAL_BITS - 1) > NORMAL_ERROR_BOUND,
            "fewer bits would also do: {measured:?}"
        );
    }

    #[test]
    fn position_bits_parse_with_a_helpful_error() {
        assert_eq!("auto".parse::<PositionBits>(), Ok(PositionBits::Auto));
        assert_eq!("12".parse::<PositionBits>(), Ok(PositionBits::Fixed(12)));
        let e = "30".parse::<PositionBits>().unwrap_err();
        assert!(e.contains("4 to 24") && e.contains("auto"), "{e}");
    }
}
