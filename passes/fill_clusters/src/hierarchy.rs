//! Implementation `hierarchy` of `fill_clusters`: the candidate list from a walk of each
//! visible instance's culling hierarchy (`meshlight_scene::hierarchy`), so that the list,
//! and `cull_lod`'s work after it, grow with what is on screen instead of with every
//! meshlet of every level.
//!
//! The contract is the stage's, with the optional slots bound: `hierarchy_nodes`,
//! `hierarchy_clusters` and `hierarchy_roots` (the GPU scene's, from
//! `GpuScene::import_hierarchy`), and `hierarchy_counts` if the caller wants the
//! counters (otherwise a scratch buffer holds them). The list holds a superset of the LOD
//! cut: every meshlet of every accepted leaf, each written once, as
//! `(instance, meshlet)` like `workgroup_per_instance`'s, with the same overflow words
//! (`cluster_count[1]` requested, `[0] = min([1], capacity)`). `cull_lod` after it then
//! finds exactly the cut it finds after `workgroup_per_instance` (the tests compare them).
//!
//! | param              | default | |
//! |--------------------|---------|---|
//! | `capacity`         | 0 (the whole `clusters` buffer) | clusters the list may hold |
//! | `instance_count`   | 0 (every bound instance) | instances to visit |
//! | `lod_threshold_px` | 1.0     | must equal `cull_lod`'s: a larger or smaller one drops clusters of the cut |
//! | `queue_capacity`   | 0 ([`QUEUE`]) | nodes one round's frontier holds, at most [`QUEUE`] |
//!
//! `hierarchy_counts`: `[0]` nodes tested, `[1]` leaves accepted, `[2]` subtrees emitted
//! whole because a frontier was full, `[3]` instances whose walk hit the round limit
//! (0 unless the data is damaged). Clusters + nodes tested = `cluster_count[1] + [0]`.
//!
//! # The walk
//!
//! One workgroup per instance, like `workgroup_per_instance`: the root's test (frustum
//! and LOD) is the instance test, so a culled instance costs one node. The walk is
//! breadth-first with two frontiers in workgroup memory; each round tests its frontier 64
//! nodes at a time; an accepted leaf emits its meshlets, an accepted inner node appends
//! its children to the next frontier. A frontier that would overflow emits the children
//! that do not fit whole (their meshlets are one range of the depth-first cluster list),
//! so a full queue costs pruning, never a cluster of the cut.
//!
//! Why a workgroup per instance and not a global work queue: a queue shared by all
//! workgroups needs persistent threads that wait for each other's work, which assumes
//! workgroups make progress together — lavapipe and other drivers give no such promise,
//! and a wrong guess hangs the device. One dispatch per tree level driven by indirect
//! arguments needs no such promise but costs two dependent dispatches per level (about
//! 4 µs on an H200, DESIGN §9) over the 15 to 25 levels of the chain and the level trees:
//! more than the whole walk. A workgroup owns its instance's walk, needs no inter-group
//! synchronisation and takes one dispatch; its limit is a single huge instance close up,
//! whose walk runs on one compute unit (the scenes the renderer draws have thousands).
//!
//! # Measured
//!
//! The benchmark's 15³ bunny lattice at 2240×1260, threshold 1 px (`cpu_walk` and
//! lavapipe give the same counts; `examples/walk_vs_flat.rs` and the test
//! `on_the_bunny_lattice_clusters_and_nodes_tested_stay_within_three_times_the_cut`):
//! the flat fill lists 3,771,520 clusters for a cut of 123,090 (30.6×); the walk tests
//! 81,477 nodes and lists 148,255 clusters, 229,732 tests in all, 1.87× the cut. On
//! lavapipe (two CPU cores shared with other work, so only the order of magnitude
//! holds) fill + cull takes about 0.6 s flat and 0.17–0.4 s with the walk; no GPU figure
//! has been taken yet.
//!
//! # Why skipping is exact
//!
//! `node_visible` compares the node's bounds as `cull_lod` compares each cluster's
//! (frustum, own error imperceptible, parent error perceptible), with the node's sphere
//! and errors bounding every cluster below (`meshlight_scene::hierarchy` says why), and
//! each comparison moved toward keeping by a slack of 2^-13 of the magnitudes involved
//! (the translation, the camera position, the sphere), far above the f32 rounding of the
//! transform and the projection on any GPU. So a skipped node holds no cluster of the
//! cut, and `cull_lod` after this list keeps exactly the clusters it keeps after the flat
//! list. [`crate::hierarchy_cpu`] mirrors the shader.

