//! The triangle records of a meshlet: fixed width, so a thread per triangle decodes its
//! own record with no other state.
//!
//! Local vertices are numbered in order of first use along meshoptimizer's triangle
//! order, so the largest corner of triangle `t` is close to `(t + 1) · vertices /
//! triangles`. A record stores that corner as a small signed offset from the
//! prediction, then the other two corners, in winding order, as offsets below it.
//! Measured over every meshlet of the procedural mesh and the bunny: 16.2 bits per
//! triangle, against 18.7 for the smallest corner plus two offsets and 24 for three
//! bytes.

use crate::compress::{BitWriter, bit_window, bits_for, low_bits};

/// Field widths of one meshlet's triangle records.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct TriangleBits {
    /// Bits of the largest corner's offset from its prediction (biased by half).
    pub offset: u32,
    /// Bits of each of the two other corners' distance below the largest.
    pub delta: u32,
}

impl TriangleBits {
    /// Bits of one record, so that a thread per triangle finds its record by
    /// multiplying.
    pub fn stride(self) -> u32 {
        self.offset + 2 * self.delta
    }
}

/// Where triangle `t` of `triangles` predicts its largest corner.
pub fn predicted_corner(t: u32, vertices: u32, triangles: u32) -> i64 {
    ((t as i64 + 1) * vertices as i64) / triangles.max(1) as i64
}

/// Encodes `triangles` (local indices) into whole words appended to `out`; returns the
/// field widths. Each triangle is rotated to start at its largest corner, keeping its
/// winding.
pub fn encode(triangles: &[[u32; 3]], vertices: u32, out: &mut Vec<u32>) -> TriangleBits {
    let tc = triangles.len() as u32;
    let rotated: Vec<[u32; 3]> = triangles
        .iter()
        .map(|t| {
            let r = (0..3)
                .max_by_key(|&k| (t[k], std::cmp::Reverse(k)))
                .unwrap_or(0);
            [t[r], t[(r + 1) % 3], t[(r + 2) % 3]]
        })
        .collect();
    let offsets: Vec<i64> = rotated
        .iter()
        .enumerate()
        .map(|(i, t)| t[0] as i64 - predicted_corner(i as u32, vertices, tc))
        .collect();
    let (lo, hi) = offsets
        .iter()
        .fold((0i64, 0i64), |(lo, hi), &o| (lo.min(o), hi.max(o)));
    let mut offset = 1;
    while -(1i64 << (offset - 1)) > lo || (1i64 << (offset - 1)) - 1 < hi {
        offset += 1;
    }
    let delta = bits_for(
        rotated
            .iter()
            .map(|t| (t[0] - t[1]).max(t[0] - t[2]))
            .max()
            .unwrap_or(0),
    );
    let bias = 1i64 << (offset - 1);
    let mut w = BitWriter::new(out);
    for (t, o) in rotated.iter().zip(&offsets) {
        w.put((o + bias) as u32, offset);
        w.put(t[0] - t[1], delta);
        w.put(t[0] - t[2], delta);
    }
    TriangleBits { offset, delta }
}

/// The three corners of triangle `t` as stored, which may lie outside `0..vertices` in
/// a damaged record; `None` when the block is too short for the record.
fn stored_corners(
    block: &[u32],
    t: u32,
    bits: TriangleBits,
    vertices: u32,
    triangles: u32,
) -> Option<[i64; 3]> {
    let at = t as usize * bits.stride() as usize;
    let (word, shift) = (at / 32, at % 32);
    // A record is at most 25 bits, so it lies within two consecutive words.
    let lo = *block.get(word)? as u64;
    let hi = block.get(word + 1).copied().unwrap_or(0) as u64;
    let record = (lo | (hi << 32)) >> shift;
    let mask = |b: u32| (1u64 << b) - 1;
    let offset = (record & mask(bits.offset)) as i64 - (1i64 << (bits.offset.max(1) - 1));
    let d1 = ((record >> bits.offset) & mask(bits.delta)) as i64;
    let d2 = ((record >> (bits.offset + bits.delta)) & mask(bits.delta)) as i64;
    let first = predicted_corner(t, vertices, triangles) + offset;
    Some([first, first - d1, first - d2])
}

/// The multiplier that divides a prediction's numerator `(t + 1) · vertices` by the
/// triangle count: `n / d = n · ⌈2^32 / d⌉ >> 32` exactly for `n` below `2^32 / d`,
/// and counts are 8-bit, so numerators stay below 2^16.
pub fn prediction_reciprocal(triangles: u32) -> u64 {
    (1u64 << 32).div_ceil(triangles.clamp(1, 255) as u64)
}

