//! Baked assets cached on disk, so that rendering the same mesh twice bakes it once.
//!
//! The key is an XXH3 hash of everything the asset depends on: the source file's bytes
//! (or the procedural mesh's segment count), the build options, the asset format
//! version, this crate's version and the builder's revision (a builder change must not
//! serve stale assets).
//! A cached file is loaded with the same validation as any asset; one that fails it is
//! baked again and replaced, never used.

use std::path::{Path, PathBuf};

use xxhash_rust::xxh3::xxh3_64;

use crate::asset::MeshletAsset;
use crate::asset::format::VERSION;
use crate::dag::LevelProgress;
use crate::error::SceneError;
use crate::load::load_mesh;
use crate::mesh::Mesh;
use crate::pipeline::{BuildOptions, build_asset};
use crate::procedural::procedural_mesh;

/// Raised whenever the builder makes different assets from the same input and options
/// within one crate version: 2 = meshlets grown by `greedy_meshlets` across seams,
/// groups by meshoptimizer's partitioner, the welded escalation step; 3 = positions
/// welded within a tolerance, duplicate faces dropped, cracking groups repaired; 4 =
/// meshlets split by material slot; 5 = UVs simplified with the positions and their
/// slide counted in the LOD error.
pub const BUILDER_REVISION: u32 = 5;

/// Environment variable naming the cache directory (default: the user cache directory).
pub const CACHE_DIR_ENV: &str = "MESHLIGHT_CACHE_DIR";

/// What to bake: a mesh file or the procedural mesh.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Source {
    /// A mesh file; its bytes are part of the key, so an edited file is baked again.
    File(PathBuf),
    /// The procedural mesh, generated rather than read.
    Procedural {
        /// Tube segments (see [`crate::procedural_mesh`]): part of the key.
        segments: u32,
    },
}

impl Source {
    /// What to call the source in progress and error messages.
    pub fn name(&self) -> String {
        match self {
            Source::File(p) => p.display().to_string(),
            Source::Procedural { segments } => format!("procedural mesh ({segments} segments)"),
        }
    }
}

/// Whether [`load_or_bake`] found the asset in the cache.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Outcome {
    /// Loaded from the cache; nothing was baked.
    Hit,
    /// Baked and written to the cache.
    Baked,
    /// Baked; the cache could not be written (the reason was logged).
    BakedUncached,
}

/// The cache directory: `$MESHLIGHT_CACHE_DIR`, else `$XDG_CACHE_HOME/meshlight`, else
/// `~/.cache/meshlight`, else a directory under the system temporary directory.
pub fn cache_dir() -> PathBuf {
    if let Some(dir) = std::env::var_os(CACHE_DIR_ENV) {
        return PathBuf::from(dir);
    }
    if let Some(dir) = std::env::var_os("XDG_CACHE_HOME") {
        return PathBuf::from(dir).join("meshlight");
    }
    match std::env::var_os("HOME") {
        Some(home) => PathBuf::from(home).join(".cache").join("meshlight"),
        None => std::env::temp_dir().join("meshlight-cache"),
    }
}

/// The cache key of a source baked with `options`; reads the source file.
pub fn key(source: &Source, options: &BuildOptions) -> Result<u64, SceneError> {
    let bytes = match source {
        Source::File(path) => crate::input::read_file(path, crate::input::MAX_INPUT_BYTES)?,
        Source::Procedural { segments } => format!("procedural:{segments}").into_bytes(),
    };
    Ok(key_of(bytes, options))
}

/// The cache key of a mesh already in memory (one mesh of a glTF scene): its content,
/// so the same mesh in two files, or a file edited elsewhere, bakes once.
pub fn mesh_key(mesh: &Mesh, options: &BuildOptions) -> u64 {
    let mut bytes = b"mesh:".to_vec();
    for part in [
        bytemuck::cast_slice::<_, u8>(&mesh.positions),
        bytemuck::cast_slice(&mesh.normals),
        bytemuck::cast_slice(&mesh.uvs),
        bytemuck::cast_slice(&mesh.colors),
        bytemuck::cast_slice(&mesh.indices),
        bytemuck::cast_slice(&mesh.materials),
    ] {
        bytes.extend_from_slice(&(part.len() as u64).to_le_bytes());
        bytes.extend_from_slice(part);
    }
    key_of(bytes, options)
}