use crate::{STAGE, VIEW_INPUT, contract, workgroup_grid};
use meshlight_gpu_scene::view::frame_view;
use meshlight_graph::file::Params;
use meshlight_graph::{
    Access, BindingLayout, BufferDesc, Element, GraphError, Pass, ProgramDesc, RecordContext,
    Result, SetupContext, StageContract,
};
use meshlight_shaders::cpu::layout::Instance;
use meshlight_shaders::{PassShader, pass_shader};

/// The implementation name pipelines use.
pub const IMPLEMENTATION: &str = "hierarchy";

pub const SHADER: PassShader = pass_shader!("fill_clusters::hierarchy", "hierarchy.wgsl");

/// Nodes a frontier holds in workgroup memory (`QUEUE` in the shader).
pub const QUEUE: u32 = 1024;
/// Rounds after which a walk stops and counts itself unfinished (`MAX_ROUNDS`).
pub const MAX_ROUNDS: u32 = 256;
/// The slack of a node test, relative to the magnitudes it combines (`SLACK`).
pub const SLACK: f32 = 1.0 / 8192.0;

/// The slots the walk reads, besides the stage's own.
pub const DATA_SLOTS: [&str; 3] = ["hierarchy_nodes", "hierarchy_clusters", "hierarchy_roots"];
/// The counters' slot; a scratch buffer when it is left unbound.
pub const COUNTS_SLOT: &str = "hierarchy_counts";

/// The `hierarchy` implementation.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HierarchyFill {
    /// Clusters the list may hold; `None`: as many as the `clusters` buffer holds.
    pub capacity: Option<u32>,
    /// Instances to visit; `None`: every instance the `instances` buffer holds.
    pub instance_count: Option<u32>,
    /// Pixels of error the cut may show: `cull_lod`'s `lod_threshold_px`.
    pub lod_threshold_px: f32,
    /// Nodes a frontier holds; `None`: [`QUEUE`].
    pub queue_capacity: Option<u32>,
}

impl Default for HierarchyFill {
    fn default() -> Self {
        Self {
            capacity: None,
            instance_count: None,
            lod_threshold_px: 1.0,
            queue_capacity: None,
        }
    }
}

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct GpuParams {
    capacity: u32,
    instance_count: u32,
    groups_x: u32,
    queue_capacity: u32,
    lod_threshold_px: f32,
    _pad: [u32; 3],
}

const PARAM_KEYS: [&str; 4] = [
    "capacity",
    "instance_count",
    "lod_threshold_px",
    "queue_capacity",
];

impl HierarchyFill {
    /// Reads the params of the table in the module docs.
    pub fn from_params(params: &Params) -> Result<Self> {
        params.only(&PARAM_KEYS)?;
        let nonzero = |v: u32| (v > 0).then_some(v);
        let pass = Self {
            capacity: nonzero(params.u32("capacity", 0)?),
            instance_count: nonzero(params.u32("instance_count", 0)?),
            lod_threshold_px: params.f32("lod_threshold_px", 1.0)?,
            queue_capacity: nonzero(params.u32("queue_capacity", 0)?),
        };
        pass.check()?;
        Ok(pass)
    }

    fn check(&self) -> Result<()> {
        let t = self.lod_threshold_px;
        if !(t.is_finite() && t >= 0.0) {
            return Err(GraphError::parameter(format!(
                "`lod_threshold_px` = {t} must be a finite number of pixels >= 0 (cull_lod's)"
            )));
        }
        if let Some(q) = self.queue_capacity
            && q > QUEUE
        {
            return Err(GraphError::parameter(format!(
                "`queue_capacity` = {q} is above the {QUEUE} nodes a frontier holds; leave it out for {QUEUE}"
            )));
        }
        Ok(())
    }
}

