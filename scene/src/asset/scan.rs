//! One pass over every meshlet's packed vertices and triangles, gathering what the DAG
//! checks ([`crate::verify`]) need from the payload: whether every triangle's stored
//! corners lie within the meshlet, how far its farthest vertex lies from the centre of
//! its culling sphere, and the fingerprint of its triangles' boundary
//! ([`crate::chain_fingerprint`]) for the crack check.
//!
//! The renderer runs these checks on every asset it loads, so the pass decodes each
//! meshlet once, into arrays on the stack (a meshlet has at most 255 vertices), skips
//! normals and UVs, and runs on every core; the checks then work on one small record per
//! meshlet. Decoding follows [`MeshletAsset::decode_meshlet`], which is what the GPU
//! does: corners clamped into the meshlet, grid points from `grid_min` plus the packed
//! offsets.

use rayon::prelude::*;

use super::MeshletAsset;
use super::format::{MeshletRecord, PayloadLayout};
use super::triangles::{TriangleBits, for_each_stored, prediction_reciprocal};
use crate::asset::format::MAX_MESHLET_VERTICES;
use crate::chain_fingerprint::{ChainKeys, triangle};
use crate::compress::{bit_window, low_bits};

/// Vertex words a meshlet can have: one more than its 8-bit vertex count allows, so
/// that an index taken modulo it needs no bounds check.
const WORDS: usize = 256;
const _: () = assert!(MAX_MESHLET_VERTICES < WORDS);

/// One meshlet's decoded vertices: their fingerprint words, and their grid points an
/// axis at a time.
struct Decoded {
    words: [(u64, u64); WORDS],
    axes: [[i32; WORDS]; 3],
}

/// What the DAG checks need of one meshlet's payload.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MeshletScan {
    /// The first triangle whose stored corners fall outside the meshlet's vertices (the
    /// GPU clamps them, so the record is damaged).
    pub first_out_of_range: Option<u32>,
    /// Largest distance of a decoded vertex from the culling sphere's centre.
    pub farthest: f32,
    /// Fingerprint of the boundary of the meshlet's triangles, as decoded.
    pub boundary: u64,
}

/// Scans every meshlet whose data the asset holds (all of them, or the roots of one
/// opened for streaming), in parallel; the result is in meshlet order.
pub fn scan_meshlets(asset: &MeshletAsset, keys: &ChainKeys) -> Vec<MeshletScan> {
    let meshlets = &asset.meshlets()[..asset.held_meshlets()];
    // Chunks of meshlets keep rayon's per-item overhead off meshlets this small, and
    // share one array of vertex words.
    const CHUNK: usize = 64;
    let mut scans = vec![
        MeshletScan {
            first_out_of_range: None,
            farthest: 0.0,
            boundary: 0,
        };
        meshlets.len()
    ];
    let payload: &[u8] = bytemuck::cast_slice(asset.payload());
    scans
        .par_chunks_mut(CHUNK)
        .enumerate()
        .for_each(|(c, out)| {
            let meshlets = &meshlets[c * CHUNK..c * CHUNK + out.len()];
            scan_chunk(asset, payload, meshlets, keys, out);
        });
    scans
}

/// Scans `meshlets` into `out`, with the instructions of the machine it runs on where it
/// has them: BMI2's shifts by a register and AVX2 took about a fifth off the decoding,
/// AVX-512's eight triangle records at a time a fifth more.
fn scan_chunk(
    asset: &MeshletAsset,
    payload: &[u8],
    meshlets: &[MeshletRecord],
    keys: &ChainKeys,
    out: &mut [MeshletScan],
) {
    #[cfg(target_arch = "x86_64")]
    {
        use std::arch::is_x86_feature_detected as has;
        if has!("avx512f") && has!("avx512dq") && has!("bmi2") {
            // SAFETY: the features it is compiled for were just detected.
            return unsafe { scan_chunk_avx512(asset, payload, meshlets, keys, out) };
        }
        if has!("avx2") && has!("bmi2") {
            // SAFETY: as above.
            return unsafe { scan_chunk_avx2(asset, payload, meshlets, keys, out) };
        }
    }
    scan_chunk_portable::<false>(asset, payload, meshlets, keys, out)
}

