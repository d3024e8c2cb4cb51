//! What `meshlight bake` and `meshlight inspect` run: a mesh baked into an asset with a
//! progress bar and a summary, an asset inspected and its invariants verified. The
//! command line parses its arguments into [`BakeOptions`]; tests call these directly.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::time::Instant;

use crate::asset::MeshletAsset;
use crate::compress::PositionBits;
use crate::error::SceneError;
use crate::grouping::Grouping;
use crate::load::{DEFAULT_TRIANGLE_BUDGET, LoadOptions, load_mesh_with};
use crate::mesh::Mesh;
use crate::pipeline::{BuildOptions, Built, build_asset};
use crate::procedural::{DEFAULT_SEGMENTS, procedural_mesh};
use crate::verify::{expected_levels, level_stats, quality, verify};

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

/// A progress bar of `len` steps in the style of every bake: a spinner, `what` (an
/// indicatif template naming the work and where the bar goes), then the time taken.
pub fn progress_bar(len: u64, what: &str) -> indicatif::ProgressBar {
    let template = format!("{{spinner}} {what} ({{elapsed}})");
    let style = indicatif::ProgressStyle::with_template(&template)
        .unwrap_or_else(|e| panic!("progress template `{template}`: {e}"));
    indicatif::ProgressBar::new(len).with_style(style.progress_chars("=> "))
}