impl Pass for HierarchyFill {
    fn contract(&self) -> StageContract {
        contract()
    }
    fn implementation(&self) -> &'static str {
        IMPLEMENTATION
    }
    fn setup(&self, ctx: &mut SetupContext) -> Result<()> {
        self.check()?;
        if let Some(slot) = DATA_SLOTS.iter().find(|s| !ctx.is_bound(s)) {
            return Err(GraphError::parameter(format!(
                "`{STAGE}` implementation `{IMPLEMENTATION}` walks the culling hierarchy: bind slot `{slot}` to the GPU scene's buffer of that name (GpuScene::import_hierarchy, or gpu::import_hierarchy_for)"
            )));
        }
        ctx.min_bytes("cluster_count", 8);
        ctx.frame_input(VIEW_INPUT);
        let mut layout = BindingLayout::compute("fill_clusters::hierarchy")
            .slot(0, "instances")
            .slot(1, "clusters")
            .slot(2, "cluster_count")
            .uniform(3)
            .uniform(4)
            .slot(5, "hierarchy_nodes")
            .slot(6, "hierarchy_clusters")
            .slot(7, "hierarchy_roots");
        if ctx.is_bound(COUNTS_SLOT) {
            ctx.min_bytes(COUNTS_SLOT, 16);
            layout = layout.slot(8, COUNTS_SLOT);
        } else {
            ctx.scratch_buffer(
                COUNTS_SLOT,
                BufferDesc::array(Element::U32, 4),
                &[Access::ClearedReadWrite],
            );
            layout = layout.scratch(8, COUNTS_SLOT, Access::ClearedReadWrite);
        }
        for entry in ["prepare", "fill", "finish"] {
            ctx.program(
                entry,
                ProgramDesc::compute(&SHADER, entry).layout(layout.clone()),
            );
        }
        Ok(())
    }
    fn record(&self, ctx: &mut RecordContext<'_>) -> Result<()> {
        let view = frame_view(ctx, VIEW_INPUT, None)?;
        let (_, instance_bytes) = ctx.buffer("instances")?;
        let bound = (instance_bytes / size_of::<Instance>() as u64).min(u32::MAX as u64) as u32;
        let instance_count = self.instance_count.unwrap_or(bound).min(bound);
        let limit = ctx.device().limits().max_compute_workgroups_per_dimension;
        let [x, y] = workgroup_grid(instance_count, limit);
        if y > limit {
            return Err(GraphError::Record {
                pass: ctx.pass_name().to_string(),
                message: format!(
                    "{instance_count} instances need more than {limit}² workgroups; set `instance_count` lower"
                ),
            });
        }
        let params = GpuParams {
            capacity: self.capacity.unwrap_or(u32::MAX),
            instance_count,
            groups_x: x,
            queue_capacity: self.queue_capacity.unwrap_or(QUEUE).min(QUEUE),
            lod_threshold_px: self.lod_threshold_px,
            _pad: [0; 3],
        };
        let uniforms: [(u32, &[u8]); 2] = [
            (3, bytemuck::bytes_of(&view)),
            (4, bytemuck::bytes_of(&params)),
        ];
        // Three dispatches, each in its own compute pass so the next sees its writes:
        // the counters zeroed, the walks, the written count.
        for (entry, grid) in [("prepare", [1, 1]), ("fill", [x, y]), ("finish", [1, 1])] {
            let program = ctx.compute(entry)?;
            let group = ctx.bind_group(&program, 0, &uniforms)?;
            let mut pass = ctx.compute_pass();
            pass.set_pipeline(&program.pipeline);
            pass.set_bind_group(0, &group, &[]);
            if grid[0] > 0 {
                pass.dispatch_workgroups(grid[0], grid[1], 1);
            }
        }
        Ok(())
    }
}

pub(crate) fn build(params: &Params) -> Result<Box<dyn Pass>> {
    Ok(Box::new(HierarchyFill::from_params(params)?))
}

