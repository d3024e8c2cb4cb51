//! The buffers of a glTF file: the GLB binary chunk, base64 `data:` URIs, or files beside
//! the `.gltf`. Read here rather than by the glTF crate's importer, which also decodes
//! images and would bring an image library into the build for nothing.

use std::path::Path;

use gltf::json::Root;

/// Every buffer of `root`, each at least as long as its declared `byteLength`.
pub fn load_buffers(
    root: &Root,
    mut blob: Option<Vec<u8>>,
    base: Option<&Path>,
) -> Result<Vec<Vec<u8>>, String> {
    let mut out = Vec::with_capacity(root.buffers.len());
    for (i, b) in root.buffers.iter().enumerate() {
        let data = match b.uri.as_deref() {
            None => blob.take().ok_or_else(|| {
                format!(
                    "buffer {i} has no uri and the file has no binary chunk (only a .glb has one)"
                )
            })?,
            Some(uri) if uri.starts_with("data:") => {
                let (_, payload) = uri.split_once(";base64,").ok_or_else(|| {
                    format!("buffer {i} has a data URI that is not base64; embed it as `data:...;base64,`")
                })?;
                decode_base64(payload)
                    .ok_or_else(|| format!("buffer {i} has a data URI with invalid base64"))?
            }
            Some(uri) => {
                let relative = percent_decode(uri)
                    .ok_or_else(|| format!("buffer {i} has a malformed uri {uri:?}"))?;
                let path = base.unwrap_or(Path::new(".")).join(&relative);
                std::fs::read(&path).map_err(|e| {
                    format!(
                        "cannot read buffer {i} from {} ({e}); keep .bin files beside the .gltf",
                        path.display()
                    )
                })?
            }
        };
        if (data.len() as u64) < b.byte_length.0 {
            return Err(format!(
                "buffer {i} holds {} bytes but declares byteLength {}",
                data.len(),
                b.byte_length.0
            ));
        }
        out.push(data);
    }
    Ok(out)
}

/// Standard base64 (RFC 4648), padding optional; `None` on any other character.
fn decode_base64(text: &str) -> Option<Vec<u8>> {
    let value = |c: u8| -> Option<u32> {
        Some(match c {
            b'A'..=b'Z' => c - b'A',
            b'a'..=b'z' => c - b'a' + 26,
            b'0'..=b'9' => c - b'0' + 52,
            b'+' => 62,
            b'/' => 63,
            _ => return None,
        } as u32)
    };
    let digits = text.trim_end_matches('=').as_bytes();
    let mut out = Vec::with_capacity(digits.len() * 3 / 4);
    for chunk in digits.chunks(4) {
        let mut n = 0u32;
        for (k, &c) in chunk.iter().enumerate() {
            n |= value(c)? << (18 - 6 * k);
        }
        let bytes = [(n >> 16) as u8, (n >> 8) as u8, n as u8];
        match chunk.len() {
            4 => out.extend_from_slice(&bytes),
            3 => out.extend_from_slice(&bytes[..2]),
            2 => out.push(bytes[0]),
            _ => return None,
        }
    }
    Some(out)
}

/// A URI path with `%XX` escapes decoded.
fn percent_decode(uri: &str) -> Option<String> {
    let bytes = uri.as_bytes();
    let mut out = Vec::with_capacity(bytes.len());
    let mut i = 0;
    while i < bytes.len() {
        if bytes[i] == b'%' {
            let hex = std::str::from_utf8(bytes.get(i + 1..i + 3)?).ok()?;
            out.push(u8::from_str_radix(hex, 16).ok()?);
            i += 3;
        } else {
            out.push(bytes[i]);
            i += 1;
        }
    }
    String::from_utf8(out).ok()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn base64_and_percent_escapes_decode() {
        assert_eq!(decode_base64("TWFu").unwrap(), b"Man");
        assert_eq!(decode_base64("TWE=").unwrap(), b"Ma");
        assert_eq!(decode_base64("TQ==").unwrap(), b"M");
        assert_eq!(decode_base64("").unwrap(), b"");
        assert!(decode_base64("TW?u").is_none());
        assert!(decode_base64("T").is_none());
        assert_eq!(percent_decode("a%20b.bin").unwrap(), "a b.bin");
        assert!(percent_decode("a%2").is_none());
    }
}
