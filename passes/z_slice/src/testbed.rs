//! z_slice in a test graph, for the GPU tests of the light-clustering stages: the scene's
//! objects imported, the pass added, and what it wrote read back. Every stage after it is
//! tested on the list z_slice wrote on the GPU, and each builds that list the same way.

use crate::cpu::{WORD_CAPACITY, WORD_REQUESTED};
use crate::{CLUSTER_GRID, CLUSTERABLE_OBJECT, SLICE_INSTANCE, SliceInstance, ZSlice};
use meshlight_graph::{
    Bindings, Buffer, BufferDesc, CompileOptions, Element, Executor, FrameData, GraphBuilder,
    Handle, Imports, PassOutputs, Result,
};
use meshlight_shaders::cpu::layout::{ClusterGrid, ClusterableKind, ClusterableObject, View};

/// What a test's buffers are used as: bound as storage, filled, read back.
pub const USAGE: wgpu::BufferUsages = wgpu::BufferUsages::STORAGE
    .union(wgpu::BufferUsages::COPY_DST)
    .union(wgpu::BufferUsages::COPY_SRC);

/// z_slice's outputs a walking stage (count_raster, populate) reads.
pub const WALK_INPUTS: [&str; 5] = [
    "slice_instances",
    "slice_counts",
    "slice_draw_args",
    "slice_dispatch_args",
    "cluster_grid",
];

/// z_slice added to a test graph.
pub struct Sliced {
    /// The imported objects.
    pub objects: Handle<Buffer>,
    /// What the pass wrote.
    pub outputs: PassOutputs,
}

impl Sliced {
    /// Adds `pass` over `objects` objects, imported as `objects` (at least one stored: a
    /// zero-length binding is not allowed) and `object_count` (see [`run_frame`]). It
    /// writes its list into `instances` and zeroes `cluster_counts`, both the caller's;
    /// its count words, arguments and grid are created here.
    pub fn add(
        g: &mut GraphBuilder,
        pass: ZSlice,
        objects: usize,
        instances: Handle<Buffer>,
        cluster_counts: Handle<Buffer>,
    ) -> Result<Self> {
        let stored = objects.max(1) as u64;
        let objects = g.import_buffer(
            "objects",
            BufferDesc::array(CLUSTERABLE_OBJECT, stored),
            USAGE,
        );
        let count = g.import_buffer("object_count", BufferDesc::array(Element::U32, 1), USAGE);
        let words = crate::cpu::COUNT_WORDS as u64;
        let slice_counts = g.create_buffer("slice_counts", BufferDesc::array(Element::U32, words));
        let draw = g.create_buffer("slice_draw_args", BufferDesc::array(Element::DRAW_ARGS, 1));
        let dispatch = g.create_buffer(
            "slice_dispatch_args",
            BufferDesc::array(Element::DISPATCH_ARGS, 1),
        );
        let grid = g.create_buffer("cluster_grid", BufferDesc::array(CLUSTER_GRID, 1));
        let bindings = Bindings::new()
            .bind("objects", objects)
            .bind("object_count", count)
            .bind("slice_instances", instances)
            .bind("slice_counts", slice_counts)
            .bind("slice_draw_args", draw)
            .bind("slice_dispatch_args", dispatch)
            .bind("cluster_grid", grid)
            .bind("cluster_counts", cluster_counts);
        let outputs = g.add_pass("z_slice", pass, bindings)?;
        Ok(Self { objects, outputs })
    }

    /// [`Sliced::add`] over the grid `pass` cuts `view` into, with a list long enough for
    /// every object in every slice and a count per froxel and kind, both created: what
    /// the walking stages are tested after. Returns the grid too.
    pub fn add_for_walk(
        g: &mut GraphBuilder,
        pass: ZSlice,
        objects: usize,
        view: &View,
    ) -> Result<(Self, ClusterGrid)> {
        let [w, h] = view.viewport_size.map(|v| v as u32);
        let grid = pass.grid([w, h]);
        let entries = (objects as u64 * u64::from(grid.dims[2])).max(1);
        let instances = g.create_buffer(
            "slice_instances",
            BufferDesc::array(SLICE_INSTANCE, entries),
        );
        let counts = u64::from(grid.cluster_count * ClusterableKind::COUNT);
        let counts = g.create_buffer("cluster_counts", BufferDesc::array(Element::U32, counts));
        Ok((Self::add(g, pass, objects, instances, counts)?, grid))
    }

    /// `bindings` with what a walking stage reads bound: the objects and
    /// [`WALK_INPUTS`].
    pub fn bind_walk(&self, bindings: Bindings) -> Result<Bindings> {
        let mut bindings = bindings.bind("objects", self.objects);
        for name in WALK_INPUTS {
            bindings = bindings.bind(name, self.outputs.buffer(name)?);
        }
        Ok(bindings)
    }

    /// Exports what [`read_written`] reads.
    pub fn export_written(&self, g: &mut GraphBuilder) -> Result<()> {
        self.export(g, &["slice_instances", "slice_counts", "cluster_grid"])
    }

    /// Exports the outputs of these slots, to read them after the frame.
    pub fn export(&self, g: &mut GraphBuilder, slots: &[&str]) -> Result<()> {
        for slot in slots {
            g.export(self.outputs.buffer(slot)?);
        }
        Ok(())
    }
}

/// Compiles `g` for `exec`'s GPU and runs one frame of it seen through `view`: `objects`
/// imported as `objects` (one default object when there are none, as [`Sliced::add`]
/// declares) and `object_count` (`count`), beside the caller's `imports`.
pub fn run_frame(
    exec: &mut Executor,
    g: GraphBuilder,
    objects: &[ClusterableObject],
    count: u32,
    view: &View,
    imports: Imports,
) -> Result<()> {
    let compiled = g.compile(&CompileOptions::for_gpu(&exec.gpu))?;
    let mut padded = objects.to_vec();
    padded.resize(objects.len().max(1), ClusterableObject::default());
    let gpu = &exec.gpu;
    let imports = imports
        .buffer(
            "objects",
            &gpu.buffer_with_data("objects", bytemuck::cast_slice(&padded), USAGE),
        )
        .buffer(
            "object_count",
            &gpu.buffer_with_data("object_count", bytemuck::bytes_of(&count), USAGE),
        );
    let frame = FrameData::new().with(crate::VIEW_INPUT, bytemuck::bytes_of(view));
    exec.execute_frame(&compiled, &imports, &frame)?;
    Ok(())
}

/// An exported buffer after the frame, as values of `T`.
pub fn read<T: bytemuck::Pod>(exec: &mut Executor, name: &str) -> Vec<T> {
    let bytes = exec
        .read_buffer(name)
        .unwrap_or_else(|e| panic!("{name}: {e}"));
    bytemuck::pod_collect_to_vec(&bytes)
}

/// What z_slice published (exported with [`Sliced::export_written`]): the instances it wrote (the first `min(requested, capacity)`) and the
/// grid.
pub fn read_written(exec: &mut Executor) -> (Vec<SliceInstance>, ClusterGrid) {
    let words: Vec<u32> = read(exec, "slice_counts");
    let mut instances: Vec<SliceInstance> = read(exec, "slice_instances");
    instances.truncate(words[WORD_REQUESTED].min(words[WORD_CAPACITY]) as usize);
    let grid: Vec<ClusterGrid> = read(exec, "cluster_grid");
    (instances, grid[0])
}
