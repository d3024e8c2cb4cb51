//! Light clustering as a graph: z_slice → count_raster → scan_fan → populate, built in
//! code ([`build`], or [`add_stages`] into a larger frame) or loaded from a pipeline file
//! ([`load`]); both declare the same resources under the same names, so either runs with
//! the same [`Clusterer`](super::Clusterer).

use meshlight::count_raster::KINDS;
use meshlight::graph::file::{Params, Registry};
use meshlight::graph::{Bindings, BufferDesc, Element, GraphBuilder, GraphError, Result};
use meshlight::scan_fan::{ScanFan, ScanOptions, WALK_TILES, WORKGROUP};
use meshlight::z_slice::{
    CLUSTER_GRID, CLUSTERABLE_OBJECT, GridSettings, SLICE_INSTANCE, ZSlice, cpu::COUNT_WORDS,
};
use std::collections::BTreeMap;
use std::path::Path;

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

/// What the clustering is asked for; the same for both ways of building the graph.
#[derive(Clone, Debug, PartialEq)]
pub struct ClusteringSettings {
    /// The view's size in pixels.
    pub viewport: [u32; 2],
    pub grid: GridSettings,
    /// The implementation of `count_raster` and of `populate`, as registered: the same
    /// for both, so the two stages decide every (object, froxel) pair with the same
    /// code. Shipped: `compute` (workgroups walk the instances' tiles: the fast path
    /// where few units run graphics) and `raster` (a quad per instance through the
    /// rasteriser).
    pub implementation: String,
    /// The `scan_fan` implementation that turns the counts into offsets, as registered
    /// (`scan_fan`, `two_step`, `decoupled_lookback`).
    pub scan: String,
    /// Objects the object buffer holds; more in a frame is an error naming this.
    pub objects: u64,
    /// Initial sizes of z_slice's list and of the froxel lists; grown on overflow.
    pub slice_instances: u64,
    pub entries: u64,
}

impl ClusteringSettings {
    pub fn new(viewport: [u32; 2], objects: u64) -> Self {
        Self {
            viewport,
            grid: GridSettings::default(),
            implementation: "compute".into(),
            scan: "scan_fan".into(),
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

    fn check(&self) -> Result<()> {
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

    fn grid_pass(&self) -> ZSlice {
        ZSlice {
            grid: self.grid,
            ..ZSlice::default()
        }
    }
}

/// The four stages and their working buffers, into `g`, which must already hold
/// `objects` and `object_count` (imported, or written by an earlier pass). The outputs
/// are `cluster_grid`, `cluster_offsets`, `cluster_counts` and `cluster_objects`; the
/// counters `slice_counts` and `list_counts`.
pub fn add_stages(g: &mut GraphBuilder, s: &ClusteringSettings) -> Result<()> {
    add_stages_with(g, s, &meshlight::registry())
}

/// [`add_stages`] with the implementations of `registry`.
pub fn add_stages_with(
    g: &mut GraphBuilder,
    s: &ClusteringSettings,
    registry: &Registry,
) -> Result<()> {
    s.check()?;
    g.size_param(SLICE_INSTANCES_PARAM, s.slice_instances);
    g.size_param(ENTRIES_PARAM, s.entries);
    let lists = s.lists();
    for (name, desc) in [
        (
            "slice_instances",
            BufferDesc::array_param(SLICE_INSTANCE, SLICE_INSTANCES_PARAM),
        ),
        (
            "slice_counts",
            BufferDesc::array(Element::U32, COUNT_WORDS as u64),
        ),
        ("slice_draw_args", BufferDesc::array(Element::DRAW_ARGS, 1)),
        (
            "slice_dispatch_args",
            BufferDesc::array(Element::DISPATCH_ARGS, 1),
        ),
        ("cluster_grid", BufferDesc::array(CLUSTER_GRID, 1)),
        ("cluster_counts", BufferDesc::array(Element::U32, lists)),
        ("cluster_offsets", BufferDesc::array(Element::U32, lists)),
        ("list_total", BufferDesc::array(Element::U32, 1)),
        (
            "cluster_objects",
            BufferDesc::array_param(Element::U32, ENTRIES_PARAM),
        ),
        ("list_counts", BufferDesc::array(Element::U32, 2)),
    ] {
        g.create_buffer(name, desc);
    }
    // Slots not bound here bind to the resource of the same name.
    g.add_pass("z_slice", s.grid_pass(), Bindings::new())?;
    // The stages with several implementations come from the registry, as in a file.
    let [width, height, _] = s.grid.dims;
    let tiles = Params::new(toml::toml! {
        width = (width)
        height = (height)
    });
    let count = registry.build(meshlight::count_raster::STAGE, &s.implementation, &tiles)?;
    g.add_boxed_pass("count", count, Bindings::new())?;
    let mut scan_params = toml::toml! { count = (lists as i64) };
    if s.scan == "scan_fan" && fits_one_walk(lists as u32) {
        scan_params.insert(
            "items_per_thread".into(),
            toml::Value::Integer(WALK_ITEMS_PER_THREAD.into()),
        );
    }
    let scan = registry.build(
        meshlight::scan_fan::STAGE,
        &s.scan,
        &Params::new(scan_params),
    )?;
    let bindings = Bindings::new()
        .bind_named("input", "cluster_counts")
        .bind_named("output", "cluster_offsets")
        .bind_named("total", "list_total");
    g.add_boxed_pass("scan", scan, bindings)?;
    let populate = registry.build(meshlight::populate::STAGE, &s.implementation, &tiles)?;
    g.add_boxed_pass("populate", populate, Bindings::new())?;
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

/// `scan_fan` over `lists` counts: with tiles large enough for the single-dispatch walk
/// where the lists fit, else the default tiles.
pub fn scan_fan(lists: u32) -> ScanFan {
    let mut options = ScanOptions::new(lists);
    if fits_one_walk(lists) {
        options.items_per_thread = WALK_ITEMS_PER_THREAD;
    }
    ScanFan::with_options(options)
}

/// The clustering on its own: objects imported, the lists exported, counters read back.
pub fn build(s: &ClusteringSettings) -> Result<GraphBuilder> {
    let mut g = GraphBuilder::new();
    import_objects(&mut g, s);
    add_stages(&mut g, s)?;
    export_and_read_back(&mut g)?;
    Ok(g)
}

/// Imports `objects` (sized by [`OBJECTS_PARAM`]) and `object_count`.
pub fn import_objects(g: &mut GraphBuilder, s: &ClusteringSettings) {
    g.size_param(OBJECTS_PARAM, s.objects);
    g.import_buffer(
        "objects",
        BufferDesc::array_param(CLUSTERABLE_OBJECT, OBJECTS_PARAM),
        OBJECT_USAGE,
    );
    g.import_buffer(
        "object_count",
        BufferDesc::array(Element::U32, 1),
        OBJECT_USAGE,
    );
}

fn export_and_read_back(g: &mut GraphBuilder) -> Result<()> {
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
    add_readbacks(g)
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

/// A pipeline file with the clusterer's sizes set in its `[params]`, the counters' read
/// backs added. The grid's shape and the implementations are the file's.
pub fn load(path: &Path, s: &ClusteringSettings) -> Result<GraphBuilder> {
    let mut pipeline = meshlight::graph::file::Pipeline::load(path)?;
    pipeline.set_params(overrides(s))?;
    let mut g = pipeline.build(&meshlight::registry())?;
    add_readbacks(&mut g)?;
    Ok(g)
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
