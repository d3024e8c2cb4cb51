//! `meshlight bake DIR -o OUTDIR`: every mesh file under a directory baked at once, the
//! tree mirrored under the output directory (`DIR/props/crate.glb` →
//! `OUTDIR/props/crate.mlasset`), outputs already up to date skipped ([`stamp`]), and a
//! table of what happened to each file.
//!
//! An output is a pure function of its input's bytes and the build options, the same
//! bytes a single-file bake writes. The builder is deterministic, so they do not depend
//! on the number of threads or on the order the files finish in.

pub mod stamp;

/// The fresh directory the unit tests write in, the one the binary's tests use.
#[cfg(test)]
#[path = "../../tests/common/scratch.rs"]
mod scratch;

use meshlight::scene::load::load_mesh;
use meshlight::scene::{BuildOptions, Built, MeshletAsset, build_asset};
use meshlight_output::{OutputError, create_parent};
use rayon::prelude::*;
use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// File extensions baked (compared without regard to case).
pub const MESH_EXTENSIONS: [&str; 4] = ["obj", "gltf", "glb", "stl"];
/// Extension of an output asset; its stamp adds [`stamp::STAMP_SUFFIX`].
pub const ASSET_EXTENSION: &str = "mlasset";

/// Why a directory bake as a whole did not succeed.
#[derive(Debug, thiserror::Error)]
pub enum LibraryError {
    #[error("cannot read the directory {}: {reason}", path.display())]
    Walk { path: PathBuf, reason: String },
    #[error("{} holds no mesh files ({})", dir.display(), MESH_EXTENSIONS.map(|e| format!(".{e}")).join(", "))]
    NoMeshes { dir: PathBuf },
    #[error("{failed} of {total} meshes were not baked; the table says why for each")]
    NotBaked { failed: usize, total: usize },
    #[error(transparent)]
    Output(#[from] OutputError),
}

/// What became of one mesh file.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Status {
    Baked,
    UpToDate,
    /// The input cannot be baked: unreadable, malformed, or its asset fails its checks.
    Refused(String),
    /// Baked, but the output could not be written.
    Failed(String),
}

impl Status {
    fn text(&self) -> String {
        match self {
            Status::Baked => "baked".into(),
            Status::UpToDate => "up to date".into(),
            Status::Refused(why) => format!("refused: {why}"),
            Status::Failed(why) => format!("failed: {why}"),
        }
    }
}

/// The numbers of an output asset, from its header.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct AssetStats {
    pub lod0_triangles: u32,
    pub clusters: u32,
    pub levels: u32,
    /// Groups left unsimplified because simplifying them would crack a LOD cut; `None`
    /// where the count is not known (see [`fallback_groups`]).
    pub fallback_groups: Option<u32>,
}

/// One row of the summary.
#[derive(Debug, Clone)]
pub struct Row {
    /// Relative to the input directory.
    pub input: PathBuf,
    pub output: PathBuf,
    pub stats: Option<AssetStats>,
    pub seconds: f64,
    pub status: Status,
}

/// Every mesh file under `dir`, relative to it, in sorted order. Directories reached
/// through symbolic links are not entered (a link to a parent would never end); linked
/// files are baked like others.
pub fn find_meshes(dir: &Path) -> Result<Vec<PathBuf>, LibraryError> {
    let mut found = Vec::new();
    let mut pending = vec![PathBuf::new()];
    while let Some(relative) = pending.pop() {
        let here = dir.join(&relative);
        let walk = |e: std::io::Error| LibraryError::Walk {
            path: here.clone(),
            reason: e.to_string(),
        };
        for entry in std::fs::read_dir(&here).map_err(walk)? {
            let entry = entry.map_err(walk)?;
            let path = relative.join(entry.file_name());
            let kind = entry.file_type().map_err(walk)?;
            if kind.is_dir() {
                pending.push(path);
            } else if is_mesh(&path) && (kind.is_file() || dir.join(&path).is_file()) {
                found.push(path);
            }
        }
    }
    found.sort();
    Ok(found)
}