/// What every key hashes after the input: the options, the format, the builder.
fn key_of(mut bytes: Vec<u8>, options: &BuildOptions) -> u64 {
    bytes.extend(
        format!(
            "|{:?}|{}|weld {:e}|format {VERSION}|builder {} r{BUILDER_REVISION}",
            options.grouping,
            options.position_bits,
            options.weld_tolerance,
            env!("CARGO_PKG_VERSION")
        )
        .into_bytes(),
    );
    xxh3_64(&bytes)
}

/// The asset of `source` from the cache in `dir`, or baked (with `progress` after each
/// level) and stored there.
pub fn load_or_bake(
    source: &Source,
    options: &BuildOptions,
    dir: &Path,
    progress: &mut dyn FnMut(LevelProgress),
) -> Result<(MeshletAsset, Outcome), SceneError> {
    let key = key(source, options)?;
    cached_or_built(key, dir, MeshletAsset::load_verified, || {
        build_asset(&load_source(source)?, options, progress).map(|b| b.asset)
    })
}

/// [`load_or_bake`] for a scene that streams: the cached file opened for streaming
/// ([`MeshletAsset::open_resident`]: its resident part read, its pages read as the view
/// needs them), baking it into the cache first when it is not there. Only when the
/// cache cannot be written is the asset returned whole, as baked.
pub fn open_or_bake_resident(
    source: &Source,
    options: &BuildOptions,
    dir: &Path,
    progress: &mut dyn FnMut(LevelProgress),
) -> Result<(MeshletAsset, Outcome), SceneError> {
    let key = key(source, options)?;
    cached_resident(key, dir, || {
        build_asset(&load_source(source)?, options, progress).map(|b| b.asset)
    })
}

/// [`load_or_bake_mesh`] for a scene that streams, as [`open_or_bake_resident`].
pub fn open_or_bake_mesh_resident(
    mesh: &Mesh,
    options: &BuildOptions,
    dir: &Path,
    progress: &mut dyn FnMut(LevelProgress),
) -> Result<(MeshletAsset, Outcome), SceneError> {
    cached_resident(mesh_key(mesh, options), dir, || {
        build_asset(mesh, options, progress).map(|b| b.asset)
    })
}

/// The cache entry `key` opened for streaming, built and stored first when missing.
fn cached_resident(
    key: u64,
    dir: &Path,
    build: impl FnOnce() -> Result<MeshletAsset, SceneError>,
) -> Result<(MeshletAsset, Outcome), SceneError> {
    let (asset, outcome) = cached_or_built(key, dir, MeshletAsset::open_resident, build)?;
    match outcome {
        // Baked just now and stored: the file is what streams, not the copy in memory.
        Outcome::Baked => Ok((MeshletAsset::open_resident(&entry(dir, key))?, outcome)),
        _ => Ok((asset, outcome)),
    }
}

/// The file of cache entry `key` in `dir`.
fn entry(dir: &Path, key: u64) -> PathBuf {
    dir.join(format!("{key:016x}.mlasset"))
}

/// The asset of a mesh in memory (one mesh of a glTF scene) from the cache in `dir`,
/// keyed by its content ([`mesh_key`]), or baked and stored there.
pub fn load_or_bake_mesh(
    mesh: &Mesh,
    options: &BuildOptions,
    dir: &Path,
    progress: &mut dyn FnMut(LevelProgress),
) -> Result<(MeshletAsset, Outcome), SceneError> {
    cached_or_built(
        mesh_key(mesh, options),
        dir,
        MeshletAsset::load_verified,
        || build_asset(mesh, options, progress).map(|b| b.asset),
    )
}

/// The cache entry `key` in `dir` read with `open`, or built and stored there. `open`
/// checks what `inspect` checks ([`MeshletAsset::load_verified`], or
/// [`MeshletAsset::open_resident`] for the resident part): an entry that a bug or a
/// disk damaged in a way the checksum cannot see is baked again, never drawn.
fn cached_or_built(
    key: u64,
    dir: &Path,
    open: fn(&Path) -> Result<MeshletAsset, SceneError>,
    build: impl FnOnce() -> Result<MeshletAsset, SceneError>,
) -> Result<(MeshletAsset, Outcome), SceneError> {
    let path = entry(dir, key);
    if path.exists() {
        match open(&path) {
            Ok(asset) => return Ok((asset, Outcome::Hit)),
            Err(e) => log::warn!(
                "cached asset {} is unusable ({e}); baking again",
                path.display()
            ),
        }
    }
    let asset = build()?;
    let outcome = match store(&asset, dir, &path) {
        Ok(()) => Outcome::Baked,
        Err(e) => {
            log::warn!("could not cache the baked asset in {}: {e}", dir.display());
            Outcome::BakedUncached
        }
    };
    Ok((asset, outcome))
}

