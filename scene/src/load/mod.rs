//! Mesh files to [`Mesh`]: one module per format, chosen by the file extension.

mod gltf;
mod obj;
mod stl;

use std::path::Path;

use crate::error::SceneError;
use crate::mesh::Mesh;

pub use self::gltf::load_gltf;
pub use self::obj::{load_obj, parse_obj};
pub use self::stl::{load_stl, parse_stl};

/// Loads an OBJ, glTF 2.0 (.gltf/.glb) or STL file. Normals are generated later, by
/// [`Mesh::clean`], where the file has none.
pub fn load_mesh(path: &Path) -> Result<Mesh, SceneError> {
    let extension = path
        .extension()
        .and_then(|e| e.to_str())
        .map(str::to_ascii_lowercase)
        .unwrap_or_default();
    match extension.as_str() {
        "obj" => load_obj(path),
        "gltf" | "glb" => load_gltf(path),
        "stl" => load_stl(path),
        _ => Err(SceneError::UnsupportedFormat {
            path: path.to_owned(),
            extension,
        }),
    }
}

pub(crate) fn read_file(path: &Path) -> Result<Vec<u8>, SceneError> {
    std::fs::read(path).map_err(|e| SceneError::io(path, e))
}
