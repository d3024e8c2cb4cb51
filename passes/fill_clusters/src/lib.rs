//! Stage `fill_clusters`: the per-frame list of candidate clusters for `cull_lod`.
//! Implementation `workgroup_per_instance` (this module) lists every meshlet (all LOD
//! levels) of every instance the camera may see; implementation `hierarchy`
//! ([`hierarchy`]) walks each visible instance's culling hierarchy and lists only the
//! meshlets of the leaves that may hold clusters of the LOD cut.
//!
//! Culling works per cluster, but most of the scene is usually rejected a whole instance
//! at a time; doing that here keeps the list short. Cluster ids in the visibility buffer
//! index this per-frame list, so its 25 bits bound the clusters of one frame, not the
//! scene. One workgroup per instance reserves its range with one atomic, so the list is
//! built without a prefix sum and each instance's clusters stay together.
//!
//! # Contract
//!
//! | slot            | access             | holds   | |
//! |-----------------|--------------------|---------|---|
//! | `instances`     | storage read       | Instance | the GPU scene's instances; one workgroup each |
//! | `instances_high`| storage read, optional | Instance | the instances past one binding's limit (`meshlight_gpu_scene::instance_table`) |
//! | `meshes`        | storage read       | Mesh    | each instance's mesh bounding sphere |
//! | `clusters`      | storage write      | Cluster | `(instance, meshlet)`; capacity = its size / 8, or the `capacity` param if smaller |
//! | `cluster_count` | cleared read-write | u32 × 2 | `[0]` clusters written = `min([1], capacity)`, `[1]` clusters requested |
//! | `hierarchy_nodes` | storage read, optional | HierarchyNode | the GPU scene's hierarchy nodes (`hierarchy` only) |
//! | `hierarchy_clusters` | storage read, optional | u32 | the leaves' meshlets (`hierarchy` only) |
//! | `hierarchy_roots` | storage read, optional | u32 | per mesh, its root node (`hierarchy` only) |
//! | `hierarchy_counts` | cleared read-write, optional | u32 × 4 (or more) | nodes tested, leaves accepted, subtrees emitted whole, walks unfinished; then nodes hidden, entries tested and passed (`hierarchy` only; [`hierarchy`] says when) |
//!
//! Frame input `view` (`meshlight_shaders::cpu::layout::View`).
//!
//! | param            | default | |
//! |------------------|---------|---|
//! | `capacity`       | 0 (the whole `clusters` buffer) | clusters the list may hold, at most the buffer's |
//! | `instance_count` | 0 (every bound instance) | instances to visit, at most the bound count |
//! | `list`, `lists`  | 0, 1    | the buffers hold `lists` lists side by side and the pass writes list `list` ([`ListPart`]) |
//!
//! # Definitions the tests pin down
//!
//! - An instance is visible when `sphere_in_frustum(view, s.xyz, s.w)` holds for
//!   `s = instance_transform_sphere(instance, mesh.bounding_sphere)` (radius times the
//!   largest axis scale). An invisible instance, or one with no meshlets, requests nothing.
//! - A visible instance requests `meshlet_count` clusters `(i, first_meshlet + k)`,
//!   `k = 0, 1, …` in that order, at `start + k` where `start = atomicAdd(&[1], count)`.
//!   Slots at or past the capacity are not written: the instance straddling the capacity
//!   writes the prefix that fits, later ones nothing. No slot outside `0..capacity` is
//!   touched.
//! - After every workgroup, one thread sets `[0] = min([1], capacity)`; the overflow is
//!   `[1] - [0]`.
//! - Instances are dispatched one workgroup each, as `x × y` workgroups with x under the
//!   per-dimension limit, so any instance count the buffer holds is visited.
//! - [`cpu::cpu_fill`] is the reference (which instances, which clusters, the two words).
//!
//! # Switching a pipeline to `hierarchy`
//!
//! Import the hierarchy buffers (`GpuScene::import_hierarchy`, or
//! `gpu::import_hierarchy_for` before the device exists; `GpuScene::imports` already
//! binds them), add the pass as `HierarchyFill { lod_threshold_px, .. }` with cull's
//! threshold, and bind `hierarchy_counts` to a 4-word buffer to read the counters. In a
//! pipeline file: three imported resources named like the slots (`HierarchyNode`,
//! element size 64; `u32`; `u32`) sized by parameters the renderer sets from
//! `gpu::hierarchy_lengths`, and `implementation = "hierarchy"` with
//! `params = { lod_threshold_px = <cull's> }`.

