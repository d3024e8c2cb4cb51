//! Mesh files to [`Mesh`]: one module per format, chosen by the file extension.

mod gltf;
mod obj;
mod stl;

use std::path::Path;

use crate::error::SceneError;
use crate::mesh::{MAX_TRIANGLES, Mesh};

pub use self::gltf::{
    AlphaMode, CameraProjection, DEFAULT_MATERIAL, GltfScene, IDENTITY_UV_TRANSFORM, SceneCamera,
    SceneInstance, SceneMaterial, SceneMesh, SceneTexture, TextureRef, UvTransform, Wrap,
    load_gltf, load_gltf_scene, load_gltf_scene_with, load_gltf_with, percent_decode,
    referenced_path, texture_transform,
};
pub use self::obj::{
    ObjMaterial, ObjScene, load_obj, load_obj_scene, names_material_library, parse_obj,
};
pub use self::stl::{load_stl, parse_stl};

pub use crate::input::MAX_INPUT_BYTES;

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
    /// Whether an image a glTF material samples that cannot be used (missing, not PNG
    /// or JPEG, corrupt, too large) is an error. By default it is a warning and the
    /// materials sampling it use their factors, so that a scene missing one texture
    /// still opens.
    pub strict_textures: bool,
}

impl Default for LoadOptions {
    fn default() -> Self {
        Self {
            max_triangles: DEFAULT_TRIANGLE_BUDGET,
            strict_textures: false,
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

/// A mesh input's bytes: a regular file of at most [`MAX_INPUT_BYTES`].
pub(crate) fn read_file(path: &Path) -> Result<Vec<u8>, SceneError> {
    crate::input::read_file(path, MAX_INPUT_BYTES)
}
