//! Light clustering as a graph: z_slice → count_raster → scan_fan → populate. The frame
//! is `pipelines/light_clustering.toml`, embedded ([`SHIPPED`]); [`build`] applies a
//! [`ClusteringSettings`] to it through the pipeline's methods ([`apply`]), and [`load`]
//! does the same to a file of the caller's, so both run with the same
//! [`Clusterer`](super::Clusterer). A virtual-geometry frame that clusters lights holds
//! the same four passes, and takes the same settings through [`apply`].

use meshlight::count_raster::KINDS;
use meshlight::graph::file::Pipeline;
use meshlight::graph::{GraphBuilder, GraphError, Result};
use meshlight::scan_fan::{WALK_TILES, WORKGROUP};
use meshlight::z_slice::{GridSettings, cpu::COUNT_WORDS};
use std::collections::BTreeMap;
use std::path::Path;

/// The light clustering's frame, `pipelines/light_clustering.toml`.
pub const SHIPPED: &str = include_str!("../pipelines/light_clustering.toml");
/// How errors name [`SHIPPED`].
pub const SHIPPED_FILE: &str = "pipelines/light_clustering.toml";

/// The stages of the light clustering, in the order they run.
pub const STAGES: [&str; 4] = [
    meshlight::z_slice::STAGE,
    meshlight::count_raster::STAGE,
    meshlight::scan_fan::STAGE,
    meshlight::populate::STAGE,
];

/// The imported resources the clustering reads: the objects and how many are valid.
pub const INPUTS: [&str; 2] = ["objects", "object_count"];

/// Size parameter: clusterable objects the object buffer holds.
pub const OBJECTS_PARAM: &str = "objects";
/// Size parameter: (object, slice) instances z_slice's list holds.
pub const SLICE_INSTANCES_PARAM: &str = "slice_instances";
/// Size parameter: entries all froxel lists together hold.
pub const ENTRIES_PARAM: &str = "cluster_entries";
/// The readback of z_slice's count words.
pub const SLICE_COUNTS_READBACK: &str = "slice_counts";
/// The readback of populate's `list_counts` (needed, capacity).
pub const LIST_COUNTS_READBACK: &str = "list_counts";
/// How many frames later the counters come back.
pub const COUNTS_LATENCY: u32 = 2;
/// Usage of the imported object buffers.
pub const OBJECT_USAGE: wgpu::BufferUsages = wgpu::BufferUsages::STORAGE
    .union(wgpu::BufferUsages::COPY_DST)
    .union(wgpu::BufferUsages::COPY_SRC);

/// What the clustering is asked for, applied to the shipped frame and to a file alike.
#[derive(Clone, Debug, PartialEq)]
pub struct ClusteringSettings {
    /// The view's size in pixels.
    pub viewport: [u32; 2],
    /// The froxel grid: tiles across, down and depth slices, and how depth is sliced.
    pub grid: GridSettings,
    /// The implementation of `count_raster` and of `populate`, as registered: the same
    /// for both, so the two stages decide every (object, froxel) pair with the same
    /// code. Shipped: `compute` (workgroups walk the instances' tiles: the fast path
    /// where few units run graphics) and `raster` (a quad per instance through the
    /// rasteriser). `None`: the pipeline's (`compute` in the shipped files).
    pub implementation: Option<String>,
    /// The `scan_fan` implementation that turns the counts into offsets, as registered
    /// (`scan_fan`, `two_step`, `decoupled_lookback`); `None`: the pipeline's
    /// (`scan_fan` in the shipped files).
    pub scan: Option<String>,
    /// Objects the object buffer holds; more in a frame is an error naming this.
    pub objects: u64,
    /// Initial sizes of z_slice's list and of the froxel lists; grown on overflow.
    pub slice_instances: u64,
    /// See `slice_instances`.
    pub entries: u64,
}

impl ClusteringSettings {
    /// The default grid over a `viewport`, for up to `objects` lights, with lists
    /// sized for them (grown when a frame needs more).
    pub fn new(viewport: [u32; 2], objects: u64) -> Self {
        Self {
            viewport,
            grid: GridSettings::default(),
            implementation: None,
            scan: None,
            objects,
            slice_instances: (objects * 4).max(1024),
            entries: (objects * 16).max(4096),
        }
    }

    /// Lists: one per froxel and kind.
    pub fn lists(&self) -> u64 {
        let [w, h, d] = self.grid.dims.map(u64::from);
        w * h * d * u64::from(KINDS)
    }

