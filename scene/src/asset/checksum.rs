//! The file checksum: XXH3-64 (the `xxhash-rust` crate), which verifies many GB/s per
//! core, so that checking a file costs far less than reading it. It detects accidental
//! damage (truncation is caught earlier, by size), not tampering.

use xxhash_rust::xxh3::{xxh3_64, xxh3_64_with_seed};

/// The checksum stored in a file: the header (with its checksum field read as zero)
/// seeds the hash of the body, so that damage to any byte is detected.
pub fn file_checksum(header: &[u32], body: &[u32]) -> u64 {
    let mut h = [0u32; super::format::AssetHeader::WORDS];
    h.copy_from_slice(header);
    let at = std::mem::offset_of!(super::format::AssetHeader, checksum) / 4;
    h[at] = 0;
    h[at + 1] = 0;
    let seed = xxh3_64(bytemuck::cast_slice(&h));
    xxh3_64_with_seed(bytemuck::cast_slice(body), seed)
}

/// The checksum of one streamed page's bytes, checked when the page is read back on its
/// own, long after the file's checksum was: the file may have changed since.
pub fn page_checksum(bytes: &[u8]) -> u64 {
    xxh3_64(bytes)
}
