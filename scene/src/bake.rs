//! What `meshlight bake` runs for one mesh: loaded (or generated), built, checked as
//! `inspect` would check it, and written, with what happened returned as a
//! [`BakeReport`] and progress reported through a callback. The command line parses its
//! arguments into [`BakeOptions`], draws the progress and prints the report; a host
//! application can bake the same way and show both its own way.

use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use crate::asset::MeshletAsset;
use crate::asset::summary::AssetSummary;
use crate::compress::PositionBits;
use crate::dag::{Fallbacks, LevelProgress};
use crate::error::SceneError;
use crate::grouping::Grouping;
use crate::load::{DEFAULT_TRIANGLE_BUDGET, LoadOptions, load_mesh_with};
use crate::mesh::{CleanReport, Mesh};
use crate::pipeline::{BuildOptions, Built, build_asset};
use crate::procedural::{DEFAULT_SEGMENTS, procedural_mesh};
use crate::verify::{quality, verify};

/// Input name that selects the built-in procedural mesh instead of a file.
pub const PROCEDURAL_INPUT: &str = "procedural";

/// What to bake and how: the options of `meshlight bake`.
#[derive(Debug, Clone)]
pub struct BakeOptions {
    /// Mesh to bake: .obj, .gltf, .glb or .stl; [`PROCEDURAL_INPUT`] for the built-in
    /// torus knot.
    pub input: PathBuf,
    /// Asset file to write (conventionally *.mlasset).
    pub output: PathBuf,
    /// How meshlets are grouped for simplification.
    pub grouping: Grouping,
    /// Bits per axis of the mesh-wide position grid.
    pub position_bits: PositionBits,
    /// Tube segments of the procedural mesh (16 × segments² triangles).
    pub segments: u32,
    /// Most triangles a glTF scene's node tree may expand to, checked before anything is
    /// expanded.
    pub max_triangles: u64,
}

impl BakeOptions {
    /// `input` baked into `output` with the command line's defaults.
    pub fn new(input: impl Into<PathBuf>, output: impl Into<PathBuf>) -> Self {
        Self {
            input: input.into(),
            output: output.into(),
            grouping: Grouping::default(),
            position_bits: PositionBits::Auto,
            segments: DEFAULT_SEGMENTS,
            max_triangles: DEFAULT_TRIANGLE_BUDGET,
        }
    }
}

/// How far a bake has come, for a progress display: the triangle count is known once
/// the mesh is loaded, and each level of the DAG leaves fewer triangles to simplify.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum BakeProgress {
    /// The mesh is loaded; building starts. Its triangles are what the levels work down
    /// from.
    Loaded {
        /// Triangles of the mesh as loaded, before cleaning.
        triangles: u64,
    },
    /// A level of the DAG is built.
    Level(LevelProgress),
}

/// What a bake did: the figures `meshlight bake` prints.
#[derive(Debug, Clone, PartialEq)]
pub struct BakeReport {
    /// The mesh file baked (or [`PROCEDURAL_INPUT`]).
    pub input: PathBuf,
    /// The asset file written.
    pub output: PathBuf,
    /// Triangles of the cleaned mesh the DAG was built from.
    pub mesh_triangles: usize,
    /// Vertices of the cleaned mesh.
    pub mesh_vertices: usize,
    /// What cleaning dropped and welded.
    pub clean: CleanReport,
    /// Whether distinct positions met on the position grid, so that the mesh was
    /// snapped to the grid and built again.
    pub snapped_to_grid: bool,
    /// Groups repaired because simplifying them would have cracked a LOD cut.
    pub fallbacks: Fallbacks,
    /// Header and DAG statistics of the asset written.
    pub summary: AssetSummary,
    /// Loading (or generating) the mesh.
    pub load_time: Duration,
    /// Building the DAG alone.
    pub dag_time: Duration,
    /// Cleaning, building and packing (loading not included).
    pub total_time: Duration,
    /// What is poor about the DAG (see [`crate::verify::quality`]); the asset is
    /// written all the same.
    pub warnings: Vec<String>,
}

