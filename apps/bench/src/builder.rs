//! Builder benchmark scenarios, for `cargo bench` and `meshlight bench`: our build
//! against meshoptimizer's own `clod_build` on the same mesh in the same run, the
//! asset's bytes per triangle and its load speed from the page cache.

use std::path::Path;
use std::time::Instant;

use meshlight::scene::asset::MeshletAsset;
use meshlight::scene::error::SceneError;
use meshlight::scene::mesh::Mesh;
use meshlight::scene::pipeline::{BuildOptions, build_asset};

/// One builder scenario's numbers.
#[derive(Debug, Clone)]
pub struct BuilderBench {
    pub name: String,
    pub input_triangles: usize,
    /// Best wall time of the whole build (clean, DAG, packing), seconds.
    pub build_seconds: f64,
    pub levels: u32,
    pub root_meshlets: u32,
    /// Best wall time of meshoptimizer's `clod_build` on the cleaned mesh, seconds.
    pub clod_seconds: f64,
    pub clod_levels: u32,
    pub clod_root_clusters: usize,
    pub bytes_per_lod0_triangle: f64,
    pub asset_bytes: usize,
    /// Load (read + checksum + validation) from the page cache, bytes per second.
    pub load_bytes_per_second: f64,
    /// The same through [`MeshletAsset::load_verified`] (every check `inspect` runs,
    /// the DAG invariants included), bytes per second.
    pub verified_load_bytes_per_second: f64,
}

impl BuilderBench {
    pub fn triangles_per_second(&self) -> f64 {
        self.input_triangles as f64 / self.build_seconds
    }
    pub fn clod_triangles_per_second(&self) -> f64 {
        self.input_triangles as f64 / self.clod_seconds
    }
}

/// Runs the builder scenario `repeats` times (best time kept); the asset is written to
/// `scratch` for the load measurement.
pub fn builder_scenario(
    name: &str,
    mesh: &Mesh,
    repeats: usize,
    scratch: &Path,
) -> Result<BuilderBench, SceneError> {
    let options = BuildOptions::default();
    let (best, built) = best_time(repeats, || build_asset(mesh, &options, &mut |_| {}))?;
    let h = *built.asset.header();

    let (clod_seconds, clod_levels, clod_root_clusters) = clod_baseline(&built.mesh, repeats);

    let path = scratch.join(format!(
        "{}.mlasset",
        name.replace(|c: char| !c.is_ascii_alphanumeric(), "_")
    ));
    built.asset.save(&path)?;
    let bytes = built.asset.bytes().len();
    // Warm the page cache, then take the best of several loads.
    MeshletAsset::load(&path)?;
    let (load_best, _) = best_time(10, || MeshletAsset::load(&path))?;
    let (verified_best, _) = best_time(3, || MeshletAsset::load_verified(&path))?;
    let _ = std::fs::remove_file(&path);

    Ok(BuilderBench {
        name: name.to_owned(),
        input_triangles: built.mesh.triangle_count(),
        build_seconds: best,
        levels: h.level_count,
        root_meshlets: h.root_count,
        clod_seconds,
        clod_levels,
        clod_root_clusters,
        bytes_per_lod0_triangle: bytes as f64 / h.lod0_triangles as f64,
        asset_bytes: bytes,
        load_bytes_per_second: bytes as f64 / load_best,
        verified_load_bytes_per_second: bytes as f64 / verified_best,
    })
}

/// The best wall time of `runs` calls of `f` (one at least), seconds, and what the last
/// call returned; every result passes through `black_box` so that none is optimised away.
fn best_time<T, E>(runs: usize, mut f: impl FnMut() -> Result<T, E>) -> Result<(f64, T), E> {
    let mut best = f64::INFINITY;
    let mut last = None;
    for _ in 0..runs.max(1) {
        let start = Instant::now();
        let value = f()?;
        best = best.min(start.elapsed().as_secs_f64());
        last = Some(std::hint::black_box(value));
    }
    Ok((best, last.expect("runs.max(1) runs at least once")))
}

/// meshoptimizer's reference cluster-LOD builder (its `clusterlod.h`, compiled into the
/// meshopt crate) with the same cluster limits and normals as attributes.
fn clod_baseline(mesh: &Mesh, repeats: usize) -> (f64, u32, usize) {
    let adapter = meshopt::VertexDataAdapter::new(bytemuck::cast_slice(&mesh.positions), 12, 0)
        .expect("Vec3 is 12 bytes");
    let mut config = meshopt::clod_default_config(meshlight::scene::meshlets::MAX_TRIANGLES);
    config.max_vertices = meshlight::scene::meshlets::MAX_VERTICES;
    let clod_mesh = meshopt::ClodMesh {
        vertex_attributes: bytemuck::cast_slice(&mesh.normals),
        vertex_attributes_stride: 12,
        attribute_weights: &[0.5, 0.5, 0.5],
        ..meshopt::ClodMesh::new(&mesh.indices, &adapter)
    };
    let mut best = f64::INFINITY;
    let (mut levels, mut roots) = (0, 0);
    for _ in 0..repeats.max(1) {
        let start = Instant::now();
        let mut depth = 0;
        let mut terminal_clusters = 0;
        meshopt::clod_build(config, &clod_mesh, |group, clusters| {
            depth = depth.max(group.depth);
            // A terminal group (stuck, or the last one) has an infinite error: its
            // clusters are roots, wherever in the build it was output.
            if group.simplified.error == f32::MAX {
                terminal_clusters += clusters.len();
            }
            0
        });
        best = best.min(start.elapsed().as_secs_f64());
        // Cluster levels = group depths + the terminal group's output level.
        levels = depth as u32 + 1;
        roots = terminal_clusters;
    }
    (best, levels, roots)
}

/// A table of scenario results.
pub fn format_table(rows: &[BuilderBench]) -> String {
    let mut s = String::from(
        "scenario                 input tris   build s  Mtris/s  levels root | clod_build s  Mtris/s  levels root | ratio | B/tri | load GB/s | verified GB/s\n",
    );
    for r in rows {
        s += &format!(
            "{:<24} {:>10} {:>9.3} {:>8.3} {:>7} {:>4} | {:>12.3} {:>8.3} {:>7} {:>4} | {:>5.2} | {:>5.2} | {:>9.2} | {:>13.2}\n",
            r.name,
            r.input_triangles,
            r.build_seconds,
            r.triangles_per_second() / 1e6,
            r.levels,
            r.root_meshlets,
            r.clod_seconds,
            r.clod_triangles_per_second() / 1e6,
            r.clod_levels,
            r.clod_root_clusters,
            r.clod_seconds / r.build_seconds,
            r.bytes_per_lod0_triangle,
            r.load_bytes_per_second / 1e9,
            r.verified_load_bytes_per_second / 1e9
        );
    }
    s
}
