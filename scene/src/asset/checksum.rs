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

/// Recomputes the checksums of an asset's words in place: each page's, then the
/// header's over the resident part (which holds the page records). The writer's last
/// step, and what a tool that edits an asset in place does after its edit. Ranges the
/// header or a page record puts outside the words are left alone (the loader refuses
/// them), so any words may be given.
pub fn seal(words: &mut [u32]) {
    use super::format::{AssetHeader, PageRecord, SECTION_PAGES, SECTION_PAYLOAD};
    let n = AssetHeader::WORDS;
    if words.len() < n {
        return;
    }
    let header: AssetHeader = *bytemuck::from_bytes(bytemuck::cast_slice(&words[..n]));
    let within = |offset: u32, len: u64| {
        let end = u64::from(offset) + len;
        (end <= words.len() as u64).then_some(offset as usize..end as usize)
    };
    let payload = within(
        header.sections[SECTION_PAYLOAD].offset,
        u64::from(header.sections[SECTION_PAYLOAD].words),
    );
    let pages = within(
        header.sections[SECTION_PAGES].offset,
        u64::from(header.sections[SECTION_PAGES].words),
    );
    if let (Some(payload), Some(pages)) = (payload, pages) {
        let record_words = size_of::<PageRecord>() / 4;
        for at in pages.step_by(record_words) {
            let Some(record) = words.get(at..at + record_words) else {
                break;
            };
            let record: PageRecord = *bytemuck::from_bytes(bytemuck::cast_slice(record));
            let (first, end) = (
                payload.start as u64 + u64::from(record.first_word),
                payload.start as u64 + u64::from(record.first_word) + u64::from(record.words),
            );
            if end > payload.end as u64 {
                continue;
            }
            let sum = page_checksum(bytemuck::cast_slice(&words[first as usize..end as usize]));
            let checksum = std::mem::offset_of!(PageRecord, checksum) / 4;
            words[at + checksum] = sum as u32;
            words[at + checksum + 1] = (sum >> 32) as u32;
        }
    }
    let resident_end = (header.sections[SECTION_PAYLOAD].offset as usize)
        .saturating_add(header.resident_words as usize)
        .clamp(n, words.len());
    let sum = file_checksum(&words[..n], &words[n..resident_end]);
    let at = std::mem::offset_of!(AssetHeader, checksum) / 4;
    words[at] = sum as u32;
    words[at + 1] = (sum >> 32) as u32;
}