#![warn(missing_docs)]

pub mod cpu;
pub mod hierarchy;
pub mod hierarchy_cpu;

pub use cpu::{FillResult, cpu_fill};
pub use hierarchy::HierarchyFill;
pub use hierarchy_cpu::{HierarchyWalk, WalkOcclusion, WalkParams, cpu_walk, cpu_walk_with};

use meshlight_gpu_scene::ListPart;
use meshlight_gpu_scene::gpu::elements;
use meshlight_gpu_scene::instance_table::{self, InstanceTable};
use meshlight_gpu_scene::view::frame_view;
use meshlight_graph::prelude::*;

/// The stage name pipelines use.
pub const STAGE: &str = "fill_clusters";
/// The implementation name pipelines use.
pub const IMPLEMENTATION: &str = "workgroup_per_instance";
/// The frame input holding the `View`.
pub const VIEW_INPUT: &str = "view";

/// `workgroup_per_instance`'s WGSL with its uniform block and the list module, public so
/// the shader tests compose and validate every entry point.
pub const SHADER: PassShader = pass_shader!(
    "fill_clusters::fill",
    "fill.wgsl",
    params: GpuParams,
    modules: [("fill_clusters::list", "list.wgsl")]
);

/// The depth pyramid's slot (`hierarchy` with occlusion).
pub const PYRAMID_SLOT: &str = "pyramid";
/// The first pass's output: the nodes the pyramid hid.
pub const OCCLUDED_NODES_SLOT: &str = "occluded_nodes";
/// The first pass's count words for it: `[0]` written, `[1]` found.
pub const OCCLUDED_NODE_COUNT_SLOT: &str = "occluded_node_count";
/// The second pass's input: the same list, bound under another name.
pub const CANDIDATE_NODES_SLOT: &str = "candidate_nodes";
/// The second pass's count words of that list: the first pass's `occluded_node_count`.
pub const CANDIDATE_NODE_COUNT_SLOT: &str = "candidate_node_count";
/// An entry of the hidden-node list: `(instance, node, 1)`, three u32 (the walk's
/// `Subtree`).
pub const HIDDEN_NODE: Element = Element::named("HiddenNode", 12);
/// The frame input (u32) a first pass with a pyramid reads: non-zero when the camera
/// jumped, so last frame's depth cannot hide anything (`cull_lod`'s).
pub const CAMERA_CUT_INPUT: &str = "camera_cut";

/// The slots every implementation of `fill_clusters` shares.
pub fn contract() -> StageContract {
    StageContract {
        stage: STAGE,
        slots: vec![
            Slot::read("instances", elements::INSTANCE, "the scene's instances"),
            instance_table::high_slot(),
            Slot::read("meshes", elements::MESH, "the scene's meshes (bounding spheres)"),
            Slot::buffer(
                "clusters",
                Access::StorageWrite,
                elements::CLUSTER,
                "(instance, meshlet) of every visible instance's meshlets, below the capacity",
            ),
            Slot::buffer(
                "cluster_count",
                Access::ClearedReadWrite,
                Element::U32,
                "[0] clusters written = min(requested, capacity), [1] clusters requested",
            ),
            Slot::read(
                "hierarchy_nodes",
                elements::HIERARCHY_NODE,
                "the scene's culling-hierarchy nodes (implementation `hierarchy`)",
            )
            .optional(),
            Slot::read(
                "hierarchy_clusters",
                Element::U32,
                "the hierarchy leaves' meshlets (implementation `hierarchy`)",
            )
            .optional(),
            Slot::read(
                "hierarchy_roots",
                Element::U32,
                "per mesh, its hierarchy's root node (implementation `hierarchy`)",
            )
            .optional(),
            Slot::buffer(
                "hierarchy_counts",
                Access::ClearedReadWrite,
                Element::U32,
                "nodes tested, leaves accepted, subtrees emitted whole, walks unfinished, nodes hidden",
            )
            .optional(),
        ],
    }
}

