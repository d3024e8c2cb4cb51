//! The crate's one error type.
//!
//! Every variant names the file (or the in-memory source) and says what is wrong and,
//! where there is something to change, what to change: the messages reach users of
//! `meshlight bake` and `meshlight inspect` verbatim.

use std::path::PathBuf;

/// Everything that can go wrong between a mesh file and a loaded meshlet asset.
#[derive(Debug, thiserror::Error)]
pub enum SceneError {
    /// A file could not be read: missing, unreadable, or failing mid-read.
    #[error("{path}: cannot read the file ({source}); check that the path exists and is readable")]
    Io {
        /// The file.
        path: PathBuf,
        /// What the system said.
        #[source]
        source: std::io::Error,
    },

    /// An asset could not be written.
    #[error(
        "{path}: cannot write the file ({source}); check that the folder exists and is writable"
    )]
    Write {
        /// The file.
        path: PathBuf,
        /// What the system said.
        #[source]
        source: std::io::Error,
    },

    /// The input is a device, pipe or folder, which would block or mean nothing.
    #[error(
        "{path}: is {kind}, not a regular file; give the path of a file (devices, pipes and \
         folders are not read)"
    )]
    NotARegularFile {
        /// The path given.
        path: PathBuf,
        /// What it is instead, e.g. `a character device`.
        kind: &'static str,
    },

    /// A file larger than any input of its kind (a mesh larger than the asset format can
    /// hold), refused before it is read into memory.
    #[error(
        "{path}: the file is {size} bytes, more than the {limit} bytes such an input may \
         have; split it into several files"
    )]
    FileTooLarge {
        /// The file.
        path: PathBuf,
        /// Its size in bytes.
        size: u64,
        /// The largest size read.
        limit: u64,
    },

    /// A glTF node tree that instances more triangles than the loading budget, refused
    /// from the declared counts before anything is expanded.
    #[error(
        "{path}: the glTF node tree expands to {count} triangles, more than the budget of \
         {budget}; if the scene really instances that much, raise the budget (`--max-triangles`, \
         `LoadOptions::max_triangles`, at most {limit}), else fix the node tree's shared subtrees"
    )]
    TriangleBudget {
        /// The file.
        path: PathBuf,
        /// Triangles the node tree expands to.
        count: u64,
        /// The budget it exceeds.
        budget: u64,
        /// The largest budget that may be given: the asset format's triangle limit.
        limit: u64,
    },

    /// A file whose extension names no format the loaders read.
    #[error(
        "{path}: unsupported file type {extension:?}; give a mesh ending in .obj, .gltf, .glb or .stl"
    )]
    UnsupportedFormat {
        /// The file.
        path: PathBuf,
        /// Its extension (empty when it has none).
        extension: String,
    },

    /// An OBJ file the parser refuses.
    #[error("{path}: invalid OBJ: {reason}")]
    Obj {
        /// The file.
        path: PathBuf,
        /// What is wrong, with the line where known.
        reason: String,
    },

    /// A glTF file that is malformed or refers to what it does not hold.
    #[error("{path}: invalid glTF: {reason}")]
    Gltf {
        /// The file.
        path: PathBuf,
        /// What is wrong, naming the accessor, buffer or node.
        reason: String,
    },

    /// An image a glTF material samples could not be used, with
    /// [`crate::load::LoadOptions::strict_textures`] (otherwise a warning).
    #[cfg(feature = "build")]
    #[error("{path}: {reason}")]
    GltfTexture {
        /// The file.
        path: PathBuf,
        /// The glTF image.
        image: usize,
        /// Why, naming the image and what to change.
        #[source]
        reason: crate::texture::TextureError,
    },

    /// A glTF primitive without positions, which cannot be drawn.
    #[error(
        "{path}: glTF mesh {mesh:?}, primitive {primitive} has no POSITION attribute; \
         re-export it with vertex positions or remove the primitive"
    )]
    GltfMissingPosition {
        /// The file.
        path: PathBuf,
        /// The mesh's name (or its index, for an unnamed one).
        mesh: String,
        /// The primitive's index in the mesh.
        primitive: usize,
    },

    /// An STL file the parser refuses.
    #[error("{path}: invalid STL{}: {reason}", line.map(|l| format!(" at line {l}")).unwrap_or_default())]
    Stl {
        /// The file.
        path: PathBuf,
        /// The line of an ASCII file where the problem is; `None` when it is not on one
        /// line (a binary file, or the file as a whole).
        line: Option<usize>,
        /// What is wrong.
        reason: String,
    },

    /// A mesh with nothing to build: no triangles, or only degenerate ones.
    #[error(
        "{source_name}: the mesh has no triangles{detail}; give a mesh with at least one non-degenerate triangle"
    )]
    EmptyMesh {
        /// The file or in-memory source.
        source_name: String,
        /// Why, when there were triangles: e.g. that all were degenerate.
        detail: String,
    },

    /// A position that is NaN or infinite, which no bounds or grid can hold.
    #[error(
        "{source_name}: vertex {vertex} has a non-finite position {position:?}; \
         fix or remove that vertex in the source mesh"
    )]
    NonFinitePosition {
        /// The file or in-memory source.
        source_name: String,
        /// The vertex's index.
        vertex: usize,
        /// The position as read.
        position: [f32; 3],
    },

    /// A normal or texture coordinate that is NaN or infinite.
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
        /// The value read.
        value: f32,
    },

    /// A coordinate too large for the position grid and the bounding spheres to
    /// represent without overflow.
    #[error(
        "{source_name}: vertex {vertex} at {position:?} lies beyond ±{limit:e}, the largest \
         coordinate the position grid and bounding spheres represent; scale the mesh down or \
         move it nearer the origin"
    )]
    CoordinateRange {
        /// The file or in-memory source.
        source_name: String,
        /// The vertex's index.
        vertex: usize,
        /// The position as read.
        position: [f32; 3],
        /// The largest coordinate allowed.
        limit: f32,
    },

    /// A mesh so small that no position grid resolves it: its step would fall below the
    /// smallest normal `f32`.
    #[error(
        "{source_name}: the mesh spans {extent:e} units, below {limit:e}, the smallest extent \
         the position grid resolves; scale the mesh up (export it in smaller units)"
    )]
    ExtentTooSmall {
        /// The file or in-memory source.
        source_name: String,
        /// The largest side of its bounds.
        extent: f32,
        /// The smallest extent allowed.
        limit: f32,
    },

    /// A triangle naming a vertex the mesh does not have.
    #[error(
        "{source_name}: triangle {triangle} refers to vertex {index}, but the mesh has only \
         {vertex_count} vertices; the index buffer is corrupt"
    )]
    IndexOutOfRange {
        /// The file or in-memory source.
        source_name: String,
        /// The triangle's index.
        triangle: usize,
        /// The vertex index it names.
        index: u32,
        /// Vertices the mesh has.
        vertex_count: usize,
    },

    /// A mesh with more triangles or vertices than the asset format counts.
    #[error(
        "{source_name}: {count} {what} exceed the asset format's limit of {limit}; \
         split the mesh into several assets"
    )]
    TooLarge {
        /// The file or in-memory source.
        source_name: String,
        /// `triangles` or `vertices`.
        what: &'static str,
        /// How many the mesh has.
        count: u64,
        /// How many the format allows.
        limit: u64,
    },

    /// A triangle whose material slot is past what a meshlet record can hold.
    #[error(
        "{source_name}: triangle {triangle} has material slot {slot}, but a mesh may use \
         at most {limit} (slots 0 to {}); split the mesh so that each part has fewer \
         materials",
        limit - 1
    )]
    TooManyMaterials {
        /// The file or in-memory source.
        source_name: String,
        /// The first triangle with too high a slot.
        triangle: usize,
        /// Its slot.
        slot: u32,
        /// [`crate::mesh::MAX_MATERIALS`].
        limit: u32,
    },

    /// Normals or texture coordinates whose count differs from the positions'.
    #[error(
        "{source_name}: the attribute arrays do not match the {vertex_count} positions ({detail})"
    )]
    AttributeMismatch {
        /// The file or in-memory source.
        source_name: String,
        /// Positions the mesh has.
        vertex_count: usize,
        /// Which array has how many.
        detail: String,
    },

    /// A build option outside its range; the message gives the range.
    #[error("invalid build option: {0}")]
    InvalidOption(String),

    /// The builder could not make an asset of a valid mesh, or made one that fails its
    /// own checks: a bug to report with the mesh.
    #[error("{source_name}: the LOD build failed: {reason}")]
    Build {
        /// The file or in-memory source.
        source_name: String,
        /// What failed.
        reason: String,
    },

    /// A file that is not an asset (often a mesh given to `inspect`); the message says
    /// how to bake one.
    #[error(
        "{path}: not a meshlet asset (wrong magic bytes); bake one with `{}`",
        bake_command(path)
    )]
    AssetMagic {
        /// The file.
        path: PathBuf,
    },

    /// An asset written by another format version, refused rather than misread.
    #[error(
        "{path}: asset format version {found}, this build reads version {expected}; \
         re-bake it from its source mesh with `meshlight bake MESH -o {path}`"
    )]
    AssetVersion {
        /// The file.
        path: PathBuf,
        /// The version it says.
        found: u32,
        /// The version this build reads.
        expected: u32,
    },

    /// An asset shorter than its header says, as after an interrupted copy.
    #[error(
        "{path}: the asset is truncated ({actual} bytes, expected {expected}); re-bake or re-copy it"
    )]
    AssetTruncated {
        /// The file.
        path: PathBuf,
        /// The size its header says.
        expected: u64,
        /// Its size.
        actual: u64,
    },

    /// An asset whose bytes changed after it was written.
    #[error(
        "{path}: the asset is corrupt (checksum {found:#018x}, header says {expected:#018x}); re-bake or re-copy it"
    )]
    AssetChecksum {
        /// The file.
        path: PathBuf,
        /// The checksum its header says.
        expected: u64,
        /// The checksum of its bytes.
        found: u64,
    },

    /// One page of an asset whose bytes do not match the page's checksum: damaged on
    /// disk, or changed since the resident part was read.
    #[error(
        "{path}: page {page} of the asset is corrupt (checksum {found:#018x}, its record says \
         {expected:#018x}); re-bake or re-copy it"
    )]
    AssetPageChecksum {
        /// The file.
        path: PathBuf,
        /// The page (its group's index).
        page: u32,
        /// The checksum its record says.
        expected: u64,
        /// The checksum of its bytes.
        found: u64,
    },

    /// An asset whose checksum holds but whose structure does not: a field out of range
    /// or inconsistent with another, which would make the GPU read out of bounds.
    #[error("{path}: the asset is corrupt: {field} {problem}; re-bake it from its source mesh")]
    AssetField {
        /// The file.
        path: PathBuf,
        /// The header field, record field or section that is wrong, e.g.
        /// `header.quant_step` or `meshlet[12].grid_min`.
        field: String,
        /// What is wrong with it.
        problem: String,
    },

    /// An asset whose structure holds but whose DAG breaks its invariants, so that it
    /// would draw cracks or the wrong detail.
    #[error("{path}: the asset is corrupt: {reason}; re-bake it from its source mesh")]
    AssetCorrupt {
        /// The file.
        path: PathBuf,
        /// The first violation and how many there are.
        reason: String,
    },
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