/// Loads the input (or generates the procedural mesh), builds, saves and prints the
/// bake summary.
pub fn run_bake(args: &BakeOptions) -> Result<(), SceneError> {
    let load_start = Instant::now();
    let load = LoadOptions {
        max_triangles: args.max_triangles,
    };
    let mesh = load_input(&args.input, args.segments, &load)?;
    let load_time = load_start.elapsed();

    let bar = progress_bar(
        mesh.triangle_count() as u64,
        "building LOD DAG [{bar:30}] {msg}",
    );
    // Short builds finish before a bar would help; indicatif hides it off a terminal.
    if mesh.triangle_count() < 200_000 {
        bar.set_draw_target(indicatif::ProgressDrawTarget::hidden());
    }
    let input_triangles = mesh.triangle_count() as u64;
    let built = build_asset(
        &mesh,
        &BuildOptions {
            grouping: args.grouping,
            position_bits: args.position_bits,
            ..BuildOptions::default()
        },
        &mut |p| {
            // Triangles left shrink by about half per level; show progress toward zero.
            bar.set_position(input_triangles.saturating_sub(p.active_triangles as u64));
            bar.set_message(format!(
                "level {}: {} clusters, {} triangles left",
                p.level, p.active_clusters, p.active_triangles
            ));
        },
    )?;
    bar.finish_and_clear();
    check_before_writing(&args.input, &built.asset)?;
    built.asset.save(&args.output)?;
    print!(
        "{}",
        bake_summary(&args.input, &args.output, &built, load_time.as_secs_f64())
    );
    for w in quality(&built.asset).warnings {
        println!("  warning: {w}");
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

/// The text `meshlight bake` prints.
pub fn bake_summary(input: &Path, output: &Path, built: &Built, load_seconds: f64) -> String {
    let h = built.asset.header();
    let mut s = String::new();
    let _ = writeln!(s, "baked {} -> {}", input.display(), output.display());
    let c = &built.clean;
    let _ = writeln!(
        s,
        "  input: {} triangles, {} vertices; {} degenerate and {} duplicate triangles dropped, \
         {} vertices welded to a neighbour{}",
        built.mesh.triangle_count(),
        built.mesh.positions.len(),
        c.dropped_degenerate,
        c.dropped_duplicate,
        c.welded_vertices,
        if built.snapped_to_grid {
            "; snapped to the position grid"
        } else {
            ""
        }
    );
    let _ = writeln!(
        s,
        "  crack repairs: {} groups kept unsimplified (fallback), {} simplified again with \
         their border triangles locked",
        built.fallbacks.unsimplified, built.fallbacks.relocked
    );
    s += &dag_table(&built.asset);
    let seconds = built.total_time.as_secs_f64();
    let _ = writeln!(
        s,
        "  build time: {:.3} s ({:.3} s DAG, {:.3} s loading before), {:.0} input triangles/s",
        seconds,
        built.dag_time.as_secs_f64(),
        load_seconds,
        h.lod0_triangles as f64 / seconds
    );
    s
}

/// Loads an asset (which validates magic, version, size, checksum and structure),
/// prints its header and statistics, and verifies the DAG invariants. Structural
/// violations fail; quality findings are printed as warnings and do not.
pub fn run_inspect(file: &Path) -> Result<(), SceneError> {
    let asset = MeshletAsset::load(file)?;
    print!("{}", inspect_summary(file, &asset));
    let problems = verify(&asset);
    if problems.is_empty() {
        println!("  invariants: all hold");
        let q = quality(&asset);
        for w in &q.warnings {
            println!("  warning: {w}");
        }
        if q.warnings.is_empty() {
            println!(
                "  quality: levels halve, {} root(s)",
                asset.header().root_count
            );
        }
        Ok(())
    } else {
        for p in &problems {
            println!("  violated: {p}");
        }
        crate::asset::dag_error(file, &problems)
    }
}

/// The header and DAG statistics `meshlight inspect` prints.
pub fn inspect_summary(path: &Path, asset: &MeshletAsset) -> String {
    let h = asset.header();
    let mut s = String::new();
    let _ = writeln!(s, "{}: meshlet asset version {}", path.display(), h.version);
    let _ = writeln!(
        s,
        "  {} bytes, checksum {:#018x}, {} meshlets, {} groups, UVs: {}",
        asset.bytes().len(),
        h.checksum[0] as u64 | ((h.checksum[1] as u64) << 32),
        h.meshlet_count,
        h.group_count,
        if h.has_uvs() { "yes" } else { "no" }
    );
    let _ = writeln!(
        s,
        "  bounds {:?} .. {:?}; position grid {} bits, step {:.3e} (max error {:.3e})",
        h.bounds_min,
        h.bounds_max,
        h.quant_bits,
        h.quant_step,
        asset.quantization().max_error()
    );
    let _ = writeln!(
        s,
        "  source: {} vertices; {} degenerate triangles were dropped",
        h.input_vertices, h.dropped_degenerate
    );
    s += &dag_table(asset);
    s
}

fn dag_table(asset: &MeshletAsset) -> String {
    let h = asset.header();
    let stats = level_stats(asset);
    let mut s = String::new();
    let _ = writeln!(s, "  level  meshlets  triangles  fill   max error");
    for (level, st) in stats.iter().enumerate() {
        let max_error = asset
            .meshlets()
            .iter()
            .filter(|m| m.level() as usize == level)
            .map(|m| asset.lod(m).1)
            .fold(0.0f32, f32::max);
        let _ = writeln!(
            s,
            "  {level:>5}  {:>8}  {:>9}  {:>5.1}  {:.3e}",
            st.meshlets,
            st.triangles,
            st.triangles as f64 / st.meshlets.max(1) as f64,
            max_error
        );
    }
    let roots: Vec<_> = asset
        .meshlets()
        .iter()
        .filter(|m| m.parent_group == crate::asset::format::NO_GROUP)
        .collect();
    let _ = writeln!(
        s,
        "  levels: {} (log2 of LOD-0 meshlets + 1 = {:.1}); root: {} meshlets, {} triangles",
        h.level_count,
        expected_levels(h.lod0_meshlets),
        roots.len(),
        roots.iter().map(|m| m.triangle_count()).sum::<u32>()
    );
    let _ = writeln!(
        s,
        "  meshlet fill: {:.1} triangles per meshlet overall, {:.1} at LOD 0",
        h.total_triangles as f64 / h.meshlet_count.max(1) as f64,
        h.lod0_triangles as f64 / h.lod0_meshlets.max(1) as f64
    );
    let _ = writeln!(
        s,
        "  size: {} bytes, {:.2} bytes per LOD-0 triangle ({} triangles in all levels)",
        asset.bytes().len(),
        asset.bytes().len() as f64 / h.lod0_triangles.max(1) as f64,
        h.total_triangles
    );
    let nodes = asset.nodes();
    let _ = writeln!(
        s,
        "  culling hierarchy: {} nodes, {} leaves (one per group, one of roots), depth {}",
        nodes.len(),
        crate::hierarchy::leaf_count(nodes),
        crate::hierarchy::depth(nodes)
    );
    let b = asset.size_breakdown();
    let per = |bytes: usize| bytes as f64 / h.lod0_triangles.max(1) as f64;
    let _ = writeln!(
        s,
        "  bytes per LOD-0 triangle: records {:.2}, groups {:.2}, hierarchy {:.2}, positions {:.2}, normals {:.2}, UVs {:.2}, indices {:.2}; {:.2} vertex copies per triangle",
        per(b.meshlet_records),
        per(b.groups),
        per(b.hierarchy),
        per(b.positions),
        per(b.normals),
        per(b.uvs),
        per(b.indices),
        h.total_vertices as f64 / h.total_triangles.max(1) as f64
    );
    s
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
