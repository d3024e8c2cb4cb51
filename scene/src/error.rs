//! The crate's one error type.
//!
//! Every variant names the file (or the in-memory source) and says what is wrong and,
//! where there is something to change, what to change: the messages reach users of
//! `meshlight bake` and `meshlight inspect` verbatim.

use std::path::PathBuf;

/// Everything that can go wrong between a mesh file and a loaded meshlet asset.
#[derive(Debug, thiserror::Error)]
pub enum SceneError {
    #[error("{path}: cannot read the file ({source}); check that the path exists and is readable")]
    Io {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },

    #[error(
        "{path}: cannot write the file ({source}); check that the folder exists and is writable"
    )]
    Write {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },

    #[error(
        "{path}: is {kind}, not a regular file; give the path of a mesh file (devices, pipes \
         and folders are not read)"
    )]
    NotARegularFile { path: PathBuf, kind: &'static str },

    #[error(
        "{path}: the file is {size} bytes, more than the {limit} bytes a mesh input may have; \
         split the mesh into several files"
    )]
    FileTooLarge {
        path: PathBuf,
        size: u64,
        limit: u64,
    },

    #[error(
        "{path}: the glTF node tree expands to {count} triangles, more than the budget of \
         {budget}; if the scene really instances that much, raise the budget (`--max-triangles`, \
         `LoadOptions::max_triangles`, at most {limit}), else fix the node tree's shared subtrees"
    )]
    TriangleBudget {
        path: PathBuf,
        count: u64,
        budget: u64,
        limit: u64,
    },

    #[error(
        "{path}: unsupported file type {extension:?}; give a mesh ending in .obj, .gltf, .glb or .stl"
    )]
    UnsupportedFormat { path: PathBuf, extension: String },

    #[error("{path}: invalid OBJ: {reason}")]
    Obj { path: PathBuf, reason: String },

    #[error("{path}: invalid glTF: {reason}")]
    Gltf { path: PathBuf, reason: String },

    #[error(
        "{path}: glTF mesh {mesh:?}, primitive {primitive} has no POSITION attribute; \
         re-export it with vertex positions or remove the primitive"
    )]
    GltfMissingPosition {
        path: PathBuf,
        mesh: String,
        primitive: usize,
    },

    #[error("{path}: invalid STL{}: {reason}", line.map(|l| format!(" at line {l}")).unwrap_or_default())]
    Stl {
        path: PathBuf,
        line: Option<usize>,
        reason: String,
    },

    #[error(
        "{source_name}: the mesh has no triangles{detail}; give a mesh with at least one non-degenerate triangle"
    )]
    EmptyMesh { source_name: String, detail: String },

    #[error(
        "{source_name}: vertex {vertex} has a non-finite position {position:?}; \
         fix or remove that vertex in the source mesh"
    )]
    NonFinitePosition {
        source_name: String,
        vertex: usize,
        position: [f32; 3],
    },

    #[error(
        "{source_name}: {location}: {attribute} has the value {value}, which is not a finite \
         number; fix or remove it in the source file (or re-export the mesh)"
    )]
    NonFiniteAttribute {
        /// The file (or in-memory source).
        source_name: String,
        /// Where in it: `line 12`, `accessor 3, element 7`, `triangle 5`, `vertex 9`.
        location: String,
        /// What holds the value: `position`, `normal`, `texture coordinate`, with the
        /// format's name for it where it has one (`vt`, `TEXCOORD_0`).
        attribute: String,
        value: f32,
    },

    #[error(
        "{source_name}: vertex {vertex} at {position:?} lies beyond ±{limit:e}, the largest \
         coordinate the position grid and bounding spheres represent; scale the mesh down or \
         move it nearer the origin"
    )]
    CoordinateRange {
        source_name: String,
        vertex: usize,
        position: [f32; 3],
        limit: f32,
    },

    #[error(
        "{source_name}: triangle {triangle} refers to vertex {index}, but the mesh has only \
         {vertex_count} vertices; the index buffer is corrupt"
    )]
    IndexOutOfRange {
        source_name: String,
        triangle: usize,
        index: u32,
        vertex_count: usize,
    },

    #[error(
        "{source_name}: {count} {what} exceed the asset format's limit of {limit}; \
         split the mesh into several assets"
    )]
    TooLarge {
        source_name: String,
        what: &'static str,
        count: u64,
        limit: u64,
    },

    #[error(
        "{source_name}: the attribute arrays do not match the {vertex_count} positions ({detail})"
    )]
    AttributeMismatch {
        source_name: String,
        vertex_count: usize,
        detail: String,
    },

    #[error("invalid build option: {0}")]
    InvalidOption(String),

    #[error("{source_name}: the LOD build failed: {reason}")]
    Build { source_name: String, reason: String },

    #[error(
        "{path}: not a meshlet asset (wrong magic bytes); bake one with `{}`",
        bake_command(path)
    )]
    AssetMagic { path: PathBuf },

    #[error(
        "{path}: asset format version {found}, this build reads version {expected}; \
         re-bake it from its source mesh with `meshlight bake MESH -o {path}`"
    )]
    AssetVersion {
        path: PathBuf,
        found: u32,
        expected: u32,
    },

    #[error(
        "{path}: the asset is truncated ({actual} bytes, expected {expected}); re-bake or re-copy it"
    )]
    AssetTruncated {
        path: PathBuf,
        expected: u64,
        actual: u64,
    },

    #[error(
        "{path}: the asset is corrupt (checksum {found:#018x}, header says {expected:#018x}); re-bake or re-copy it"
    )]
    AssetChecksum {
        path: PathBuf,
        expected: u64,
        found: u64,
    },

    #[error("{path}: the asset is corrupt: {field} {problem}; re-bake it from its source mesh")]
    AssetField {
        path: PathBuf,
        /// The header field, record field or section that is wrong, e.g.
        /// `header.quant_step` or `meshlet[12].grid_min`.
        field: String,
        problem: String,
    },

    #[error("{path}: the asset is corrupt: {reason}; re-bake it from its source mesh")]
    AssetCorrupt { path: PathBuf, reason: String },
}

impl SceneError {
    pub(crate) fn io(path: impl Into<PathBuf>, source: std::io::Error) -> Self {
        Self::Io {
            path: path.into(),
            source,
        }
    }
}

/// The bake that makes an asset of what was read as one: a mesh file is baked into a
/// `.mlasset` beside it, anything else from `MESH`; the suggested output is never the
/// file read, which the command would otherwise overwrite.
pub fn bake_command(path: &std::path::Path) -> String {
    let is_mesh = path
        .extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| ["obj", "gltf", "glb", "stl"].contains(&e.to_ascii_lowercase().as_str()));
    let mut output = path.with_extension("mlasset");
    if output == path {
        output = path.with_extension("baked.mlasset");
    }
    let input = if is_mesh {
        path.display().to_string()
    } else {
        "MESH".to_string()
    };
    format!("meshlight bake {input} -o {}", output.display())
}

#[cfg(test)]
mod bake_command_tests {
    use super::bake_command;
    use std::path::Path;

    #[test]
    fn the_suggested_output_is_never_the_file_read() {
        for (read, command) in [
            (
                "assets/spot.obj",
                "meshlight bake assets/spot.obj -o assets/spot.mlasset",
            ),
            ("scene.GLB", "meshlight bake scene.GLB -o scene.mlasset"),
            (
                "broken.mlasset",
                "meshlight bake MESH -o broken.baked.mlasset",
            ),
            ("noext", "meshlight bake MESH -o noext.mlasset"),
        ] {
            assert_eq!(bake_command(Path::new(read)), command);
        }
    }
}
