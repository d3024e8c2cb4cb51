//! The whole chain from a mesh to an asset, with the numbers a bake summary reports.

use std::time::{Duration, Instant};

use crate::asset::MeshletAsset;
use crate::compress::{MAX_POSITION_BITS, MIN_POSITION_BITS, PositionBits, auto_position_bits};
use crate::dag::{Dag, DagOptions, LevelProgress, build_dag};
use crate::error::SceneError;
use crate::grouping::Grouping;
use crate::mesh::{CleanReport, Mesh};

/// Options of [`build_asset`].
#[derive(Debug, Clone, Copy)]
pub struct BuildOptions {
    pub grouping: Grouping,
    /// Bits per axis of the mesh-wide position grid.
    pub position_bits: PositionBits,
}

impl Default for BuildOptions {
    fn default() -> Self {
        Self {
            grouping: Grouping::Partition,
            position_bits: PositionBits::Auto,
        }
    }
}

/// An asset plus what was learnt while building it.
#[derive(Debug, Clone)]
pub struct Built {
    pub asset: MeshletAsset,
    /// The DAG in the cleaned mesh's vertex ids (for tests and tools).
    pub dag: Dag,
    /// The cleaned mesh the DAG refers to.
    pub mesh: Mesh,
    pub clean: CleanReport,
    pub dag_time: Duration,
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
    let start = Instant::now();
    let mut mesh = mesh.clone();
    let clean = mesh.clean()?;
    if clean.dropped_degenerate > 0 {
        log::info!(
            "{}: dropped {} degenerate triangles",
            mesh.source,
            clean.dropped_degenerate
        );
    }
    let dag_start = Instant::now();
    let dag = build_dag(
        &mesh,
        &DagOptions {
            grouping: options.grouping,
        },
        progress,
    )?;
    let dag_time = dag_start.elapsed();
    let position_bits = match options.position_bits {
        PositionBits::Fixed(bits) => bits,
        PositionBits::Auto => {
            let (min, max) = mesh.bounds();
            let lod0_errors: Vec<f32> = dag
                .clusters
                .iter()
                .filter(|c| c.level == 0)
                .map(|c| c.parent.error)
                .collect();
            auto_position_bits((max - min).max_element(), &lod0_errors)
        }
    };
    let asset = MeshletAsset::from_dag(&mesh, &dag, position_bits, clean.dropped_degenerate);
    Ok(Built {
        asset,
        dag,
        mesh,
        clean,
        dag_time,
        total_time: start.elapsed(),
    })
}