fn is_mesh(path: &Path) -> bool {
    path.extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| MESH_EXTENSIONS.iter().any(|m| m.eq_ignore_ascii_case(e)))
}

/// The output of `input` (relative): the same place under the output directory, with
/// the asset extension.
pub fn output_of(input: &Path) -> PathBuf {
    input.with_extension(ASSET_EXTENSION)
}

/// Bakes every mesh under `input_dir` into `output_dir` on the current rayon pool
/// (`jobs` is its size, for the summary) with one progress bar, prints the summary
/// table and fails if any mesh was not baked.
pub fn run(
    input_dir: &Path,
    output_dir: &Path,
    options: &BuildOptions,
    jobs: usize,
) -> Result<(), LibraryError> {
    let start = Instant::now();
    let inputs = find_meshes(input_dir)?;
    if inputs.is_empty() {
        return Err(LibraryError::NoMeshes {
            dir: input_dir.to_path_buf(),
        });
    }
    let bar = crate::progress::progress_bar(
        inputs.len() as u64,
        "baking [{bar:30}] {pos}/{len} meshes, last {msg}",
    );
    bar.enable_steady_tick(std::time::Duration::from_millis(120));
    let rows = bake_all(input_dir, output_dir, &inputs, options, &|row| {
        bar.set_message(row.input.display().to_string());
        bar.inc(1);
    });
    bar.finish_and_clear();
    meshlight_output::write_stdout(&summary(&rows, jobs, start.elapsed().as_secs_f64()))?;
    let failed = rows
        .iter()
        .filter(|r| matches!(r.status, Status::Refused(_) | Status::Failed(_)))
        .count();
    if failed > 0 {
        return Err(LibraryError::NotBaked {
            failed,
            total: rows.len(),
        });
    }
    Ok(())
}

/// Bakes `inputs` (relative to `input_dir`) in parallel on the current rayon pool,
/// calling `done` as each finishes; the rows come back in the order of `inputs`.
pub fn bake_all(
    input_dir: &Path,
    output_dir: &Path,
    inputs: &[PathBuf],
    options: &BuildOptions,
    done: &(dyn Fn(&Row) + Sync),
) -> Vec<Row> {
    // Two inputs differing only in extension would write one output: neither is baked.
    let mut by_output: BTreeMap<PathBuf, Vec<&PathBuf>> = BTreeMap::new();
    for input in inputs {
        by_output.entry(output_of(input)).or_default().push(input);
    }
    inputs
        .par_iter()
        .map(|input| {
            let output = output_of(input);
            let start = Instant::now();
            let others: Vec<String> = by_output[&output]
                .iter()
                .filter(|other| **other != input)
                .map(|other| other.display().to_string())
                .collect();
            let (stats, status) = if others.is_empty() {
                bake_guarded(&input_dir.join(input), &output_dir.join(&output), options)
            } else {
                let why = format!(
                    "{} bakes to the same output {}; rename one of them",
                    others.join(", "),
                    output.display()
                );
                (None, Status::Refused(why))
            };
            let row = Row {
                input: input.clone(),
                output,
                stats,
                seconds: start.elapsed().as_secs_f64(),
                status,
            };
            done(&row);
            row
        })
        .collect()
}

/// [`bake_one`], with a panic in the builder reported as that file's failure: the other
/// files of a library still bake, and the table says which input to report.
fn bake_guarded(
    input: &Path,
    output: &Path,
    options: &BuildOptions,
) -> (Option<AssetStats>, Status) {
    std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
        bake_one(input, output, options)
    }))
    .unwrap_or_else(|panic| {
        let message = panic
            .downcast_ref::<&str>()
            .map(|s| s.to_string())
            .or_else(|| panic.downcast_ref::<String>().cloned())
            .unwrap_or_else(|| "no message".into());
        let why =
            format!("the builder panicked ({message}); please report this with the input mesh");
        (None, Status::Failed(why))
    })
}

