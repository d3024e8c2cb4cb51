//! Vertex compression: positions on one mesh-wide grid, bit-packed per meshlet at the
//! fewest bits per axis; octahedral normals in 2×16-bit snorm; UVs as 2×16-bit unorm
//! over the mesh's UV rectangle; three `u8` local indices per triangle.
//!
//! One grid for the whole mesh is what keeps LOD cuts watertight after quantisation:
//! a vertex shared by two meshlets decodes to bit-identical positions in both.

use glam::{Vec2, Vec3};

/// Default bits per axis of the position grid: a step of 1/65535 of the largest extent,
/// orders of magnitude below the error of the first simplified level on the meshes we
/// build, so quantisation never decides which LOD is drawn.
pub const DEFAULT_POSITION_BITS: u32 = 16;
/// The grid and the packed deltas are decoded with 32-bit integer maths and `f32`, which
/// is exact up to 2^24 steps.
pub const MAX_POSITION_BITS: u32 = 24;
pub const MIN_POSITION_BITS: u32 = 4;

/// The mesh-wide position grid: `position = origin + step * q`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Quantization {
    pub origin: Vec3,
    pub step: f32,
    pub bits: u32,
}

impl Quantization {
    /// A grid of `bits` per axis over the largest extent of the bounds.
    pub fn new(min: Vec3, max: Vec3, bits: u32) -> Self {
        let extent = (max - min).max_element();
        let cells = ((1u64 << bits) - 1) as f32;
        // A point mesh or a flat mesh still needs a non-zero step.
        let step = if extent > 0.0 { extent / cells } else { 1.0 };
        Self {
            origin: min,
            step,
            bits,
        }
    }

    pub fn quantize(&self, p: Vec3) -> [u32; 3] {
        let max = ((1u64 << self.bits) - 1) as f32;
        ((p - self.origin) / self.step)
            .round()
            .clamp(Vec3::ZERO, Vec3::splat(max))
            .to_array()
            .map(|c| c as u32)
    }

    pub fn dequantize(&self, q: [u32; 3]) -> Vec3 {
        self.origin + Vec3::new(q[0] as f32, q[1] as f32, q[2] as f32) * self.step
    }

    /// Largest distance between a point and its decoded grid point.
    pub fn max_error(&self) -> f32 {
        self.step * 0.5 * 3f32.sqrt()
    }
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
    pub fn new(words: &'a mut Vec<u32>) -> Self {
        Self { words, bit: 0 }
    }

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

/// Words of a meshlet's packed positions.
pub fn position_words(vertex_count: u32, bits: [u32; 3]) -> u32 {
    (vertex_count * (bits[0] + bits[1] + bits[2])).div_ceil(32)
}

/// Octahedral mapping of a unit vector into 2×16-bit snorm, packed x | y << 16.
pub fn encode_normal(n: Vec3) -> u32 {
    let n = n / (n.x.abs() + n.y.abs() + n.z.abs());
    let mut o = Vec2::new(n.x, n.y);
    if n.z < 0.0 {
        o = (Vec2::ONE - Vec2::new(o.y, o.x).abs()) * Vec2::new(sign(o.x), sign(o.y));
    }
    let s = |v: f32| ((v.clamp(-1.0, 1.0) * 32767.0).round() as i16) as u16 as u32;
    s(o.x) | (s(o.y) << 16)
}

pub fn decode_normal(packed: u32) -> Vec3 {
    let u = |v: u32| ((v as u16 as i16) as f32 / 32767.0).max(-1.0);
    let (x, y) = (u(packed & 0xffff), u(packed >> 16));
    let z = 1.0 - x.abs() - y.abs();
    let t = (-z).max(0.0);
    let x = x + if x >= 0.0 { -t } else { t };
    let y = y + if y >= 0.0 { -t } else { t };
    Vec3::new(x, y, z).normalize()
}

fn sign(v: f32) -> f32 {
    if v >= 0.0 { 1.0 } else { -1.0 }
}

/// Texture coordinates as 2×16-bit unorm over the mesh's UV rectangle.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct UvQuantization {
    pub min: [f32; 2],
    pub step: [f32; 2],
}

impl UvQuantization {
    pub fn new(uvs: &[[f32; 2]]) -> Self {
        let (lo, hi) = uvs.iter().fold(
            (Vec2::splat(f32::INFINITY), Vec2::splat(f32::NEG_INFINITY)),
            |(lo, hi), &u| (lo.min(Vec2::from(u)), hi.max(Vec2::from(u))),
        );
        if uvs.is_empty() {
            return Self {
                min: [0.0; 2],
                step: [0.0; 2],
            };
        }
        let step = ((hi - lo) / 65535.0).max(Vec2::splat(f32::MIN_POSITIVE));
        Self {
            min: lo.to_array(),
            step: step.to_array(),
        }
    }

    pub fn encode(&self, uv: [f32; 2]) -> u32 {
        let q = |k: usize| {
            if self.step[k] == 0.0 {
                0
            } else {
                ((uv[k] - self.min[k]) / self.step[k])
                    .round()
                    .clamp(0.0, 65535.0) as u32
            }
        };
        q(0) | (q(1) << 16)
    }

    pub fn decode(&self, packed: u32) -> [f32; 2] {
        [
            self.min[0] + (packed & 0xffff) as f32 * self.step[0],
            self.min[1] + (packed >> 16) as f32 * self.step[1],
        ]
    }
}