/// [`scan_chunk_avx2`], with the triangle records decoded eight at a time
/// ([`wide_triangles`]).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f,avx512dq,avx2,bmi1,bmi2,lzcnt,popcnt")]
fn scan_chunk_avx512(
    asset: &MeshletAsset,
    payload: &[u8],
    meshlets: &[MeshletRecord],
    keys: &ChainKeys,
    out: &mut [MeshletScan],
) {
    scan_chunk_portable::<true>(asset, payload, meshlets, keys, out)
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,bmi1,bmi2,lzcnt,popcnt")]
fn scan_chunk_avx2(
    asset: &MeshletAsset,
    payload: &[u8],
    meshlets: &[MeshletRecord],
    keys: &ChainKeys,
    out: &mut [MeshletScan],
) {
    scan_chunk_portable::<false>(asset, payload, meshlets, keys, out)
}

/// `WIDE`: decode triangle records with AVX-512, which only [`scan_chunk_avx512`] asks
/// for, having detected it.
#[inline(always)]
fn scan_chunk_portable<const WIDE: bool>(
    asset: &MeshletAsset,
    payload: &[u8],
    meshlets: &[MeshletRecord],
    keys: &ChainKeys,
    out: &mut [MeshletScan],
) {
    let mut decoded = Decoded {
        words: [(0, 0); WORDS],
        axes: [[0; WORDS]; 3],
    };
    for (m, scan) in meshlets.iter().zip(out) {
        *scan = scan_meshlet::<WIDE>(asset, payload, m, keys, &mut decoded);
    }
}

#[inline(always)]
fn scan_meshlet<const WIDE: bool>(
    asset: &MeshletAsset,
    payload: &[u8],
    m: &MeshletRecord,
    keys: &ChainKeys,
    decoded: &mut Decoded,
) -> MeshletScan {
    let layout = PayloadLayout::of(m, asset.header().flags);
    // From the meshlet's data to the payload's end: windows read past a block's last
    // field, and the masks drop what they read there.
    let data = &payload[m.data_offset as usize * 4..];
    let quant = asset.quantization();
    let centre = [m.bounds[0], m.bounds[1], m.bounds[2]];
    let (vc, tc) = (m.vertex_count() as usize, m.triangle_count());
    let Decoded { words, axes } = decoded;
    asset.for_each_grid_point(m, |v, grid| {
        for k in 0..3 {
            axes[k][v] = grid[k] as i32;
        }
        words[v] = keys.point(grid);
    });
    // The distances in a loop of their own, which the compiler vectorises: what
    // `quant.dequantize(grid).distance_squared(centre)` computes, operation for
    // operation. Squares are not negative, so their bits order as they do.
    let (origin, step) = (quant.origin.to_array(), quant.step);
    let mut farthest_bits = 0u32;
    let [xs, ys, zs] = axes.each_ref().map(|a| &a[..vc]);
    for ((&x, &y), &z) in xs.iter().zip(ys).zip(zs) {
        let d = [x, y, z].map(|q| q as f32);
        let d = [0, 1, 2].map(|k| (origin[k] + d[k] * step) - centre[k]);
        let squared = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
        farthest_bits = farthest_bits.max(squared.to_bits());
    }
    let farthest_squared = f32::from_bits(farthest_bits);

    let triangle_bits = m.triangle_bits();
    let block = &data[layout.triangles as usize * 4..];
    let (boundary, in_range) = if WIDE {
        #[cfg(target_arch = "x86_64")]
        // SAFETY: `WIDE` only from `scan_chunk_avx512`, after detecting its features.
        unsafe {
            wide_triangles(block, triangle_bits, vc as u32, tc, words)
        }
        #[cfg(not(target_arch = "x86_64"))]
        fast_triangles(block, triangle_bits, vc as u32, tc, words, 0)
    } else {
        fast_triangles(block, triangle_bits, vc as u32, tc, words, 0)
    };
    let (first_out_of_range, boundary) = if in_range {
        (None, boundary)
    } else {
        // A damaged record: again, as the GPU decodes it (corners clamped), finding it.
        let block = &asset.payload()[(m.data_offset + layout.triangles) as usize..];
        clamped_triangles(block, triangle_bits, vc as u32, tc, words)
    };
    MeshletScan {
        first_out_of_range,
        farthest: farthest_squared.sqrt(),
        boundary,
    }
}

/// The boundary fingerprint of a meshlet's triangles from `start` on, when their records
/// all lie in range (a valid asset's), and whether they do: no clamping and no branch
/// per triangle.
#[inline(always)]
fn fast_triangles(
    block: &[u8],
    bits: TriangleBits,
    vertices: u32,
    triangles: u32,
    words: &[(u64, u64); WORDS],
    start: usize,
) -> (u64, bool) {
    let stride = bits.stride() as usize;
    let bias = 1i64 << (bits.offset.max(1) - 1);
    let reciprocal = prediction_reciprocal(triangles);
    let (offset_mask, delta_mask) = (low_bits(bits.offset), low_bits(bits.delta));
    let mut numerator = vertices as u64 * (start as u64 + 1);
    let mut out_of_range = false;
    let mut boundary = 0u64;
    for t in start..triangles as usize {
        let record = bit_window(block, t * stride);
        let predicted = ((numerator * reciprocal) >> 32) as i64;
        numerator += vertices as u64;
        let first = predicted + (record & offset_mask) as i64 - bias;
        let second = first - ((record >> bits.offset) & delta_mask) as i64;
        let third = first - ((record >> (bits.offset + bits.delta)) & delta_mask) as i64;
        // The other corners lie at or below the first.
        out_of_range |= (first >= vertices as i64) | (second.min(third) < 0);
        boundary = boundary.wrapping_add(triangle(
            words[first as usize % WORDS],
            words[second as usize % WORDS],
            words[third as usize % WORDS],
        ));
    }
    (boundary, !out_of_range)
}

/// [`fast_triangles`], eight triangles at a time in AVX-512 lanes: the same records
/// read, the same arithmetic per lane (wrapping 64-bit products and sums), the lanes'
/// fingerprints added up at the end. Triangles whose 8-byte window would reach past the
/// block, at its end, are left to [`fast_triangles`].
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f,avx512dq")]
fn wide_triangles(
    block: &[u8],
    bits: TriangleBits,
    vertices: u32,
    triangles: u32,
    words: &[(u64, u64); WORDS],
) -> (u64, bool) {
    use std::arch::x86_64::*;
    let stride = bits.stride().max(1) as u64;
    // Triangle `t` reads bytes `(t · stride) / 8 ..+ 8`: inside the block up to here.
    let inside = match block.len().checked_sub(8) {
        Some(last) => ((last as u64 * 8) / stride + 1).min(triangles as u64) as usize,
        None => 0,
    };
    let wide = inside / 8 * 8;
    let splat = |v: u64| _mm512_set1_epi64(v as i64);
    let lane = _mm512_set_epi64(7, 6, 5, 4, 3, 2, 1, 0);
    let (v_stride, v_vertices) = (splat(stride), splat(vertices as u64));
    let v_reciprocal = splat(prediction_reciprocal(triangles));
    let (v_offset_mask, v_delta_mask) = (splat(low_bits(bits.offset)), splat(low_bits(bits.delta)));
    let v_bias = splat(1 << (bits.offset.max(1) - 1));
    let (v_offset, v_second) = (
        splat(bits.offset as u64),
        splat((bits.offset + bits.delta) as u64),
    );
    let zero = _mm512_setzero_si512();
    let mut sum = zero;
    let mut out_of_range: __mmask8 = 0;
    let base = words.as_ptr() as *const i64;
    for t0 in (0..wide).step_by(8) {
        let t = _mm512_add_epi64(splat(t0 as u64), lane);
        let at = _mm512_mullo_epi64(t, v_stride);
        // SAFETY: every lane's window lies inside the block (`inside`).
        let raw = unsafe {
            _mm512_i64gather_epi64::<1>(_mm512_srli_epi64::<3>(at), block.as_ptr() as *const i64)
        };
        let record = _mm512_srlv_epi64(raw, _mm512_and_si512(at, splat(7)));
        let numerator = _mm512_mullo_epi64(_mm512_add_epi64(t, splat(1)), v_vertices);
        let predicted = _mm512_srli_epi64::<32>(_mm512_mullo_epi64(numerator, v_reciprocal));
        let first = _mm512_sub_epi64(
            _mm512_add_epi64(predicted, _mm512_and_si512(record, v_offset_mask)),
            v_bias,
        );
        let below = |shift| _mm512_and_si512(_mm512_srlv_epi64(record, shift), v_delta_mask);
        let second = _mm512_sub_epi64(first, below(v_offset));
        let third = _mm512_sub_epi64(first, below(v_second));
        out_of_range |= _mm512_cmpge_epi64_mask(first, v_vertices)
            | _mm512_cmplt_epi64_mask(_mm512_min_epi64(second, third), zero);
        // Byte offsets of the corners' words, taken modulo their 256 entries.
        let at = |corner| _mm512_slli_epi64::<4>(_mm512_and_si512(corner, splat(255)));
        // SAFETY: offsets below 256 · 16 bytes, within `words`.
        let word = |corner, half: usize| unsafe {
            _mm512_i64gather_epi64::<1>(at(corner), base.add(half))
        };
        let (ra, sa) = (word(first, 0), word(first, 1));
        let (rb, sb) = (word(second, 0), word(second, 1));
        let (rc, sc) = (word(third, 0), word(third, 1));
        let (ab0, ab1) = (_mm512_sub_epi64(rb, ra), _mm512_sub_epi64(sb, sa));
        let (ac0, ac1) = (_mm512_sub_epi64(rc, ra), _mm512_sub_epi64(sc, sa));
        let cross = _mm512_sub_epi64(_mm512_mullo_epi64(ab0, ac1), _mm512_mullo_epi64(ac0, ab1));
        sum = _mm512_add_epi64(sum, cross);
    }
    let (tail, tail_in_range) = fast_triangles(block, bits, vertices, triangles, words, wide);
    (
        (_mm512_reduce_add_epi64(sum) as u64).wrapping_add(tail),
        out_of_range == 0 && tail_in_range,
    )
}

/// The first triangle whose corners fall outside the meshlet, and the boundary
/// fingerprint of the triangles with their corners clamped, as the GPU decodes them.
fn clamped_triangles(
    block: &[u32],
    bits: TriangleBits,
    vertices: u32,
    triangles: u32,
    words: &[(u64, u64); WORDS],
) -> (Option<u32>, u64) {
    let mut first_out_of_range = None;
    let mut boundary = 0u64;
    let last = vertices.max(1) as i64 - 1;
    for_each_stored(block, bits, vertices, triangles, |t, stored| {
        let corners = match stored {
            Some(c) => {
                if c.iter().any(|&c| !(0..vertices as i64).contains(&c)) {
                    first_out_of_range.get_or_insert(t);
                }
                c.map(|c| c.clamp(0, last) as usize)
            }
            None => {
                first_out_of_range.get_or_insert(t);
                [0; 3]
            }
        };
        boundary = boundary.wrapping_add(triangle(
            words[corners[0]],
            words[corners[1]],
            words[corners[2]],
        ));
    });
    (first_out_of_range, boundary)
}

// The scans are compared on built assets.
#[cfg(all(test, feature = "build"))]
mod tests {
    use super::*;
    use crate::asset::triangles::first_out_of_range;
    use crate::chain_fingerprint::triangle;
    use crate::{BuildOptions, build_asset, procedural_mesh};

    /// What the scan finds, from the decoder the tools and tests use.
    fn reference(asset: &MeshletAsset, i: usize, keys: &ChainKeys) -> MeshletScan {
        let m = &asset.meshlets()[i];
        let d = asset.decode_meshlet(i);
        let centre = glam::Vec3::new(m.bounds[0], m.bounds[1], m.bounds[2]);
        let words: Vec<(u64, u64)> = d.grid.iter().map(|&p| keys.point(p)).collect();
        MeshletScan {
            first_out_of_range: first_out_of_range(
                asset.triangle_block(m),
                m.triangle_bits(),
                m.vertex_count(),
                m.triangle_count(),
            ),
            farthest: d
                .positions
                .iter()
                .map(|p| p.distance(centre))
                .fold(0.0, f32::max),
            boundary: d.triangles.iter().fold(0u64, |sum, t| {
                let [a, b, c] = t.map(|v| words[v as usize]);
                sum.wrapping_add(triangle(a, b, c))
            }),
        }
    }

    #[test]
    fn the_scan_finds_what_the_decoder_gives() {
        let mut asset = build_asset(&procedural_mesh(12), &BuildOptions::default(), &mut |_| {})
            .unwrap()
            .asset;
        let keys = ChainKeys::fixed(3);
        let check = |asset: &MeshletAsset| {
            let scans = scan_meshlets(asset, &keys);
            for (i, scan) in scans.iter().enumerate() {
                assert_eq!(*scan, reference(asset, i, &keys), "meshlet {i}");
            }
            // The portable decoder too, where the machine's own instructions were used.
            let mut portable = scans.clone();
            let payload: &[u8] = bytemuck::cast_slice(asset.payload());
            scan_chunk_portable::<false>(asset, payload, asset.meshlets(), &keys, &mut portable);
            assert_eq!(portable, scans);
            scans
        };
        assert!(check(&asset).iter().all(|s| s.first_out_of_range.is_none()));
        // Damage the triangle records of a few meshlets (all their bits set: corners
        // past the vertices) and move a vertex far from its meshlet's sphere.
        for i in [0, 5, 9] {
            let m = asset.meshlets()[i];
            let layout = PayloadLayout::of(&m, asset.header().flags);
            let at = asset.header().sections[super::super::format::SECTION_PAYLOAD].offset
                + m.data_offset;
            asset.words[(at + layout.triangles) as usize] = u32::MAX;
            asset.words[at as usize] ^= 0x3ff;
        }
        let scans = check(&asset);
        assert!(scans[5].first_out_of_range.is_some());
        assert!(scans[5].farthest > asset.meshlets()[5].bounds[3]);
    }
}