#[cfg(test)]
mod tests {
    use super::*;
    use meshlight_scene::asset::format::NodeRecord;
    use meshlight_shaders::{Capabilities, ShaderLibrary};

    /// The GPU scene uploads the asset's node records as they are: the WGSL struct must
    /// have their size and field offsets, and the shader's constants the Rust ones.
    #[test]
    fn the_wgsl_node_is_the_asset_record_and_the_constants_agree() {
        let mut lib = ShaderLibrary::new(Capabilities::empty()).unwrap();
        let module = lib.compose(&SHADER, &[]).unwrap();
        let node = module
            .types
            .iter()
            .find(|(_, t)| t.name.as_deref() == Some("HierarchyNode"))
            .map(|(_, t)| t)
            .expect("HierarchyNode in the shader");
        let naga::TypeInner::Struct { members, span } = &node.inner else {
            panic!("HierarchyNode is not a struct");
        };
        assert_eq!(*span as usize, size_of::<NodeRecord>());
        let offsets: Vec<(String, u32)> = members
            .iter()
            .map(|m| (m.name.clone().unwrap_or_default(), m.offset))
            .collect();
        let want = [
            ("bounds", std::mem::offset_of!(NodeRecord, bounds)),
            ("lod_sphere", std::mem::offset_of!(NodeRecord, lod_sphere)),
            ("min_error", std::mem::offset_of!(NodeRecord, min_error)),
            (
                "max_parent_error",
                std::mem::offset_of!(NodeRecord, max_parent_error),
            ),
            ("first_child", std::mem::offset_of!(NodeRecord, first_child)),
            ("child_count", std::mem::offset_of!(NodeRecord, child_count)),
            (
                "first_cluster",
                std::mem::offset_of!(NodeRecord, first_cluster),
            ),
            (
                "cluster_count",
                std::mem::offset_of!(NodeRecord, cluster_count),
            ),
            ("reserved", std::mem::offset_of!(NodeRecord, reserved)),
        ];
        let want: Vec<(String, u32)> = want
            .iter()
            .map(|(n, o)| (n.to_string(), *o as u32))
            .collect();
        assert_eq!(offsets, want);
        let constant = |name: &str| -> f64 {
            let line = SHADER
                .source
                .lines()
                .find(|l| l.starts_with(&format!("const {name}:")))
                .unwrap_or_else(|| panic!("no const {name}"));
            let text = line.split('=').nth(1).unwrap().trim();
            text.trim_end_matches(';')
                .trim_end_matches('u')
                .parse()
                .unwrap()
        };
        assert_eq!(constant("QUEUE"), QUEUE as f64);
        assert_eq!(constant("MAX_ROUNDS"), MAX_ROUNDS as f64);
        assert_eq!(constant("SLACK"), SLACK as f64);
    }

    #[test]
    fn params_are_read_and_bad_ones_refused() {
        use meshlight_graph::file::Registry;
        let mut registry = Registry::new();
        crate::register(&mut registry);
        let pass = |params: &str| {
            let text = format!(
                "[[pass]]\nname = \"fill\"\nstage = \"fill_clusters\"\nimplementation = \"hierarchy\"\nparams = {{ {params} }}\n"
            );
            meshlight_graph::file::parse_pipeline(&text, "test.toml", &registry).map(|_| ())
        };
        match pass("lod_threshold_px = 2.0, queue_capacity = 16, capacity = 100") {
            Ok(()) | Err(GraphError::UnboundSlot { .. }) => {}
            Err(e) => panic!("{e}"),
        }
        for (params, key) in [
            ("lod_threshold_px = -1.0", "lod_threshold_px"),
            ("queue_capacity = 5000", "queue_capacity"),
            ("queu_capacity = 4", "queu_capacity"),
        ] {
            match pass(params) {
                Err(GraphError::Parameter { message, .. }) => {
                    assert!(message.contains(key), "{message}")
                }
                other => panic!("{params}: {:?}", other.err()),
            }
        }
    }
}