/// The `hierarchy` implementation's slots: the stage's, and those of occlusion per node.
/// `workgroup_per_instance` has no occlusion slots, so a `pyramid` in the pipeline is
/// not bound to it by name (and binding one to it is an unknown-slot error).
pub fn hierarchy_contract() -> StageContract {
    let mut c = contract();
    c.slots.extend([
            Slot::texture(
                PYRAMID_SLOT,
                Access::Sampled,
                Some(wgpu::TextureFormat::R32Float),
                "depth pyramid (`hierarchy`): last frame's in the first pass, this frame's in the second",
            )
            .optional(),
            Slot::buffer(
                OCCLUDED_NODES_SLOT,
                Access::StorageWrite,
                HIDDEN_NODE,
                "first pass: (instance, node, 1) of every node the pyramid hid, three words each",
            )
            .optional(),
            Slot::buffer(
                OCCLUDED_NODE_COUNT_SLOT,
                Access::ClearedReadWrite,
                Element::U32,
                "first pass: [0] hidden nodes written, [1] found",
            )
            .optional(),
            Slot::read(
                CANDIDATE_NODES_SLOT,
                HIDDEN_NODE,
                "second pass: the first pass's hidden nodes, where the walk starts",
            )
            .optional(),
            Slot::read(
                CANDIDATE_NODE_COUNT_SLOT,
                Element::U32,
                "second pass: the first pass's hidden-node count",
            )
            .optional(),
    ]);
    c
}

/// The `workgroup_per_instance` implementation.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct FillClusters {
    /// Clusters the list may hold; `None`: as many as the `clusters` buffer holds.
    pub capacity: Option<u32>,
    /// Instances to visit; `None`: every instance the `instances` buffer holds.
    pub instance_count: Option<u32>,
    /// The list of the buffers it writes.
    pub part: ListPart,
}

uniform_block! {
    /// The uniform of fill.wgsl, which imports the struct from this declaration.
    struct GpuParams as "Params" in "fill_clusters::fill_params" {
        /// Clusters the list may hold; the shader also clamps it to the bound list's length.
        capacity: u32,
        /// Instances to visit (at most the bound instance count).
        instance_count: u32,
        /// x size of the dispatch, to linearise the workgroup id.
        groups_x: u32,
        /// The list written ([`ListPart`]).
        list: u32,
        /// The lists the buffers hold.
        lists: u32,
        pad_a: u32,
        pad_b: u32,
        pad_c: u32,
    }
}

const PARAM_KEYS: [&str; 4] = ["capacity", "instance_count", "list", "lists"];

impl FillClusters {
    /// Reads `capacity` and `instance_count` (0 or absent: the bound buffer's size), and
    /// `list` and `lists` ([`ListPart`]).
    pub fn from_params(params: &Params) -> Result<Self> {
        params.only(&PARAM_KEYS)?;
        let nonzero = |v: u32| (v > 0).then_some(v);
        Ok(Self {
            capacity: nonzero(params.u32("capacity", 0)?),
            instance_count: nonzero(params.u32("instance_count", 0)?),
            part: ListPart::from_params(params, 1)?,
        })
    }
}

/// The instances a fill visits (`instance_count`, else as many as the `instances` buffer
/// holds) and a workgroup per instance laid out under the adapter's per-dimension limit.
pub(crate) struct InstanceGrid {
    pub instance_count: u32,
    pub groups: [u32; 2],
    /// The adapter's workgroups per dimension.
    pub limit: u32,
}

pub(crate) fn instance_grid(
    ctx: &RecordContext<'_>,
    instance_count: Option<u32>,
) -> Result<InstanceGrid> {
    let bound = instance_table::bound_instances(ctx)?;
    let instance_count = instance_count.unwrap_or(bound).min(bound);
    let limit = ctx.device().limits().max_compute_workgroups_per_dimension;
    let groups = workgroup_grid(instance_count, limit);
    if groups[1] > limit {
        return Err(GraphError::Record {
            pass: ctx.pass_name().to_string(),
            message: format!(
                "{instance_count} instances need more than {limit}² workgroups; set `instance_count` lower"
            ),
        });
    }
    Ok(InstanceGrid {
        instance_count,
        groups,
        limit,
    })
}

