//! The whole chain from a mesh to an asset, with the numbers a bake summary reports.

use std::time::{Duration, Instant};

use crate::asset::MeshletAsset;
use glam::Vec3;
use rustc_hash::FxHashMap;

use crate::compress::{
    MAX_POSITION_BITS, MIN_POSITION_BITS, PositionBits, Quantization, auto_position_bits,
};
use crate::dag::{Dag, DagOptions, Fallbacks, LevelProgress, build_dag};
use crate::error::SceneError;
use crate::grouping::Grouping;
use crate::mesh::{CleanReport, Mesh};
use crate::weld::{DEFAULT_WELD_TOLERANCE, MAX_WELD_TOLERANCE};

/// Options of [`build_asset`].
#[derive(Debug, Clone, Copy)]
pub struct BuildOptions {
    /// How meshlets are grouped for simplification.
    pub grouping: Grouping,
    /// Bits per axis of the mesh-wide position grid.
    pub position_bits: PositionBits,
    /// Positions closer than this share of the mesh's extent (its largest bounding-box
    /// side) are welded into one before building (see [`crate::weld`]); 0 joins only
    /// identical positions. Default [`DEFAULT_WELD_TOLERANCE`], at most
    /// [`MAX_WELD_TOLERANCE`].
    pub weld_tolerance: f32,
}

impl Default for BuildOptions {
    fn default() -> Self {
        Self {
            grouping: Grouping::Partition,
            position_bits: PositionBits::Auto,
            weld_tolerance: DEFAULT_WELD_TOLERANCE,
        }
    }
}

/// An asset plus what was learnt while building it.
#[derive(Debug, Clone)]
pub struct Built {
    /// The packed asset, ready to save or upload.
    pub asset: MeshletAsset,
    /// The DAG in the cleaned mesh's vertex ids (for tests and tools).
    pub dag: Dag,
    /// The cleaned mesh the DAG refers to.
    pub mesh: Mesh,
    /// What cleaning dropped and welded before building.
    pub clean: CleanReport,
    /// Groups whose simplification would have cracked a LOD cut and were repaired
    /// (also in `dag.fallbacks`).
    pub fallbacks: Fallbacks,
    /// Groups kept unsimplified to avoid a crack: `fallbacks.unsimplified`, the number
    /// a bake summary reports per mesh.
    pub fallback_groups: u32,
    /// Whether distinct positions met on the position grid, so that the mesh was
    /// snapped to the grid and built again (see [`build_asset`]).
    pub snapped_to_grid: bool,
    /// Building the DAG alone, to tell the builder's cost from cleaning and packing.
    pub dag_time: Duration,
    /// Cleaning, building and packing.
    pub total_time: Duration,
}

/// Cleans `mesh`, builds its LOD DAG and packs it. `progress` is called after each level.
pub fn build_asset(
    mesh: &Mesh,
    options: &BuildOptions,
    progress: &mut dyn FnMut(LevelProgress),
) -> Result<Built, SceneError> {
    if let PositionBits::Fixed(bits) = options.position_bits
        && !(MIN_POSITION_BITS..=MAX_POSITION_BITS).contains(&bits)
    {
        return Err(SceneError::InvalidOption(format!(
            "position bits {bits} is outside {MIN_POSITION_BITS}..={MAX_POSITION_BITS}; \
             give a value in that range or `auto`"
        )));
    }
    if !(0.0..=MAX_WELD_TOLERANCE).contains(&options.weld_tolerance) {
        return Err(SceneError::InvalidOption(format!(
            "weld tolerance {} is outside 0..={MAX_WELD_TOLERANCE} (a share of the mesh's \
             extent); give a value in that range, e.g. the default {DEFAULT_WELD_TOLERANCE}",
            options.weld_tolerance
        )));
    }
    let start = Instant::now();
    let mut mesh = mesh.clone();
    let mut clean = mesh.clean_with(options.weld_tolerance)?;
    let dag_options = DagOptions {
        grouping: options.grouping,
    };
    let dag_start = Instant::now();
    let mut dag = build_dag(&mesh, &dag_options, progress)?;
    let position_bits = match options.position_bits {
        PositionBits::Fixed(bits) => bits,
        PositionBits::Auto => {
            let (min, max) = mesh.bounds();
            // The positions' own error: a texture's slide (also in `parent.error`) says
            // nothing of how finely positions must be stored.
            let lod0_errors: Vec<f32> = dag
                .clusters
                .iter()
                .filter(|c| c.level == 0)
                .map(|c| match dag.groups.get(c.parent_group as usize) {
                    Some(g) => g.simplify_error.max(g.deviation),
                    None => c.parent.error,
                })
                .collect();
            auto_position_bits((max - min).max_element(), &lod0_errors)
        }
    };
    let (min, max) = mesh.bounds();
    let grid = Quantization::new(min, max, position_bits);
    // The asset stores grid points, and the GPU (and the crack check) joins vertices by
    // them: two positions the builder kept apart but the grid merges would make border
    // edges the builder never locked. Rare (points closer than a grid step); then the
    // mesh is snapped to the grid and built again, so both see the same points.
    let snapped_to_grid = grid_merges_points(&mesh, &grid);
    if snapped_to_grid {
        for p in &mut mesh.positions {
            *p = grid.dequantize(grid.quantize(*p));
        }
        let again = mesh.clean_with(0.0)?;
        clean.dropped_degenerate += again.dropped_degenerate;
        clean.dropped_duplicate += again.dropped_duplicate;
        dag = build_dag(&mesh, &dag_options, &mut |_| {})?;
    }
    let dag_time = dag_start.elapsed();
    if clean.dropped_degenerate + clean.dropped_duplicate > 0 {
        log::info!(
            "{}: dropped {} degenerate and {} duplicate triangles",
            mesh.source,
            clean.dropped_degenerate,
            clean.dropped_duplicate
        );
    }
    let asset = MeshletAsset::from_dag_on_grid(
        &mesh,
        &dag,
        grid,
        crate::asset::Dropped {
            degenerate: clean.dropped_degenerate,
            duplicate: clean.dropped_duplicate,
        },
    );
    Ok(Built {
        asset,
        fallbacks: dag.fallbacks,
        fallback_groups: dag.fallbacks.unsimplified as u32,
        snapped_to_grid,
        dag,
        mesh,
        clean,
        dag_time,
        total_time: start.elapsed(),
    })
}

/// Whether two distinct positions used by triangles fall on one grid point.
///
/// Each vertex once (the cleaned mesh uses every vertex), in a table sized for all of
/// them, keyed by the grid point packed into one integer: FxHash mixes an integer well,
/// where an array's bytes hashed in turn clustered and made this a tenth of the build.
fn grid_merges_points(mesh: &Mesh, grid: &Quantization) -> bool {
    let mut used = vec![false; mesh.positions.len()];
    for &v in &mesh.indices {
        used[v as usize] = true;
    }
    let mut first: FxHashMap<u128, Vec3> =
        FxHashMap::with_capacity_and_hasher(mesh.positions.len(), Default::default());
    mesh.positions.iter().zip(&used).any(|(&p, &used)| {
        let q = grid.quantize(p);
        let key = q[0] as u128 | (q[1] as u128) << 32 | (q[2] as u128) << 64;
        used && *first.entry(key).or_insert(p) != p
    })
}