/// Calls `each` with every triangle's index and stored corners in order, as
/// `stored_corners` gives them one at a time, but with the prediction's division done
/// as a multiplication: the load-time checks visit every triangle of an asset, and a
/// division per triangle cost as much as the rest of decoding it.
pub fn for_each_stored(
    block: &[u32],
    bits: TriangleBits,
    vertices: u32,
    triangles: u32,
    mut each: impl FnMut(u32, Option<[i64; 3]>),
) {
    let bytes: &[u8] = bytemuck::cast_slice(block);
    let stride = bits.stride() as usize;
    let bias = 1i64 << (bits.offset.max(1) - 1);
    let (offset_mask, delta_mask) = (low_bits(bits.offset), low_bits(bits.delta));
    let reciprocal = prediction_reciprocal(triangles);
    let vertices = vertices.min(255) as u64;
    let mut numerator = vertices;
    for t in 0..triangles.min(255) {
        let at = t as usize * stride;
        let predicted = ((numerator * reciprocal) >> 32) as i64;
        // A record starting past the block is missing (the block is too short).
        let corners = (at / 32 < block.len()).then(|| {
            let record = bit_window(bytes, at);
            let first = predicted + (record & offset_mask) as i64 - bias;
            let d1 = ((record >> bits.offset) & delta_mask) as i64;
            let d2 = ((record >> (bits.offset + bits.delta)) & delta_mask) as i64;
            [first, first - d1, first - d2]
        });
        each(t, corners);
        numerator += vertices;
    }
}

/// Decodes triangle `t` from a meshlet's triangle `block`. Corners are clamped into
/// `0..vertices`, as the GPU decoder clamps them: no record, however damaged, can
/// index outside its meshlet, so loading need not decode every triangle to check it
/// (that took most of the load time). [`first_out_of_range`] finds damaged records.
pub fn decode(
    block: &[u32],
    t: u32,
    bits: TriangleBits,
    vertices: u32,
    triangles: u32,
) -> [u32; 3] {
    let last = vertices.max(1) as i64 - 1;
    stored_corners(block, t, bits, vertices, triangles)
        .map_or([0; 3], |c| c.map(|c| c.clamp(0, last) as u32))
}

/// The first triangle whose stored corners fall outside `0..vertices` (and were
/// clamped by [`decode`]): a damaged asset, which `verify` reports.
pub fn first_out_of_range(
    block: &[u32],
    bits: TriangleBits,
    vertices: u32,
    triangles: u32,
) -> Option<u32> {
    // Every record, the division done as `for_each_stored` does it (a page's checks
    // visit every triangle of the page). First without a branch per triangle: the
    // lowest corner (a record's first corner is its highest: the deltas are
    // subtracted) and the highest first corner. Only a block that fails is walked
    // again, for its first bad triangle.
    let (mut lowest, mut highest, mut missing) = (i64::MAX, i64::MIN, false);
    for_each_stored(
        block,
        bits,
        vertices,
        triangles,
        |_, corners| match corners {
            Some([a, b, c]) => {
                lowest = lowest.min(b.min(c));
                highest = highest.max(a);
            }
            None => missing = true,
        },
    );
    if !missing && lowest >= 0 && highest < i64::from(vertices) {
        return None;
    }
    let mut first = None;
    for_each_stored(block, bits, vertices, triangles, |t, corners| {
        let bad = corners.is_none_or(|c| c.iter().any(|&c| !(0..vertices as i64).contains(&c)));
        if bad && first.is_none() {
            first = Some(t);
        }
    });
    first
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_stepped_prediction_is_the_divided_one() {
        for triangles in 1..=255u32 {
            for vertices in [1u32, 2, 7, 64, 128, 200, 254, 255] {
                let bits = TriangleBits {
                    offset: 9,
                    delta: 0,
                };
                // One record per triangle with offset field = bias: corner = prediction.
                let mut words = Vec::new();
                {
                    let mut w = crate::compress::BitWriter::new(&mut words);
                    for _ in 0..triangles {
                        w.put(1 << 8, 9);
                    }
                }
                for_each_stored(&words, bits, vertices, triangles, |t, corners| {
                    assert_eq!(
                        corners.map(|c| c[0]),
                        Some(predicted_corner(t, vertices, triangles)),
                        "{vertices} vertices, {triangles} triangles, triangle {t}"
                    );
                });
            }
        }
    }

    #[test]
    fn records_round_trip_with_winding_kept() {
        let triangles = [[0, 1, 2], [2, 1, 3], [3, 4, 2], [5, 0, 4], [1, 5, 3]];
        let mut words = Vec::new();
        let bits = encode(&triangles, 6, &mut words);
        for (t, tri) in triangles.iter().enumerate() {
            let d = decode(&words, t as u32, bits, 6, 5);
            let r = (0..3).find(|&k| d[k] == tri[0]).unwrap();
            assert_eq!([d[r], d[(r + 1) % 3], d[(r + 2) % 3]], *tri);
        }
        assert_eq!(first_out_of_range(&words, bits, 6, 5), None);
        for (vertices, triangles) in [(6, 5), (5, 5), (6, 3), (200, 5), (255, 1), (1, 255)] {
            let mut visited = 0;
            for_each_stored(&words, bits, vertices, triangles, |t, corners| {
                assert_eq!(
                    corners,
                    stored_corners(&words, t, bits, vertices, triangles),
                    "{vertices} vertices, {triangles} triangles: triangle {t}"
                );
                visited += 1;
            });
            assert_eq!(visited, triangles);
        }
        // One vertex fewer: some corner falls outside; it is found, and decodes clamped.
        let t = first_out_of_range(&words, bits, 5, 5).unwrap();
        assert!(decode(&words, t, bits, 5, 5).iter().all(|&c| c < 5));
    }
}
