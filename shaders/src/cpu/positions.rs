//! Quantised, bit-packed meshlet positions and packed u8 indices, as `meshlight::meshlet`
//! decodes them. The asset builder writes streams with these functions.

/// A mesh-wide quantisation grid: `position = origin + q * step` for integer q.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Grid {
    /// The grid point with q = 0, usually the mesh's bounding-box minimum.
    pub origin: [f32; 3],
    /// Mesh units per grid step; a power of two keeps `q * step` exact.
    pub step: f32,
}

impl Grid {
    /// The `vec4` form stored in an instance: xyz origin, w step.
    pub fn to_vec4(self) -> [f32; 4] {
        [self.origin[0], self.origin[1], self.origin[2], self.step]
    }

    /// The nearest grid coordinate of a position at or above `origin`.
    pub fn quantize(self, p: [f32; 3]) -> [u32; 3] {
        std::array::from_fn(|i| ((p[i] - self.origin[i]) / self.step).round().max(0.0) as u32)
    }

    /// The position of a grid coordinate, computed like the shader: integer first.
    pub fn dequantize(self, q: [u32; 3]) -> [f32; 3] {
        std::array::from_fn(|i| self.origin[i] + q[i] as f32 * self.step)
    }
}

/// The fewest bits that hold every value in `0..=max_delta`.
pub fn bits_for(max_delta: u32) -> u32 {
    32 - max_delta.leading_zeros()
}

/// Per-axis bit widths in the `Meshlet::position_bits` form: x | y << 8 | z << 16.
pub fn pack_bit_widths(bits: [u32; 3]) -> u32 {
    assert!(
        bits.iter().all(|&b| b <= 32),
        "a bit width above 32: {bits:?}"
    );
    bits[0] | (bits[1] << 8) | (bits[2] << 16)
}

/// Appends one meshlet's position deltas (q - meshlet minimum) to `stream`, bit-packed
/// with `bits` per axis, then padding so that the shader's two-word read of every field
/// (even a zero-width one at the very end) stays inside the stream. Returns the
/// meshlet's `position_offset`; the next meshlet may start right after.
pub fn pack_positions(deltas: &[[u32; 3]], bits: [u32; 3], stream: &mut Vec<u32>) -> u32 {
    let offset = u32::try_from(stream.len()).expect("position stream beyond 2^32 words");
    let mut writer = BitWriter {
        stream,
        start: offset as usize,
        bit: 0,
    };
    for delta in deltas {
        for axis in 0..3 {
            let count = bits[axis];
            assert!(
                count == 32 || delta[axis] >> count == 0,
                "delta {} does not fit {count} bits",
                delta[axis]
            );
            writer.write(delta[axis], count);
        }
    }
    // The last field may start at bit `total` (a zero-width axis), whose two-word read
    // touches word total / 32 + 1.
    let total = writer.bit;
    stream.resize(offset as usize + total / 32 + 2, 0);
    offset
}

struct BitWriter<'a> {
    stream: &'a mut Vec<u32>,
    start: usize,
    bit: usize,
}

impl BitWriter<'_> {
    fn write(&mut self, value: u32, count: u32) {
        let mut written = 0;
        while written < count {
            let word = self.start + self.bit / 32;
            if self.stream.len() <= word {
                self.stream.resize(word + 1, 0);
            }
            let at = (self.bit % 32) as u32;
            let take = (32 - at).min(count - written);
            let chunk = extract_bits(value, written, take);
            self.stream[word] |= chunk << at;
            written += take;
            self.bit += take as usize;
        }
    }
}

/// WGSL `extractBits` for u32: `count` bits from `offset`, clamped like the builtin.
pub fn extract_bits(value: u32, offset: u32, count: u32) -> u32 {
    let offset = offset.min(32);
    let count = count.min(32 - offset);
    if count == 0 {
        0
    } else {
        ((u64::from(value) >> offset) & ((1u64 << count) - 1)) as u32
    }
}

/// `meshlight::math::read_bits`: a field of `count` bits at `bit` of the word pair.
pub fn read_bits(words: [u32; 2], bit: u32, count: u32) -> u32 {
    let low_count = count.min(32 - bit);
    let low = extract_bits(words[0], bit, low_count);
    if count <= low_count {
        return low;
    }
    let high = extract_bits(words[1], 0, count - low_count);
    low | (high << low_count)
}

/// Decodes local vertex `vertex` of a meshlet exactly as the shader does.
pub fn read_position(
    stream: &[u32],
    position_offset: u32,
    bits: [u32; 3],
    vertex: u32,
) -> [u32; 3] {
    let stride = bits[0] + bits[1] + bits[2];
    let mut before = 0;
    std::array::from_fn(|axis| {
        let bit = vertex * stride + before;
        before += bits[axis];
        let word = (position_offset + bit / 32) as usize;
        read_bits([stream[word], stream[word + 1]], bit % 32, bits[axis])
    })
}

/// Appends a meshlet's triangles as u8 local indices, four per word, first in the low
/// byte. Returns the meshlet's `index_offset`.
pub fn pack_indices(triangles: &[[u8; 3]], stream: &mut Vec<u32>) -> u32 {
    let offset = u32::try_from(stream.len()).expect("index stream beyond 2^32 words");
    let bytes: Vec<u8> = triangles.iter().flatten().copied().collect();
    for chunk in bytes.chunks(4) {
        let mut word = [0u8; 4];
        word[..chunk.len()].copy_from_slice(chunk);
        stream.push(u32::from_le_bytes(word));
    }
    offset
}

/// Corner `corner` of triangle `triangle`, read like the shader.
pub fn read_index(stream: &[u32], index_offset: u32, triangle: u32, corner: u32) -> u32 {
    let byte = triangle * 3 + corner;
    extract_bits(
        stream[(index_offset + byte / 4) as usize],
        (byte % 4) * 8,
        8,
    )
}