impl BakeReport {
    /// The report of `built`, baked from `input` into `output` after `load_time` spent
    /// loading.
    pub fn new(input: &Path, output: &Path, built: &Built, load_time: Duration) -> Self {
        Self {
            input: input.to_path_buf(),
            output: output.to_path_buf(),
            mesh_triangles: built.mesh.triangle_count(),
            mesh_vertices: built.mesh.positions.len(),
            clean: built.clean,
            snapped_to_grid: built.snapped_to_grid,
            fallbacks: built.fallbacks,
            summary: AssetSummary::of(&built.asset),
            load_time,
            dag_time: built.dag_time,
            total_time: built.total_time,
            warnings: quality(&built.asset).warnings,
        }
    }
}

/// Loads the input (or generates the procedural mesh), builds it, checks the asset and
/// saves it, calling `progress` as it goes. Nothing is written when the asset fails the
/// checks `inspect` runs.
pub fn bake(
    options: &BakeOptions,
    progress: &mut dyn FnMut(BakeProgress),
) -> Result<BakeReport, SceneError> {
    refuse_overwriting_the_input(&options.input, &options.output)?;
    let load_start = Instant::now();
    let load = LoadOptions {
        max_triangles: options.max_triangles,
        ..LoadOptions::default()
    };
    let mesh = load_input(&options.input, options.segments, &load)?;
    let load_time = load_start.elapsed();
    progress(BakeProgress::Loaded {
        triangles: mesh.triangle_count() as u64,
    });
    let built = build_asset(
        &mesh,
        &BuildOptions {
            grouping: options.grouping,
            position_bits: options.position_bits,
            ..BuildOptions::default()
        },
        &mut |level| progress(BakeProgress::Level(level)),
    )?;
    check_before_writing(&options.input, &built.asset)?;
    built.asset.save(&options.output)?;
    Ok(BakeReport::new(
        &options.input,
        &options.output,
        &built,
        load_time,
    ))
}

/// Refuses an output that is the input itself (the same file by another name, or
/// through a link): the asset would replace the mesh it was baked from.
fn refuse_overwriting_the_input(input: &Path, output: &Path) -> Result<(), SceneError> {
    let resolved = |p: &Path| -> Option<std::path::PathBuf> {
        p.canonicalize().ok().or_else(|| {
            // An output that does not exist yet: its folder resolved, then its name.
            let parent = match p.parent() {
                Some(d) if !d.as_os_str().is_empty() => d,
                _ => Path::new("."),
            };
            Some(parent.canonicalize().ok()?.join(p.file_name()?))
        })
    };
    if let (Some(i), Some(o)) = (resolved(input), resolved(output))
        && i == o
    {
        return Err(SceneError::InvalidOption(format!(
            "the output {} is the input mesh itself; give `-o` another path (the asset would \
             overwrite the mesh it is baked from)",
            output.display()
        )));
    }
    Ok(())
}

/// Refuses to write an asset that `inspect` would reject: the same structural checks
/// as loading, and the DAG invariants.
fn check_before_writing(input: &Path, asset: &MeshletAsset) -> Result<(), SceneError> {
    let mut problems: Vec<String> = Vec::new();
    if let Err(e) = asset.validate() {
        problems.push(format!("{} {}", e.field, e.problem));
    }
    if problems.is_empty() {
        problems = verify(asset);
    }
    match problems.first() {
        None => Ok(()),
        Some(first) => Err(SceneError::Build {
            source_name: input.display().to_string(),
            reason: format!(
                "the built asset fails its own checks ({} problems, first: {first}), so it was \
                 not written; please report this with the input mesh",
                problems.len()
            ),
        }),
    }
}

fn load_input(input: &Path, segments: u32, options: &LoadOptions) -> Result<Mesh, SceneError> {
    if input.as_os_str() == PROCEDURAL_INPUT && !input.exists() {
        return Ok(procedural_mesh(segments));
    }
    load_mesh_with(input, options)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// What `bake` runs before writing refuses an asset that `inspect` would reject.
    #[test]
    fn bake_does_not_write_what_inspect_rejects() {
        let built =
            crate::build_asset(&procedural_mesh(8), &Default::default(), &mut |_| {}).unwrap();
        assert!(check_before_writing(Path::new("m.obj"), &built.asset).is_ok());
        let broken = crate::damaged::error_below_child(&built).unwrap();
        let err = check_before_writing(Path::new("m.obj"), &broken).unwrap_err();
        assert!(matches!(err, SceneError::Build { .. }), "{err:?}");
        assert!(err.to_string().contains("not written"), "{err}");
    }
}
