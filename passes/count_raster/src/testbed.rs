//! count_raster in a test graph, after z_slice's ([`meshlight_pass_z_slice::testbed`]):
//! the walks the GPU tests of this stage and of `populate` run, and the graph and frame
//! they start from.

use crate::Walk;
use meshlight_graph::{Bindings, Executor, GraphBuilder, Imports, PassOutputs, Result};
use meshlight_pass_z_slice::testbed::{Sliced, read_written, run_frame};
use meshlight_pass_z_slice::{SliceInstance, ZSlice};
use meshlight_shaders::cpu::layout::{ClusterGrid, ClusterableObject, View};

/// Which walk a test runs.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Implementation {
    /// The `raster` implementation: a quad per instance.
    Raster,
    /// The `compute` implementation with its default grid.
    Compute,
    /// `compute` dispatched with one workgroup: the walk takes a round per 64 instances.
    ComputeRounds,
}

impl Implementation {
    /// Every walk, for tests that run each.
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

/// What a walking stage's GPU test runs over: the objects, the view they are seen
/// through and the z_slice that cuts the view into the grid the walk covers.
pub struct Scene {
    /// The camera the objects are clustered for.
    pub view: View,
    /// The lights, probes and decals to cluster.
    pub objects: Vec<ClusterableObject>,
    /// The z_slice pass, whose grid the walk covers.
    pub z_slice: ZSlice,
}

/// z_slice and count_raster over a [`Scene`], walking as a test's [`Implementation`],
/// in a test graph: what the GPU tests of this stage and of `populate` build before
/// adding what they read back (populate its scan and its own pass too), and run alike.
pub struct Counted<'a> {
    /// The scene the graph was built for.
    pub scene: &'a Scene,
    /// The graph so far: z_slice and count_raster, for the test to add to.
    pub graph: GraphBuilder,
    /// z_slice's outputs the walk read.
    pub sliced: Sliced,
    /// The grid z_slice cuts the view into.
    pub grid: ClusterGrid,
    /// The walk count_raster runs, for a later stage to walk alike.
    pub walk: Walk,
    /// What count_raster wrote: it counts into z_slice's `cluster_counts`.
    pub outputs: PassOutputs,
}

impl<'a> Counted<'a> {
    /// The graph over `scene` ([`Sliced::add_for_walk`]), count_raster walking what
    /// z_slice wrote.
    pub fn add(scene: &'a Scene, implementation: Implementation) -> Result<Self> {
        let mut graph = GraphBuilder::new();
        let objects = scene.objects.len();
        let (sliced, grid) = Sliced::add_for_walk(&mut graph, scene.z_slice, objects, &scene.view)?;
        let walk = implementation.walk(&grid);
        let counts = sliced.outputs.buffer("cluster_counts")?;
        let bindings = sliced.bind_walk(Bindings::new().bind("cluster_counts", counts))?;
        let outputs = graph.add_boxed_pass("count", crate::pass(walk), bindings)?;
        Ok(Self {
            scene,
            graph,
            sliced,
            grid,
            walk,
            outputs,
        })
    }

    /// Runs one frame of the graph on `exec` over all of the scene's objects with the
    /// caller's `imports` beside them ([`run_frame`]), and returns what z_slice wrote
    /// ([`read_written`]); the caller reads what it exported.
    pub fn run(
        mut self,
        exec: &mut Executor,
        imports: Imports,
    ) -> Result<(Vec<SliceInstance>, ClusterGrid)> {
        self.sliced.export_written(&mut self.graph)?;
        let Scene { view, objects, .. } = self.scene;
        let count = objects.len() as u32;
        run_frame(exec, self.graph, objects, count, view, imports)?;
        Ok(read_written(exec))
    }
}