/// Bakes one file unless its output is up to date.
fn bake_one(input: &Path, output: &Path, options: &BuildOptions) -> (Option<AssetStats>, Status) {
    let key = match stamp::input_key(input, options) {
        Ok(key) => key,
        Err(e) => return (None, Status::Refused(e.to_string())),
    };
    if let Some(stats) = stamp::up_to_date(output, &key) {
        return (Some(stats), Status::UpToDate);
    }
    let built = match load_mesh(input).and_then(|mesh| build_asset(&mesh, options, &mut |_| {})) {
        Ok(built) => built,
        Err(e) => return (None, Status::Refused(e.to_string())),
    };
    let stats = AssetStats {
        fallback_groups: fallback_groups(&built),
        ..stats_of(&built.asset)
    };
    if let Some(why) = fails_its_checks(&built.asset) {
        return (Some(stats), Status::Refused(why));
    }
    let text = stamp::stamp_text(&key, &built.asset, stats.fallback_groups);
    match write_replacing(output, built.asset.bytes())
        .and_then(|()| write_replacing(&stamp::stamp_of(output), text.as_bytes()))
    {
        Ok(()) => (Some(stats), Status::Baked),
        Err(e) => (Some(stats), Status::Failed(e.to_string())),
    }
}

/// Groups the builder kept unsimplified to avoid a crack (see `Built::fallback_groups`),
/// for the summary's column and the stamp.
fn fallback_groups(built: &Built) -> Option<u32> {
    Some(built.fallback_groups)
}

/// The numbers of a baked or loaded asset (the fallback count is not in the asset).
fn stats_of(asset: &MeshletAsset) -> AssetStats {
    let h = asset.header();
    AssetStats {
        lod0_triangles: h.lod0_triangles,
        clusters: h.meshlet_count,
        levels: h.level_count,
        fallback_groups: None,
    }
}

/// What `inspect` would reject, checked before writing as the single-file bake does.
fn fails_its_checks(asset: &MeshletAsset) -> Option<String> {
    let mut problems = match asset.validate() {
        Ok(()) => Vec::new(),
        Err(e) => vec![format!("{} {}", e.field, e.problem)],
    };
    if problems.is_empty() {
        problems = meshlight::scene::verify::verify(asset);
    }
    problems.first().map(|first| {
        format!(
            "the built asset fails its own checks ({} problems, first: {first}); please report this with the input mesh",
            problems.len()
        )
    })
}

/// Writes through a temporary file beside `path` and a rename, so that an interrupted
/// bake or a reader running at the same time never sees half a file under the name.
fn write_replacing(path: &Path, bytes: &[u8]) -> Result<(), OutputError> {
    create_parent(path)?;
    let mut tmp = path.as_os_str().to_owned();
    tmp.push(format!(".tmp{}", std::process::id()));
    let tmp = PathBuf::from(tmp);
    let error = |path: &Path, action, e: std::io::Error| OutputError {
        path: path.to_path_buf(),
        action,
        reason: e.to_string(),
    };
    std::fs::write(&tmp, bytes).map_err(|e| error(&tmp, "write", e))?;
    std::fs::rename(&tmp, path).map_err(|e| {
        let _ = std::fs::remove_file(&tmp);
        error(path, "replace", e)
    })
}

/// The table printed after a directory bake, then a line of totals.
pub fn summary(rows: &[Row], jobs: usize, seconds: f64) -> String {
    let width = rows
        .iter()
        .map(|r| r.input.display().to_string().chars().count())
        .max()
        .unwrap_or(0)
        .max(4);
    let mut s = String::new();
    let _ = writeln!(
        s,
        "{:<width$}  {:>10}  {:>8}  {:>6}  {:>8}  {:>8}  status",
        "file", "triangles", "clusters", "levels", "fallback", "time"
    );
    let number = |n: Option<u32>| n.map_or_else(|| "-".to_string(), |n| n.to_string());
    for r in rows {
        let st = r.stats;
        let _ = writeln!(
            s,
            "{:<width$}  {:>10}  {:>8}  {:>6}  {:>8}  {:>6.2} s  {}",
            r.input.display().to_string(),
            number(st.map(|s| s.lod0_triangles)),
            number(st.map(|s| s.clusters)),
            number(st.map(|s| s.levels)),
            number(st.and_then(|s| s.fallback_groups)),
            r.seconds,
            r.status.text()
        );
    }
    let count = |f: fn(&Status) -> bool| rows.iter().filter(|r| f(&r.status)).count();
    let baked_triangles: u64 = rows
        .iter()
        .filter(|r| r.status == Status::Baked)
        .filter_map(|r| r.stats.map(|s| u64::from(s.lod0_triangles)))
        .sum();
    let _ = writeln!(
        s,
        "{} meshes in {seconds:.2} s with {jobs} job(s): {} baked, {} up to date, {} refused, {} failed; {:.0} triangles baked per second",
        rows.len(),
        count(|s| *s == Status::Baked),
        count(|s| *s == Status::UpToDate),
        count(|s| matches!(s, Status::Refused(_))),
        count(|s| matches!(s, Status::Failed(_))),
        baked_triangles as f64 / seconds.max(1e-9)
    );
    s
}

