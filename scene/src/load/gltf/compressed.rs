//! Buffer views compressed with `EXT_meshopt_compression` (what `gltfpack -c` writes),
//! decoded once after the buffers are loaded. Each compressed view is replaced by a plain
//! one over its decoded bytes (appended as a new buffer), so every reader after this step
//! (accessors, images) sees an ordinary file and applies its ordinary checks.
//!
//! The compressed stream is untrusted: every field is checked against the buffer it names
//! and against the loader's input limit before anything is decoded, and meshoptimizer's
//! decoders never read or write outside the sizes given (garbage in gives garbage values,
//! which the accessor and index checks after this catch, not memory errors).

use gltf::json::Root;
use gltf::json::Value;
use gltf::json::buffer::Stride;
use gltf::json::validation::USize64;

use crate::load::MAX_INPUT_BYTES;

/// The extension's name, as files list it.
pub const EXTENSION: &str = "EXT_meshopt_compression";

/// Whether a buffer whose `EXT_meshopt_compression` object is `ext` is the extension's
/// fallback buffer: a placeholder that a loader decoding the views never reads (it has
/// no data, or data for loaders without the extension).
pub fn is_fallback(ext: Option<&Value>) -> bool {
    ext.and_then(|e| e.get("fallback"))
        .and_then(Value::as_bool)
        .unwrap_or(false)
}

/// How a view's stream was encoded.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Mode {
    /// Vertex attributes (`meshopt_encodeVertexBuffer`).
    Attributes,
    /// A triangle list (`meshopt_encodeIndexBuffer`).
    Triangles,
    /// Any index sequence (`meshopt_encodeIndexSequence`).
    Indices,
}

/// The filter applied to decoded attributes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Filter {
    None,
    Octahedral,
    Quaternion,
    Exponential,
}

/// One view's `EXT_meshopt_compression` object, checked.
struct Stream {
    buffer: usize,
    offset: usize,
    length: usize,
    stride: usize,
    count: usize,
    mode: Mode,
    filter: Filter,
}

/// Decodes every compressed view of `root` from `buffers`, appending the decoded bytes
/// as new buffers and pointing the views at them. The error names the view and what
/// is wrong with it.
pub fn decode_views(root: &mut Root, buffers: &mut Vec<Vec<u8>>) -> Result<(), String> {
    let mut decoded_total = 0usize;
    for (i, view) in root.buffer_views.iter_mut().enumerate() {
        let Some(ext) = view
            .extensions
            .as_ref()
            .and_then(|e| e.others.get(EXTENSION))
        else {
            continue;
        };
        let what = format!("buffer view {i} ({EXTENSION})");
        let stream = parse(ext, buffers).map_err(|e| format!("{what}: {e}"))?;
        let size = stream.count.saturating_mul(stream.stride);
        decoded_total = decoded_total.saturating_add(size);
        if decoded_total as u64 > MAX_INPUT_BYTES {
            return Err(format!(
                "{what}: the compressed views decode to more than {MAX_INPUT_BYTES} bytes, the \
                 loader's input limit; split the scene into smaller files"
            ));
        }
        let source = &buffers[stream.buffer][stream.offset..stream.offset + stream.length];
        let bytes = decode(&stream, source).map_err(|e| format!("{what}: {e}"))?;
        view.buffer = gltf::json::Index::new(buffers.len() as u32);
        view.byte_offset = Some(USize64(0));
        view.byte_length = USize64(bytes.len() as u64);
        if stream.mode == Mode::Attributes {
            view.byte_stride = Some(Stride(stream.stride));
        }
        buffers.push(bytes);
    }
    Ok(())
}