    /// Refuses a grid with an empty dimension, more lists than the prefix sum takes, or
    /// an empty capacity, naming what to change.
    pub fn check(&self) -> Result<()> {
        let err = |message: String| {
            Err(GraphError::Setting {
                setting: "the light clustering's settings".into(),
                message,
            })
        };
        if self.grid.dims.contains(&0) {
            return err(format!(
                "a cluster grid of {:?} froxels: every dimension needs at least 1",
                self.grid.dims
            ));
        }
        if self.lists() > u64::from(meshlight::scan_fan::MAX_COUNT) {
            return err(format!(
                "a cluster grid of {:?} froxels has {} lists, past the prefix sum's {}; use fewer froxels",
                self.grid.dims,
                self.lists(),
                meshlight::scan_fan::MAX_COUNT
            ));
        }
        if self.objects == 0 || self.slice_instances == 0 || self.entries == 0 {
            return err(
                "the object, slice-instance and entry capacities must be at least 1".into(),
            );
        }
        Ok(())
    }
}

/// Applies `s` to a pipeline holding the clustering's passes: its sizes and grid
/// (`[params]`), z_slice's depth slicing, the `count_raster`/`populate` and `scan_fan`
/// implementations, and the scan's tiles (the single-dispatch walk where the lists fit
/// one, the implementation's default otherwise).
pub fn apply(p: &mut Pipeline, s: &ClusteringSettings) -> Result<()> {
    s.check()?;
    p.set_params(overrides(s))?;
    p.set_stage_param(
        meshlight::z_slice::STAGE,
        "first_slice_end",
        f64::from(s.grid.first_slice_end),
    );
    p.set_stage_param(meshlight::z_slice::STAGE, "far", f64::from(s.grid.far));
    if let Some(implementation) = &s.implementation {
        for stage in [meshlight::count_raster::STAGE, meshlight::populate::STAGE] {
            p.set_implementation(stage, implementation);
        }
    }
    let lists = s.lists() as u32;
    for scan in p.passes_of_mut(meshlight::scan_fan::STAGE) {
        if let Some(implementation) = &s.scan {
            scan.implementation = implementation.clone();
        }
        if scan.implementation == "scan_fan" && fits_one_walk(lists) {
            scan.set_param("items_per_thread", i64::from(WALK_ITEMS_PER_THREAD));
        } else {
            scan.params.remove("items_per_thread");
        }
    }
    Ok(())
}

/// Whether `lists` counts fit in [`WALK_TILES`] tiles of [`WALK_ITEMS_PER_THREAD`]
/// elements a lane, so that one workgroup walks them in a single dispatch.
fn fits_one_walk(lists: u32) -> bool {
    lists <= WALK_TILES * WORKGROUP * WALK_ITEMS_PER_THREAD
}

/// Lanes' elements of the scan when the lists fit in [`WALK_TILES`] tiles of that size:
/// one workgroup then walks the tiles in one dispatch instead of the fan's three
/// dependent ones (the default grid's 13,824 lists are two tiles of 8,192).
pub const WALK_ITEMS_PER_THREAD: u32 = 32;

/// The clustering on its own, from [`SHIPPED`]: objects imported, the lists exported,
/// counters read back.
pub fn build(s: &ClusteringSettings) -> Result<GraphBuilder> {
    from_pipeline(Pipeline::parse(SHIPPED, SHIPPED_FILE)?, s)
}

/// A pipeline file of the caller's with `s` applied ([`apply`]), its counters read back.
pub fn load(path: &Path, s: &ClusteringSettings) -> Result<GraphBuilder> {
    from_pipeline(Pipeline::load(path)?, s)
}

fn from_pipeline(mut p: Pipeline, s: &ClusteringSettings) -> Result<GraphBuilder> {
    apply(&mut p, s)?;
    let mut g = p.build(&meshlight::registry())?;
    for name in [
        "cluster_grid",
        "cluster_offsets",
        "cluster_counts",
        "cluster_objects",
    ] {
        let handle = g.resource(name).ok_or_else(|| GraphError::Setting {
            setting: "the light clustering's graph".into(),
            message: format!(
                "no resource `{name}`: the clustering's outputs must keep their names"
            ),
        })?;
        g.export(handle);
    }
    add_readbacks(&mut g)?;
    Ok(g)
}

/// The counters come back [`COUNTS_LATENCY`] frames later.
pub fn add_readbacks(g: &mut GraphBuilder) -> Result<()> {
    g.readback_named(
        SLICE_COUNTS_READBACK,
        "slice_counts",
        Some(0..4 * COUNT_WORDS as u64),
        COUNTS_LATENCY,
    )?;
    g.readback_named(
        LIST_COUNTS_READBACK,
        "list_counts",
        Some(0..8),
        COUNTS_LATENCY,
    )
}

/// The `[params]` the clusterer sets in a pipeline file.
pub fn overrides(s: &ClusteringSettings) -> BTreeMap<String, u64> {
    let [w, h, d] = s.grid.dims.map(u64::from);
    BTreeMap::from([
        (OBJECTS_PARAM.to_string(), s.objects),
        (SLICE_INSTANCES_PARAM.to_string(), s.slice_instances),
        (ENTRIES_PARAM.to_string(), s.entries),
        ("grid_width".to_string(), w),
        ("grid_height".to_string(), h),
        ("grid_depth".to_string(), d),
        ("lists".to_string(), s.lists()),
    ])
}
