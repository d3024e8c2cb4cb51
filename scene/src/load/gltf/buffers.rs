//! The buffers of a glTF file: the GLB binary chunk, base64 `data:` URIs, or files beside
//! the `.gltf`. Read here rather than by the glTF crate's importer, which also decodes
//! images and would bring an image library into the build for nothing.
//!
//! A model is untrusted input, so a buffer URI may only name a file inside the model's
//! own folder (relative, no `..`, no absolute path or other URI scheme, not through a
//! link that leads outside), and that file must be a regular file under the input size
//! limit: otherwise a downloaded model could pull `/etc/passwd` into an asset, or name
//! `/dev/zero` and never finish loading.

use std::path::{Component, Path, PathBuf};

use gltf::json::Root;

use crate::error::SceneError;
use crate::load::read_file;

/// Every buffer of `root`, each at least as long as its declared `byteLength`; `model`
/// is the glTF file, whose folder external buffers must lie in.
pub fn load_buffers(
    root: &Root,
    mut blob: Option<Vec<u8>>,
    model: &Path,
) -> Result<Vec<Vec<u8>>, SceneError> {
    let err = |reason: String| SceneError::Gltf {
        path: model.to_owned(),
        reason,
    };
    let mut out = Vec::with_capacity(root.buffers.len());
    for (i, b) in root.buffers.iter().enumerate() {
        let fallback = b.extensions.as_ref().is_some_and(|e| {
            super::compressed::is_fallback(e.others.get(super::compressed::EXTENSION))
        });
        if fallback {
            // Only compressed views point into it, and they are decoded from elsewhere.
            out.push(Vec::new());
            continue;
        }
        let data = match b.uri.as_deref() {
            None => blob.take().ok_or_else(|| {
                err(format!(
                    "buffer {i} has no uri and the file has no binary chunk (only a .glb has one)"
                ))
            })?,
            Some(uri) if uri.starts_with("data:") => {
                let (_, payload) = uri.split_once(";base64,").ok_or_else(|| {
                    err(format!("buffer {i} has a data URI that is not base64; embed it as `data:...;base64,`"))
                })?;
                decode_base64(payload)
                    .ok_or_else(|| err(format!("buffer {i} has a data URI with invalid base64")))?
            }
            Some(uri) => {
                let path = referenced_path(model, uri).map_err(|reason| {
                    err(format!(
                        "buffer {i} has the uri {uri:?}, which {reason}; a buffer is a `data:` \
                         URI or a file in the model's folder named relative to it (`mesh.bin`, \
                         `buffers/mesh.bin`)"
                    ))
                })?;
                read_file(&path).map_err(|e| {
                    err(format!(
                        "cannot read buffer {i} ({e}); keep .bin files beside the .gltf"
                    ))
                })?
            }
        };
        if (data.len() as u64) < b.byte_length.0 {
            return Err(err(format!(
                "buffer {i} holds {} bytes but declares byteLength {}",
                data.len(),
                b.byte_length.0
            )));
        }
        out.push(data);
    }
    Ok(out)
}

/// The file a non-`data:` URI of the glTF file `model` names (a buffer's, later an
/// image's), or why it may not be read: it must be a relative path without `..` that,
/// with links resolved, stays inside the model's folder. The one containment rule of
/// every path that follows a reference from a file (the loader, and `bake DIR`'s stamps).
pub fn referenced_path(model: &Path, uri: &str) -> Result<PathBuf, String> {
    let relative = percent_decode(uri).ok_or("is malformed (a bad %-escape)")?;
    // `file:`, `http:`, `C:` and the like: a scheme or a drive, not a relative path.
    let first = relative.split(['/', '\\']).next().unwrap_or("");
    if first.contains(':') {
        return Err("names a URI scheme or drive, not a relative path".into());
    }
    if relative.starts_with(['/', '\\']) {
        return Err("is an absolute path".into());
    }
    for c in Path::new(&relative).components() {
        match c {
            Component::Normal(_) | Component::CurDir => {}
            Component::ParentDir => return Err("leaves the model's folder with `..`".into()),
            Component::RootDir | Component::Prefix(_) => {
                return Err("is an absolute path".into());
            }
        }
    }
    if relative.split(['/', '\\']).any(|part| part == "..") {
        return Err("leaves the model's folder with `..`".into());
    }
    let folder = match model.parent() {
        Some(p) if !p.as_os_str().is_empty() => p,
        _ => Path::new("."),
    };
    let path = folder.join(&relative);
    // A link inside the folder may still lead out of it.
    if let (Ok(folder), Ok(target)) = (folder.canonicalize(), path.canonicalize())
        && !target.starts_with(&folder)
    {
        return Err(format!(
            "leads outside the model's folder (to {})",
            target.display()
        ));
    }
    Ok(path)
}

/// Standard base64 (RFC 4648), padding optional; `None` on any other character.
pub(super) fn decode_base64(text: &str) -> Option<Vec<u8>> {
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

/// A URI path with `%XX` escapes decoded, as glTF writes spaces and other characters;
/// `None` for a malformed escape or bytes that are not UTF-8.
pub fn percent_decode(uri: &str) -> Option<String> {
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
