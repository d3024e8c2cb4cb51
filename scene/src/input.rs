//! How the program opens a user's file, written once: only a regular file (a device,
//! pipe or folder would block, never end or mean nothing: `/dev/zero` would be read until
//! memory runs out, a FIFO would wait for a writer for ever), known from its metadata
//! before it is opened, and read with a size bound, so a huge or growing file costs
//! nothing.

use std::io::Read;
use std::path::Path;

use crate::error::SceneError;

/// Largest mesh input file (a mesh, or a buffer a glTF names) read, in bytes: 2 GiB.
/// The largest binary STL the triangle limit allows (the asset format's triangle limit ×
/// 50 bytes) is 1.7 GB, and an OBJ of that many triangles without normals or UVs about
/// as much.
pub const MAX_INPUT_BYTES: u64 = 1 << 31;

/// The metadata of `path`, refusing anything but a regular file (links are followed).
/// Reads the metadata only, so it never blocks on a pipe.
pub fn regular_file(path: &Path) -> Result<std::fs::Metadata, SceneError> {
    let meta = std::fs::metadata(path).map_err(|e| SceneError::io(path, e))?;
    if !meta.is_file() {
        return Err(SceneError::NotARegularFile {
            path: path.to_owned(),
            kind: file_kind(&meta),
        });
    }
    Ok(meta)
}

/// The bytes of `path`: a regular file of at most `limit` bytes, both known from its
/// metadata before a byte is read (and the read stops past the limit, should the file
/// grow meanwhile).
pub fn read_file(path: &Path, limit: u64) -> Result<Vec<u8>, SceneError> {
    let meta = regular_file(path)?;
    let too_large = |size| SceneError::FileTooLarge {
        path: path.to_owned(),
        size,
        limit,
    };
    if meta.len() > limit {
        return Err(too_large(meta.len()));
    }
    let file = std::fs::File::open(path).map_err(|e| SceneError::io(path, e))?;
    let mut bytes = Vec::with_capacity(meta.len() as usize);
    file.take(limit + 1)
        .read_to_end(&mut bytes)
        .map_err(|e| SceneError::io(path, e))?;
    if bytes.len() as u64 > limit {
        return Err(too_large(bytes.len() as u64));
    }
    Ok(bytes)
}

fn file_kind(meta: &std::fs::Metadata) -> &'static str {
    #[cfg(unix)]
    {
        use std::os::unix::fs::FileTypeExt;
        let t = meta.file_type();
        if t.is_char_device() {
            return "a character device";
        }
        if t.is_block_device() {
            return "a block device";
        }
        if t.is_fifo() {
            return "a FIFO";
        }
        if t.is_socket() {
            return "a socket";
        }
    }
    // The words the pipeline-file reader uses (graph::file), so every refusal reads
    // alike.
    if meta.is_dir() {
        "a directory"
    } else {
        "not a regular file"
    }
}