fn load_source(source: &Source) -> Result<Mesh, SceneError> {
    match source {
        Source::File(path) => load_mesh(path),
        Source::Procedural { segments } => Ok(procedural_mesh(*segments)),
    }
}

/// Writes through a temporary file and a rename, so a concurrent reader or an
/// interrupted write never leaves a half-written asset under the final name.
fn store(asset: &MeshletAsset, dir: &Path, path: &Path) -> Result<(), SceneError> {
    std::fs::create_dir_all(dir).map_err(|e| SceneError::io(dir, e))?;
    let tmp = path.with_extension(format!("tmp{}", std::process::id()));
    asset.save(&tmp)?;
    std::fs::rename(&tmp, path).map_err(|e| SceneError::io(path, e))
}

/// Reports a bake's progress at `info` level of the `log` crate, for hosts that draw no
/// progress of their own: a first bake of a large mesh takes seconds, and whoever
/// enables the logs can see that it is moving and on which level.
pub fn log_progress(name: &str, p: LevelProgress) {
    log::info!(
        "baking {name}: level {}, {} clusters, {} triangles left",
        p.level,
        p.active_clusters,
        p.active_triangles
    );
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_streamed_scene_opens_the_cached_file_for_its_resident_part() {
        let dir =
            std::env::temp_dir().join(format!("meshlight-cache-stream-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        let source = Source::Procedural { segments: 8 };
        let options = BuildOptions::default();
        let (a, first) = open_or_bake_resident(&source, &options, &dir, &mut |_| {}).unwrap();
        assert_eq!(first, Outcome::Baked);
        let (b, second) = open_or_bake_resident(&source, &options, &dir, &mut |_| {}).unwrap();
        assert_eq!(second, Outcome::Hit);
        let path = entry(&dir, key(&source, &options).unwrap());
        for asset in [&a, &b] {
            assert_eq!(asset.page_file(), Some(path.as_path()));
            assert_eq!(asset.bytes().len() as u64, asset.resident_bytes());
        }
        let (whole, _) = load_or_bake(&source, &options, &dir, &mut |_| {}).unwrap();
        assert_eq!(whole.meshlets(), a.meshlets());
        assert!(whole.bytes().len() > a.bytes().len());
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn a_second_load_hits_and_a_corrupt_entry_is_rebaked() {
        let dir = std::env::temp_dir().join(format!("meshlight-cache-test-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        let source = Source::Procedural { segments: 6 };
        let options = BuildOptions::default();
        let (a, first) = load_or_bake(&source, &options, &dir, &mut |_| {}).unwrap();
        assert_eq!(first, Outcome::Baked);
        let (b, second) = load_or_bake(&source, &options, &dir, &mut |_| {}).unwrap();
        assert_eq!(second, Outcome::Hit);
        assert_eq!(a.bytes(), b.bytes());
        // Other options are another key.
        let other = BuildOptions {
            grouping: crate::grouping::Grouping::Metis,
            ..options
        };
        assert_ne!(
            key(&source, &options).unwrap(),
            key(&source, &other).unwrap()
        );
        // A damaged cache entry is not used: it is baked again and replaced.
        let path = dir.join(format!("{:016x}.mlasset", key(&source, &options).unwrap()));
        let mut bytes = std::fs::read(&path).unwrap();
        let n = bytes.len();
        bytes[n - 5] ^= 0xff;
        std::fs::write(&path, &bytes).unwrap();
        let (c, third) = load_or_bake(&source, &options, &dir, &mut |_| {}).unwrap();
        assert_eq!(third, Outcome::Baked);
        assert_eq!(c.bytes(), a.bytes());
        // So is one whose checksum holds but whose DAG does not (a group's error
        // below its child's, written with a valid checksum).
        let mesh = crate::procedural_mesh(12);
        let built = build_asset(&mesh, &options, &mut |_| {}).unwrap();
        crate::damaged::error_below_child(&built)
            .unwrap()
            .save(&path)
            .unwrap();
        assert!(MeshletAsset::load(&path).is_ok(), "structurally sound");
        let (d, fourth) = load_or_bake(&source, &options, &dir, &mut |_| {}).unwrap();
        assert_eq!(fourth, Outcome::Baked);
        assert_eq!(d.bytes(), a.bytes());
        let _ = std::fs::remove_dir_all(&dir);
    }
}
