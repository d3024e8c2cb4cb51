//! A fast non-cryptographic 64-bit checksum over 32-bit words: four independent lanes
//! keep the multiplier pipeline busy, so verifying a file costs far less than reading
//! it. It detects accidental damage (truncation is caught earlier, by size), not
//! tampering.

const K1: u64 = 0x9E37_79B1_85EB_CA87;
const K2: u64 = 0xC2B2_AE3D_27D4_EB4F;

pub fn checksum(words: &[u32]) -> u64 {
    let mut lanes = [K1, K2, K1 ^ K2, K1.rotate_left(17)];
    let mut chunks = words.chunks_exact(8);
    for c in &mut chunks {
        for (l, lane) in lanes.iter_mut().enumerate() {
            let w = (c[2 * l] as u64) | ((c[2 * l + 1] as u64) << 32);
            *lane = (*lane ^ w.wrapping_mul(K2))
                .rotate_left(31)
                .wrapping_mul(K1);
        }
    }
    let mut h = (words.len() as u64).wrapping_mul(K1);
    for lane in lanes {
        h = (h ^ lane).wrapping_mul(K2).rotate_left(27);
    }
    for &w in chunks.remainder() {
        h = (h ^ (w as u64).wrapping_mul(K1))
            .rotate_left(23)
            .wrapping_mul(K2);
    }
    h ^= h >> 33;
    h = h.wrapping_mul(K1);
    h ^ (h >> 29)
}

/// The checksum stored in a file: the header (with its checksum field read as zero)
/// and the body, so that damage to any byte is detected.
pub fn file_checksum(header: &[u32], body: &[u32]) -> u64 {
    let mut h = [0u32; super::format::AssetHeader::WORDS];
    h.copy_from_slice(header);
    let at = std::mem::offset_of!(super::format::AssetHeader, checksum) / 4;
    h[at] = 0;
    h[at + 1] = 0;
    checksum(body) ^ checksum(&h).rotate_left(32).wrapping_mul(K1)
}
