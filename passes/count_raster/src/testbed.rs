//! count_raster in a test graph, after z_slice's ([`meshlight_pass_z_slice::testbed`]):
//! the walks the GPU tests of this stage and of `populate` run, and the count they
//! start from.

use crate::Walk;
use meshlight_graph::{Bindings, GraphBuilder, PassOutputs, Result};
use meshlight_pass_z_slice::testbed::Sliced;
use meshlight_shaders::cpu::layout::ClusterGrid;

/// Which walk a test runs.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Implementation {
    Raster,
    Compute,
    /// `compute` dispatched with one workgroup: the walk takes a round per 64 instances.
    ComputeRounds,
}

impl Implementation {
    pub const ALL: [Self; 3] = [Self::Raster, Self::Compute, Self::ComputeRounds];

    /// The walk over `grid`'s tiles.
    pub fn walk(self, grid: &ClusterGrid) -> Walk {
        match self {
            Self::Raster => Walk::Raster {
                width: grid.dims[0],
                height: grid.dims[1],
            },
            Self::Compute => Walk::Compute(crate::WALK_GROUPS),
            Self::ComputeRounds => Walk::Compute(1),
        }
    }
}

/// Adds count_raster, walking as `walk`, over what `sliced` wrote; it counts into
/// z_slice's `cluster_counts`.
pub fn add_count(g: &mut GraphBuilder, sliced: &Sliced, walk: Walk) -> Result<PassOutputs> {
    let counts = sliced.outputs.buffer("cluster_counts")?;
    let bindings = sliced.bind_walk(Bindings::new().bind("cluster_counts", counts))?;
    g.add_boxed_pass("count", crate::pass(walk), bindings)
}
