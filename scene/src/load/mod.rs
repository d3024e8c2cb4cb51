//! Mesh files to [`Mesh`]: one module per format, chosen by the file extension.

mod gltf;
mod obj;
mod stl;

use std::io::Read;
use std::path::Path;

use crate::error::SceneError;
use crate::mesh::{MAX_TRIANGLES, Mesh};

pub use self::gltf::{
    AlphaMode, CameraProjection, DEFAULT_MATERIAL, GltfScene, SceneCamera, SceneInstance,
    SceneMaterial, SceneMesh, TextureRef, load_gltf, load_gltf_scene, load_gltf_scene_with,
    load_gltf_with, percent_decode,
};
pub use self::obj::{load_obj, parse_obj};
pub use self::stl::{load_stl, parse_stl};

/// Largest mesh input file (a mesh, or a buffer a glTF names) read, in bytes: 2 GiB.
/// The largest binary STL the triangle limit allows ([`MAX_TRIANGLES`] × 50 bytes) is
/// 1.7 GB, and an OBJ of that many triangles without normals or UVs about as much.
/// Checked from the file's metadata before reading, so a huge or endless file costs
/// nothing.
pub const MAX_INPUT_BYTES: u64 = 1 << 31;

/// Default for [`LoadOptions::max_triangles`]: 2^23 (8.4 million) triangles. Building
/// takes seconds per million, so a glTF scene whose instancing expands past this is
/// more likely a mistake or a hostile file (a 630 KB file can name 27 million) than a
/// mesh someone means to bake; the option raises it.
pub const DEFAULT_TRIANGLE_BUDGET: u64 = 1 << 23;

/// Limits on what loading may expand to.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct LoadOptions {
    /// Most triangles a glTF node tree may expand to (instances × their meshes'
    /// triangles), checked from the declared counts before anything is expanded or
    /// read. At most [`MAX_TRIANGLES`], the asset format's limit.
    pub max_triangles: u64,
}

impl Default for LoadOptions {
    fn default() -> Self {
        Self {
            max_triangles: DEFAULT_TRIANGLE_BUDGET,
        }
    }
}

/// [`load_mesh_with`] with the default [`LoadOptions`].
pub fn load_mesh(path: &Path) -> Result<Mesh, SceneError> {
    load_mesh_with(path, &LoadOptions::default())
}

/// Loads an OBJ, glTF 2.0 (.gltf/.glb) or STL file. Normals are generated later, by
/// [`Mesh::clean`], where the file has none.
pub fn load_mesh_with(path: &Path, options: &LoadOptions) -> Result<Mesh, SceneError> {
    if options.max_triangles > MAX_TRIANGLES {
        return Err(SceneError::InvalidOption(format!(
            "a triangle budget of {} is more than the asset format's {MAX_TRIANGLES}; give at \
             most that",
            options.max_triangles
        )));
    }
    let extension = path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase)
        .unwrap_or_default();
    match extension.as_str() {
        "obj" => load_obj(path),
        "gltf" | "glb" => load_gltf_with(path, options),
        "stl" => load_stl(path),
        _ => Err(SceneError::UnsupportedFormat {
            path: path.to_owned(),
            extension,
        }),
    }
}

/// Reads a mesh input: a regular file (not a device, pipe or folder: `/dev/zero` would
/// never end) of at most [`MAX_INPUT_BYTES`], both known from its metadata before a
/// byte is read.
pub(crate) fn read_file(path: &Path) -> Result<Vec<u8>, SceneError> {
    let meta = std::fs::metadata(path).map_err(|e| SceneError::io(path, e))?;
    if !meta.is_file() {
        return Err(SceneError::NotARegularFile {
            path: path.to_owned(),
            kind: file_kind(&meta),
        });
    }
    if meta.len() > MAX_INPUT_BYTES {
        return Err(SceneError::FileTooLarge {
            path: path.to_owned(),
            size: meta.len(),
            limit: MAX_INPUT_BYTES,
        });
    }
    let file = std::fs::File::open(path).map_err(|e| SceneError::io(path, e))?;
    // A file that grows while it is read still stops at the limit.
    let mut bytes = Vec::with_capacity(meta.len() as usize);
    file.take(MAX_INPUT_BYTES + 1)
        .read_to_end(&mut bytes)
        .map_err(|e| SceneError::io(path, e))?;
    if bytes.len() as u64 > MAX_INPUT_BYTES {
        return Err(SceneError::FileTooLarge {
            path: path.to_owned(),
            size: bytes.len() as u64,
            limit: MAX_INPUT_BYTES,
        });
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
            return "a pipe";
        }
        if t.is_socket() {
            return "a socket";
        }
    }
    if meta.is_dir() {
        "a folder"
    } else {
        "not a file"
    }
}