#[cfg(test)]
mod tests {
    use super::scratch::scratch;
    use super::*;

    #[test]
    fn meshes_are_found_in_sorted_order_by_extension_and_collisions_are_refused() {
        let dir = scratch("find");
        for f in [
            "b/z.OBJ",
            "b/a.stl",
            "a.glb",
            "notes.txt",
            "c/d/e.gltf",
            "b/a.obj",
        ] {
            let path = dir.join(f);
            std::fs::create_dir_all(path.parent().unwrap()).unwrap();
            std::fs::write(&path, b"not a mesh").unwrap();
        }
        std::fs::create_dir_all(dir.join("empty.obj")).unwrap();
        let found = find_meshes(&dir).unwrap();
        let names: Vec<_> = found.iter().map(|p| p.to_str().unwrap()).collect();
        assert_eq!(
            names,
            ["a.glb", "b/a.obj", "b/a.stl", "b/z.OBJ", "c/d/e.gltf"]
        );
        assert_eq!(output_of(Path::new("b/z.OBJ")), Path::new("b/z.mlasset"));
        let rows = bake_all(
            &dir,
            &dir.join("out"),
            &found,
            &BuildOptions::default(),
            &|_| {},
        );
        for r in &rows {
            let Status::Refused(why) = &r.status else {
                panic!("{r:?}")
            };
            if r.input.to_str().unwrap().starts_with("b/a.") {
                assert!(why.contains("same output b/a.mlasset"), "{why}");
            } else {
                assert!(!why.contains("same output"), "{why}");
            }
        }
        let _ = std::fs::remove_dir_all(&dir);
    }

    #[test]
    fn the_summary_names_each_file_its_numbers_and_its_status() {
        let rows = [
            Row {
                input: "props/crate.glb".into(),
                output: "props/crate.mlasset".into(),
                stats: Some(AssetStats {
                    lod0_triangles: 5856,
                    clusters: 70,
                    levels: 6,
                    fallback_groups: Some(2),
                }),
                seconds: 0.25,
                status: Status::Baked,
            },
            Row {
                input: "broken.obj".into(),
                output: "broken.mlasset".into(),
                stats: None,
                seconds: 0.0,
                status: Status::Refused("line 3: a face names vertex 9".into()),
            },
        ];
        let text = summary(&rows, 2, 0.5);
        let lines: Vec<_> = text.lines().collect();
        assert_eq!(lines.len(), 4, "{text}");
        for column in [
            "file",
            "triangles",
            "clusters",
            "levels",
            "fallback",
            "time",
            "status",
        ] {
            assert!(lines[0].contains(column), "{text}");
        }
        for value in [
            "props/crate.glb",
            "5856",
            "70",
            " 6 ",
            " 2 ",
            "0.25 s",
            "baked",
        ] {
            assert!(lines[1].contains(value), "{value}: {text}");
        }
        assert!(lines[2].contains("refused: line 3"), "{text}");
        assert!(
            lines[3].contains("2 meshes")
                && lines[3].contains("1 baked")
                && lines[3].contains("1 refused"),
            "{text}"
        );
    }
}