fn parse(ext: &Value, buffers: &[Vec<u8>]) -> Result<Stream, String> {
    let field = |name: &str| -> Result<Option<usize>, String> {
        match ext.get(name) {
            None => Ok(None),
            Some(v) => v
                .as_u64()
                .and_then(|n| usize::try_from(n).ok())
                .map(Some)
                .ok_or_else(|| format!("its {name} is {v}, not a whole number")),
        }
    };
    let required = |name: &str| {
        field(name)?.ok_or_else(|| format!("it has no {name}; the extension requires one"))
    };
    let buffer = required("buffer")?;
    let offset = field("byteOffset")?.unwrap_or(0);
    let length = required("byteLength")?;
    let stride = required("byteStride")?;
    let count = required("count")?;
    let mode = match ext.get("mode").and_then(Value::as_str) {
        Some("ATTRIBUTES") => Mode::Attributes,
        Some("TRIANGLES") => Mode::Triangles,
        Some("INDICES") => Mode::Indices,
        other => {
            return Err(format!(
                "its mode is {}, not ATTRIBUTES, TRIANGLES or INDICES",
                other.map_or("missing".to_owned(), |m| format!("{m:?}"))
            ));
        }
    };
    let filter = match ext.get("filter").and_then(Value::as_str) {
        None | Some("NONE") => Filter::None,
        Some("OCTAHEDRAL") => Filter::Octahedral,
        Some("QUATERNION") => Filter::Quaternion,
        Some("EXPONENTIAL") => Filter::Exponential,
        Some(other) => {
            return Err(format!(
                "its filter is {other:?}, not NONE, OCTAHEDRAL, QUATERNION or EXPONENTIAL"
            ));
        }
    };
    let data = buffers.get(buffer).ok_or_else(|| {
        format!(
            "it names buffer {buffer}, but the file has only {}",
            buffers.len()
        )
    })?;
    if offset
        .checked_add(length)
        .is_none_or(|end| end > data.len())
    {
        return Err(format!(
            "its bytes {offset} + {length} lie outside buffer {buffer} of {} bytes",
            data.len()
        ));
    }
    let stride_ok = match mode {
        Mode::Attributes => (1..=256).contains(&stride) && stride.is_multiple_of(4),
        Mode::Triangles | Mode::Indices => stride == 2 || stride == 4,
    };
    if !stride_ok {
        return Err(format!(
            "its byteStride {stride} does not suit mode {} (attributes: a multiple of 4 up \
             to 256; indices: 2 or 4)",
            ext["mode"]
        ));
    }
    if mode == Mode::Triangles && !count.is_multiple_of(3) {
        return Err(format!(
            "mode TRIANGLES with a count of {count}, not a whole number of triangles"
        ));
    }
    let filter_ok = match filter {
        Filter::None => true,
        _ if mode != Mode::Attributes => false,
        Filter::Octahedral => stride == 4 || stride == 8,
        Filter::Quaternion => stride == 8,
        Filter::Exponential => stride.is_multiple_of(4),
    };
    if !filter_ok {
        return Err(format!(
            "filter {} does not suit mode {} with byteStride {stride} (octahedral: 4 or 8; \
             quaternion: 8; exponential: a multiple of 4; attributes only)",
            ext["filter"], ext["mode"]
        ));
    }
    Ok(Stream {
        buffer,
        offset,
        length,
        stride,
        count,
        mode,
        filter,
    })
}

/// The decoded bytes of `stream`, whose compressed bytes are `source`.
fn decode(stream: &Stream, source: &[u8]) -> Result<Vec<u8>, String> {
    let (count, stride) = (stream.count, stream.stride);
    // Words, so filters may read the bytes as the 16- and 32-bit values they hold.
    let mut words = vec![0u32; (count * stride).div_ceil(4)];
    let out = words.as_mut_ptr().cast::<std::ffi::c_void>();
    // SAFETY: `out` holds `count * stride` bytes, what each decoder writes at most; the
    // decoders read only `source.len()` bytes of `source`, and are documented safe for
    // untrusted input (they fail or produce garbage values, never access out of bounds).
    let code = unsafe {
        match stream.mode {
            Mode::Attributes => meshopt::ffi::meshopt_decodeVertexBuffer(
                out,
                count,
                stride,
                source.as_ptr(),
                source.len(),
            ),
            Mode::Triangles => meshopt::ffi::meshopt_decodeIndexBuffer(
                out,
                count,
                stride,
                source.as_ptr(),
                source.len(),
            ),
            Mode::Indices => meshopt::ffi::meshopt_decodeIndexSequence(
                out,
                count,
                stride,
                source.as_ptr(),
                source.len(),
            ),
        }
    };
    if code != 0 {
        return Err(format!(
            "its data does not decode (meshoptimizer error {code}); the file is damaged or \
             was written by a newer encoder"
        ));
    }
    // SAFETY: the filters rewrite `count` elements of `stride` bytes in place, inside the
    // buffer decoded above; the strides were checked to be the ones each filter takes.
    unsafe {
        match stream.filter {
            Filter::None => {}
            Filter::Octahedral => meshopt::ffi::meshopt_decodeFilterOct(out, count, stride),
            Filter::Quaternion => meshopt::ffi::meshopt_decodeFilterQuat(out, count, stride),
            Filter::Exponential => meshopt::ffi::meshopt_decodeFilterExp(out, count, stride),
        }
    }
    let mut bytes: Vec<u8> = words.iter().flat_map(|w| w.to_ne_bytes()).collect();
    bytes.truncate(count * stride);
    Ok(bytes)
}