/// Declares a compute program for each of `entries` in `shader`, all composed with
/// `defs` and the instance table's under one `layout`, and records those defs as the
/// pass's: an implementation's kernels run one variant and share its bindings.
pub(crate) fn instance_programs(
    ctx: &mut SetupContext,
    shader: &'static PassShader,
    entries: &[&'static str],
    layout: BindingLayout,
    defs: &impl ShaderDefs,
) {
    let table = InstanceTable::of(ctx);
    ctx.shader_defs(defs);
    ctx.shader_defs(&table);
    for &entry in entries {
        ctx.program(
            entry,
            ProgramDesc::compute(shader, entry)
                .defs(defs)
                .defs(&table)
                .layout(layout.clone()),
        );
    }
}

/// `n` workgroups as `[x, y]` with both under `limit` (x as wide as allowed).
pub fn workgroup_grid(n: u32, limit: u32) -> [u32; 2] {
    let x = n.min(limit.max(1));
    let y = if x == 0 { 0 } else { n.div_ceil(x) };
    [x, y]
}

impl Pass for FillClusters {
    fn implementation(&self) -> Implementation {
        Implementation::new(IMPLEMENTATION, contract())
    }
    fn setup(&self, ctx: &mut SetupContext) -> Result<()> {
        ctx.min_bytes("cluster_count", self.part.count_bytes());
        ctx.frame_input(VIEW_INPUT);
        let layout = BindingLayout::from_shader("fill_clusters");
        instance_programs(ctx, &SHADER, &["prepare", "fill", "finish"], layout, &());
        Ok(())
    }
    fn record(&self, ctx: &mut RecordContext<'_>) -> Result<()> {
        let view = frame_view(ctx, VIEW_INPUT, None)?;
        let InstanceGrid {
            instance_count,
            groups: [x, y],
            ..
        } = instance_grid(ctx, self.instance_count)?;
        let params = GpuParams {
            capacity: self.capacity.unwrap_or(u32::MAX),
            instance_count,
            groups_x: x,
            list: self.part.list,
            lists: self.part.lists,
            ..GpuParams::default()
        };
        let uniforms: [(&str, &[u8]); 2] = [
            ("view", bytemuck::bytes_of(&view)),
            ("params", bytemuck::bytes_of(&params)),
        ];
        if self.part.lists == 1 {
            ctx.clear("cluster_count")?;
        } else {
            // Only this pass's list's words: the other lists may be another view's.
            ctx.dispatch_compute("prepare", &uniforms, Workgroups::Direct([1, 1, 1]))?;
        }
        ctx.dispatch_compute("fill", &uniforms, Workgroups::Direct([x, y, 1]))?;
        // A second dispatch (dependent, so wgpu puts a barrier before it): the requested
        // count is final when it is read.
        ctx.dispatch_compute("finish", &uniforms, Workgroups::Direct([1, 1, 1]))
    }
}

/// Registers `fill_clusters` (implementations `workgroup_per_instance` and `hierarchy`)
/// for pipeline files.
pub fn register(registry: &mut Registry) {
    registry.register(STAGE, IMPLEMENTATION, FillClusters::from_params);
    registry.register(STAGE, hierarchy::IMPLEMENTATION, HierarchyFill::from_params);
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn grids_cover_every_instance_under_the_limit() {
        for limit in [1u32, 3, 65_535] {
            for n in [0u32, 1, 2, limit, limit + 1, 3 * limit + 2, 100_000] {
                let [x, y] = workgroup_grid(n, limit);
                assert!(x <= limit, "{n} under {limit}");
                assert!(x as u64 * y as u64 >= n as u64, "{n} under {limit}");
                assert!(n == 0 || (x as u64 * y as u64) < n as u64 + x as u64);
            }
        }
    }

    #[test]
    fn params_are_read_and_misspellings_refused() {
        let mut registry = Registry::new();
        register(&mut registry);
        let pipeline = |params: &str| {
            let text = format!(
                r#"
[[resource]]
name = "instances"
kind = "imported"
buffer = {{ element = "Instance", element_size = 224, count = 4 }}
usage = ["STORAGE"]
[[resource]]
name = "meshes"
kind = "imported"
buffer = {{ element = "Mesh", element_size = 64, count = 1 }}
usage = ["STORAGE"]
[[resource]]
name = "clusters"
kind = "exported"
buffer = {{ element = "Cluster", element_size = 8, count = 100 }}
[[resource]]
name = "cluster_count"
kind = "exported"
buffer = {{ element = "u32", count = 2 }}
[[pass]]
name = "fill"
stage = "fill_clusters"
implementation = "workgroup_per_instance"
params = {{ {params} }}
"#
            );
            meshlight_graph::file::parse_pipeline(&text, "test.toml", &registry).map(|_| ())
        };
        meshlight_testing::assert_params(
            pipeline,
            &["capacity = 10, instance_count = 3"],
            &[("capcity = 10", "capcity"), ("capacity = -1", "capacity")],
        );
    }
}
