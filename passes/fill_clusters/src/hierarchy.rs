//! Implementation `hierarchy` of `fill_clusters`: the candidate list from a walk of each
//! visible instance's culling hierarchy (`meshlight_scene::hierarchy`), so that the list,
//! and `cull_lod`'s work after it, grow with what is on screen instead of with every
//! meshlet of every level.
//!
//! The contract is the stage's, with the optional slots bound: `hierarchy_nodes`,
//! `hierarchy_clusters` and `hierarchy_roots` (the GPU scene's, from
//! `GpuScene::import_hierarchy`), and `hierarchy_counts` if the caller wants the
//! counters (otherwise a scratch buffer holds them); plus the occlusion slots of
//! [`crate::hierarchy_contract`]: `pyramid`, and `occluded_nodes` and
//! `occluded_node_count` for a first walk, `candidate_nodes` and `candidate_node_count`
//! for a second (see [`HierarchyFill::phase`]). The list holds a superset of the LOD
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
//! | `queue_capacity`   | 0 ([`QUEUE`]) | nodes one round's frontier holds, at most [`QUEUE`] (a spreading step's at most 64) |
//! | `spread_steps`     | [`SPREAD_STEPS`] | steps that hand wide walks on to more workgroups, at most [`MAX_STEPS`]; 0: one workgroup per instance walks it all |
//! | `subtree_capacity` | 0 ([`SUBTREE_CAPACITY`]) | entries each step's list of handed-on subtrees holds |
//! | `spread_groups`    | 0 ([`SPREAD_GROUPS`]) | workgroups of each step after the first |
//! | `mode`             | `"first"` | `first`: the walk from every instance's root (with a pyramid, hidden nodes go to `occluded_nodes`); `second`: the walk from the first's hidden nodes against this frame's pyramid |
//! | `occlusion_min_clusters` | [`OCCLUSION_MIN_CLUSTERS`] | with a pyramid, inner nodes with fewer meshlets below are not tested for occlusion (a walk's entries always are) |
//! | `views`            | 1       | views one walk serves, at most [`MAX_VIEWS`]: see "One walk for several views" |
//! | `occlusion_view`   | 0       | with several views and a pyramid, the view the pyramid is of (the others test no occlusion) |
//! | `list`, `lists`    | 0, `views` | the buffers hold `lists` lists and view v's is `list + v` ([`meshlight_gpu_scene::ListPart`]) |
//!
//! `hierarchy_counts`: `[0]` nodes tested, `[1]` leaves accepted, `[2]` subtrees emitted
//! whole because a frontier and the next step's list were full, `[3]` walks (of an
//! instance or of a handed-on subtree) that hit the round limit (0 unless the data is
//! damaged). Every node is tested by exactly one workgroup, so `[0]` and `[1]` do not
//! depend on how the walk was split. With a pyramid, `[4]` counts the nodes it hid
//! ([`OCCLUSION_COUNT_WORDS`]). With room for [`ENTRY_COUNT_WORDS`], `[5]` and `[6]` count
//! the walk's entries tested and passed: the first walk's are the instances' roots (so
//! instances tested and visible), the second's the hidden nodes it starts from.
//! Clusters + nodes tested = `cluster_count[1] + [0]`.
//!
//! # The walk
//!
//! Breadth-first, with two frontiers in workgroup memory, two levels a round: each round
//! tests its frontier 64 nodes at a time, and the thread that accepts an inner node tests
//! its children at once; an accepted leaf emits its meshlets, an accepted inner child
//! appends its children to the next frontier. The nodes tested are those of a
//! level-by-level walk, but each round waits on the round before (a dependent load, two
//! barriers, a global reservation), and a walk is latency-bound: the frontiers of the
//! scenes measured stay within one or two chunks, so halving the rounds is what shortens
//! it. The root's test (frustum and LOD) is the instance test, so a culled instance costs
//! one node: the roots are tested first, a thread each (`roots`), and the same thread
//! tests a passing root's children: an accepted leaf child emits its meshlets there, and
//! only the children of an accepted inner child reach a workgroup. The root's children
//! are the roots leaf (the coarsest meshlets) and the chain of finer levels
//! (`meshlight_scene::hierarchy`), so an instance far enough that its cut is its
//! coarsest meshlets costs one thread and no workgroup: the far cascade of the sun's
//! shadow over the million bunnies walks 57,774 such instances, and its walk went from
//! 0.631 to 0.517 ms on an H200 (docs/BENCHMARKS.md, "The sun's shadow", has the
//! camera's frames before and after).
//!
//! The walk is split over `spread_steps + 1` dispatches so that its cost follows the
//! work, not the instance: step 0 is one workgroup per accepted inner child of a root
//! (in the second walk, of a hidden node), starting at its children;
//! step k ≥ 1 is `spread_groups` workgroups striding over the list of subtrees step
//! k − 1 handed on. In a spreading step (all but the last) a frontier holds one chunk
//! (64 nodes, so a round is one pass of tests and two barriers); an accepted node's
//! children that do not fit are handed on as one list entry `(instance, first child,
//! count)`. So a bunny of the lattice, whose frontiers stay under a chunk, is walked by
//! its step-0 workgroup as before, while a terrain seen from nearby keeps one chunk per
//! round in its own workgroup and hands every wider part on: at step 1 its walk runs on
//! as many workgroups as it handed entries on (up to one per accepted node of a
//! round), and each further step spreads again what stays wide. The last step walks
//! each entry to the end with a frontier of `queue_capacity`, and there, or when a list
//! is full, the children that do not fit are emitted whole (their meshlets are one range
//! of the depth-first cluster list), so a full queue costs pruning, never a cluster of
//! the cut.
//!
//! Rounds on the critical path (`HierarchyWalk::rounds`, the reference's count; a level
//! by level walk needs about twice as many): the 15³ bunny lattice 6; a terrain of
//! 524,288 triangles (the default scene's ground) seen from 1.5 units above it, 8
//! unspread (16 level by level), 7 + 2 spread (2 subtrees handed on), and from far away
//! 4 (7 level by level). So on these scenes the gain is the halved rounds, while a step
//! costs a dispatch and may add a round: the spreading pays for an instance whose
//! frontier spans many chunks (a denser ground, a larger viewport), where step 1 runs
//! each handed-on part on its own compute unit instead of queueing them behind one.
//!
//! Why not one global work queue: workgroups that wait for work pushed by others assume
//! that workgroups make progress together — lavapipe and other drivers give no such
//! promise, and a wrong guess hangs the device. Here a step reads only the list the
//! previous dispatch finished. One dispatch per tree level costs two dependent dispatches
//! per level (about 4 µs on an H200: docs/BENCHMARKS.md, graph-floor) over the 15 to 25
//! levels of the chain and the level trees: more than the whole walk; a few spreading
//! steps cost one dispatch each. The written word `cluster_count[0]` is summed by the reservations themselves
//! (each adds its part below the capacity), so no dispatch follows the walk: the chain
//! is `prepare` (the counters zeroed), `roots`, `walk_dispatch` (step 0's indirect
//! arguments) and `spread_steps + 1` walks.
//!
//! # One walk for several views
//!
//! With `views` > 1 the frame input `view` holds that many Views back to back (a sun's
//! shadow cascades), and the walk serves them all: an entry of a frontier or a list
//! carries, in the top four bits of its node id, the views it is walked for; a node is
//! tested against each of those views (the same `node_visible` test, per view) and the
//! walk goes on below it for the views that accept it; an accepted leaf's meshlets are
//! written to the list of each view that accepted it. So view v's list holds exactly
//! what a walk of view v alone lists (the tests compare them, and the cut after), while
//! a node several views want is loaded and transformed once, and the views share one
//! chain of dispatches instead of one chain each. A view given an empty viewport (a
//! zeroed View) is left out: its list stays empty.
//!
//! A first walk over several views may test occlusion for one of them,
//! `occlusion_view` (the camera walked with the sun's cascades): a node that view's
//! pyramid hides goes to `occluded_nodes` as in a walk of that view alone, and the walk
//! goes on below it for the other views that accepted it. So the view's list and its
//! hidden nodes are those of its own walk, and the second walk (one view) is unchanged.
//!
//! # Measured
//!
//! The benchmark's 15³ bunny lattice at 2240×1260, threshold 1 px (`cpu_walk` and
//! lavapipe give the same counts; `examples/walk_vs_flat.rs` and the test
//! `on_the_bunny_lattice_clusters_and_nodes_tested_stay_within_three_times_the_cut`):
//! the flat fill lists 3,771,520 clusters for a cut of 123,090 (30.6×); the walk tests
//! 81,477 nodes and lists 148,255 clusters, 229,732 tests in all, 1.87× the cut. On
//! lavapipe (two CPU cores shared with other work, so only the order of magnitude
//! holds) fill + cull takes about 0.6 s flat and 0.17–0.4 s with the walk. On an H200
//! the walk of one workgroup per instance and a level a round took 0.091 ms on this
//! lattice and 0.167 ms on the default scene (1,024 knots and the ground, 1920×1080);
//! the two-level rounds and the spreading step have not been timed on a GPU yet.
//!
//! # Why skipping is exact
//!
//! `node_visible` compares the node's bounds as `cull_lod` compares each cluster's
//! (frustum, own error imperceptible, parent error perceptible; the projected error and
//! the comparison are `meshlight::view`'s `error_to_pixels` and `meshlight::meshlet`'s
//! `error_perceptible`, which `lod_cut` uses too), with the node's sphere
//! and errors bounding every cluster below (`meshlight_scene::hierarchy` says why), and
//! each comparison moved toward keeping by a slack of 2^-13 of the magnitudes involved
//! (the translation, the camera position, the sphere), far above the f32 rounding of the
//! transform and the projection on any GPU. So a skipped node holds no cluster of the
//! cut, and `cull_lod` after this list keeps exactly the clusters it keeps after the flat
//! list. [`crate::hierarchy_cpu`] mirrors the shader.

use crate::{
    CAMERA_CUT_INPUT, CANDIDATE_NODE_COUNT_SLOT, CANDIDATE_NODES_SLOT, InstanceGrid,
    OCCLUDED_NODE_COUNT_SLOT, OCCLUDED_NODES_SLOT, PYRAMID_SLOT, STAGE, VIEW_INPUT,
    hierarchy_contract, instance_grid, instance_programs,
};
use bytemuck::Zeroable;
use meshlight_gpu_scene::Phase;
use meshlight_gpu_scene::view::frame_view;
use meshlight_graph::prelude::*;
use meshlight_shaders::cpu::layout::View;

/// The implementation name pipelines use.
pub const IMPLEMENTATION: &str = "hierarchy";

/// The `hierarchy` implementation's WGSL with its uniform block and the list module,
/// public so the shader tests compose and validate every entry point.
pub const SHADER: PassShader = pass_shader!(
    "fill_clusters::hierarchy",
    "hierarchy.wgsl",
    params: GpuParams,
    modules: [("fill_clusters::list", "list.wgsl")]
);

/// Nodes a frontier holds in workgroup memory (`QUEUE` in the shader).
pub const QUEUE: u32 = 1024;
/// Rounds after which a walk stops and counts itself unfinished (`MAX_ROUNDS`).
pub const MAX_ROUNDS: u32 = 256;
/// Spreading steps by default: one hand-off, then the last step. Each step is a
/// dispatch the whole walk waits for; the scenes measured so far seldom have a frontier
/// wider than a chunk, so more steps would cost more than they spread.
pub const SPREAD_STEPS: u32 = 1;
/// Spreading steps at most (`MAX_STEPS`).
pub const MAX_STEPS: u32 = 4;
/// Entries a step's list of handed-on subtrees holds by default.
pub const SUBTREE_CAPACITY: u32 = 1 << 16;
/// Workgroups of each step after the first by default: several per compute unit of the
/// largest GPUs (132 SMs on an H100/H200), few enough that an empty list costs little.
pub const SPREAD_GROUPS: u32 = 1024;
/// The slack of a node test, relative to the magnitudes it combines (`SLACK`).
pub const SLACK: f32 = 1.0 / 8192.0;

/// The slots the walk reads, besides the stage's own.
pub const DATA_SLOTS: [&str; 3] = ["hierarchy_nodes", "hierarchy_clusters", "hierarchy_roots"];
/// The counters' slot; a scratch buffer when it is left unbound.
pub const COUNTS_SLOT: &str = "hierarchy_counts";
/// Scratch: the lists' lengths, one word per spreading step, then the roots list's.
const LIST_COUNTS: &str = "subtree_counts";
/// Scratch: the roots list, step 0's entries, 12 bytes each.
const ROOTS: &str = "root_list";
/// Scratch: step 0's indirect dispatch.
const WALK_ARGS: &str = "walk_args";
/// Entries of the roots list: a root that finds it full emits every meshlet below it.
pub const ROOT_CAPACITY: u32 = 1 << 20;
/// Workgroups (of 64 threads) the second walk's roots pass strides with.
const ROOT_GROUPS: u32 = 1024;
/// Scratch: the lists of handed-on subtrees, 12 bytes an entry.
const LISTS: &str = "subtrees";

shader_defs! {
    /// The variant of hierarchy.wgsl a pass runs.
    #[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
    pub struct WalkDefs {
        /// A pyramid is bound and tested per node.
        pub occlusion: bool => "OCCLUSION",
        /// [`Phase::Second`].
        pub second: bool => "SECOND_PASS",
        /// One walk for several views (`views` > 1).
        pub multi_view: bool => "MULTI_VIEW",
    }
}

/// Views one walk serves at most (`MAX_VIEWS` in the shader): the camera and a sun's
/// four cascades. Their mask takes the top five bits of a node id in the frontiers and
/// lists.
pub const MAX_VIEWS: u32 = 5;

/// Words of `hierarchy_counts` with occlusion: `[4]` nodes the pyramid hid.
pub const OCCLUSION_COUNT_WORDS: u64 = 5;
/// Words of `hierarchy_counts` with the entry counters: `[5]` the walk's entries tested
/// (the first walk's: one root per instance, so instances tested) and `[6]` those that
/// passed (instances visible, or nodes found visible by the second walk). Bound
/// shorter, they are not counted.
pub const ENTRY_COUNT_WORDS: u64 = 7;

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
    /// Steps that hand wide walks on to more workgroups; 0: one workgroup per instance.
    pub spread_steps: u32,
    /// Entries of each step's list; `None`: [`SUBTREE_CAPACITY`].
    pub subtree_capacity: Option<u32>,
    /// Workgroups of each step after the first; `None`: [`SPREAD_GROUPS`].
    pub spread_groups: Option<u32>,
    /// Which walk of the frame this is (`mode` in a pipeline file; two-pass occlusion
    /// culling, docs/ARCHITECTURE.md): the first walks from every instance's root and,
    /// with a pyramid bound (last frame's), sends the nodes it proves hidden to
    /// `occluded_nodes`; the second walks from those (`candidate_nodes`) against this
    /// frame's pyramid and drops what is still hidden.
    pub phase: Phase,
    /// With occlusion, the walk's entries (instance roots; the second walk's nodes) and
    /// the inner nodes with at least this many meshlets below are tested against the
    /// pyramid ([`OCCLUSION_MIN_CLUSTERS`] by default; `u32::MAX`: entries only).
    pub occlusion_min_clusters: u32,
    /// Views the walk serves, 1 to [`MAX_VIEWS`]: with more than one, the frame input
    /// `view` holds that many Views back to back, and view v's list is list
    /// `part.list + v` of the buffers. A view whose viewport is empty (all zeros) is not
    /// walked, and its list is left empty.
    pub views: u32,
    /// With several views and a pyramid (a first walk), the view the pyramid is of.
    pub occlusion_view: u32,
    /// The lists of `clusters` and `cluster_count` it writes.
    pub part: meshlight_gpu_scene::ListPart,
}

/// Inner nodes with fewer meshlets below are left to `cull_lod`'s per-cluster test; by
/// default that is every inner node, and only a walk's entries (an instance's root, a
/// node handed to the second walk) are tested. A node test costs the walk a dependent
/// texture read in its round, and on every scene measured (the default scene at 1080p
/// and 4K, the bunny lattice, the million bunnies; docs/BENCHMARKS.md, "Occlusion tests
/// in the walk") testing inner nodes, down to any size tried, cost the walk more than
/// it saved the cull.
pub const OCCLUSION_MIN_CLUSTERS: u32 = u32::MAX;

impl Default for HierarchyFill {
    fn default() -> Self {
        Self {
            capacity: None,
            instance_count: None,
            lod_threshold_px: 1.0,
            queue_capacity: None,
            spread_steps: SPREAD_STEPS,
            subtree_capacity: None,
            spread_groups: None,
            phase: Phase::First,
            occlusion_min_clusters: OCCLUSION_MIN_CLUSTERS,
            views: 1,
            occlusion_view: 0,
            part: meshlight_gpu_scene::ListPart::default(),
        }
    }
}

uniform_block! {
    /// The uniform of hierarchy.wgsl, which imports the struct from this declaration.
    struct GpuParams as "Params" in "fill_clusters::hierarchy_params" {
        /// Clusters the list may hold; the shader also clamps it to the bound list's length.
        capacity: u32,
        /// Instances to visit (at most the bound instance count).
        instance_count: u32,
        /// The dispatch's x size. The kernels take their grid from `num_workgroups` and
        /// do not read it.
        groups_x: u32,
        /// Nodes a frontier may hold, at most QUEUE (smaller in tests, to reach the spill).
        queue_capacity: u32,
        /// cull_lod's `lod_threshold_px`: the two must agree, or the cut loses clusters.
        lod_threshold_px: f32,
        /// This dispatch's step: 0 starts at the roots list (the children of every root
        /// that passed), `steps` is the last.
        step: u32,
        /// Spreading steps: lists of subtrees handed from one step to the next.
        steps: u32,
        /// Entries each list holds.
        list_capacity: u32,
        /// 1: test occlusion against `pyramid`; 0: skip it (no valid history, camera cut).
        test_occlusion: u32,
        /// Entries `node_list` may hold (clamped to its length too).
        node_capacity: u32,
        /// Entries the roots list holds (clamped to its length too).
        root_capacity: u32,
        /// The per-dimension workgroup limit step 0's indirect dispatch stays under.
        max_per_dimension: u32,
        /// Inner nodes with fewer meshlets below are not tested for occlusion (cull_lod
        /// tests their clusters): each test costs the walk a dependent texture read. A
        /// walk's entries (instance roots, the second walk's nodes) always are.
        occlusion_min_clusters: u32,
        /// Views the walk serves (MULTI_VIEW), 1 without.
        views: u32,
        /// View 0's list, and the lists the buffers hold ([`meshlight_gpu_scene::ListPart`]).
        list: u32,
        lists: u32,
        /// MULTI_VIEW with OCCLUSION: the view the pyramid is of.
        occlusion_view: u32,
        /// The lists `prepare` zeroes the words of: every view's, also in a one-view
        /// dispatch of a walk over several.
        first_cleared: u32,
        cleared_lists: u32,
        pad_a: u32,
    }
}

const PARAM_KEYS: [&str; 13] = [
    "views",
    "occlusion_view",
    "list",
    "lists",
    "mode",
    "occlusion_min_clusters",
    "capacity",
    "instance_count",
    "lod_threshold_px",
    "queue_capacity",
    "spread_steps",
    "subtree_capacity",
    "spread_groups",
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
            spread_steps: params.u32("spread_steps", SPREAD_STEPS)?,
            subtree_capacity: nonzero(params.u32("subtree_capacity", 0)?),
            spread_groups: nonzero(params.u32("spread_groups", 0)?),
            occlusion_min_clusters: params.u32("occlusion_min_clusters", OCCLUSION_MIN_CLUSTERS)?,
            phase: Phase::from_params(params)?,
            views: params.u32("views", 1)?,
            occlusion_view: params.u32("occlusion_view", 0)?,
            part: meshlight_gpu_scene::ListPart::default(),
        };
        if !(1..=MAX_VIEWS).contains(&pass.views) {
            return Err(GraphError::parameter(format!(
                "`views` = {} must be 1 to {MAX_VIEWS}: the views one walk serves",
                pass.views
            )));
        }
        if pass.phase == Phase::Second && pass.views > 1 {
            return Err(GraphError::parameter(format!(
                "a `mode = \"second\"` walk serves one view (the hidden nodes of the first walk's `occlusion_view`), not {}: set `views = 1`",
                pass.views
            )));
        }
        if pass.occlusion_view >= pass.views {
            return Err(GraphError::parameter(format!(
                "`occlusion_view` = {} must name one of the {} view(s), 0 to {}: the view the pyramid is of",
                pass.occlusion_view,
                pass.views,
                pass.views - 1
            )));
        }
        let pass = Self {
            part: meshlight_gpu_scene::ListPart::from_params(params, pass.views)?,
            ..pass
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
        if self.spread_steps > MAX_STEPS {
            return Err(GraphError::parameter(format!(
                "`spread_steps` = {} is above the {MAX_STEPS} steps the walk hands subtrees on over; use at most {MAX_STEPS}",
                self.spread_steps
            )));
        }
        if self.spread_groups.is_some_and(|g| g > u16::MAX as u32) {
            return Err(GraphError::parameter(format!(
                "`spread_groups` = {} is above the {} workgroups one dispatch dimension holds everywhere; use fewer",
                self.spread_groups.unwrap_or(0),
                u16::MAX
            )));
        }
        let entries = self.list_capacity() as u64 * self.spread_steps as u64 * 3;
        if entries > u32::MAX as u64 / 4 {
            return Err(GraphError::parameter(format!(
                "`subtree_capacity` = {} times {} steps is more than a buffer holds; lower it",
                self.list_capacity(),
                self.spread_steps
            )));
        }
        Ok(())
    }

    fn list_capacity(&self) -> u32 {
        self.subtree_capacity.unwrap_or(SUBTREE_CAPACITY)
    }

    /// Whether the walk tests occlusion (a pyramid is bound), after checking that the
    /// slots of its phase are bound and the other phase's are not.
    fn check_phase(&self, ctx: &SetupContext) -> Result<bool> {
        let bound = |slot| ctx.is_bound(slot);
        let occlusion = bound(PYRAMID_SLOT);
        let (mine, other) = match self.phase {
            Phase::First => (
                [OCCLUDED_NODES_SLOT, OCCLUDED_NODE_COUNT_SLOT],
                [CANDIDATE_NODES_SLOT, CANDIDATE_NODE_COUNT_SLOT],
            ),
            Phase::Second => (
                [CANDIDATE_NODES_SLOT, CANDIDATE_NODE_COUNT_SLOT],
                [OCCLUDED_NODES_SLOT, OCCLUDED_NODE_COUNT_SLOT],
            ),
        };
        let mode = self.phase.name();
        if let Some(slot) = other.iter().find(|s| bound(s)) {
            return Err(GraphError::parameter(format!(
                "`{slot}` is bound to a `mode = \"{mode}\"` walk, which uses `{}` and `{}`; the first walk writes `{OCCLUDED_NODES_SLOT}`, the second reads the same list as `{CANDIDATE_NODES_SLOT}` (name the resources unlike both slots, or the second walk binds them by name)",
                mine[0], mine[1]
            )));
        }
        let listed = mine.iter().filter(|s| bound(s)).count();
        if occlusion && listed < 2 || self.phase == Phase::Second && !occlusion {
            return Err(GraphError::parameter(format!(
                "a `mode = \"{mode}\"` walk with occlusion needs `{PYRAMID_SLOT}`, `{}` and `{}` bound ({})",
                mine[0],
                mine[1],
                match self.phase {
                    Phase::First => "last frame's pyramid; the nodes it hides go to the list",
                    Phase::Second => "this frame's pyramid; the first walk's hidden nodes",
                }
            )));
        }
        if !occlusion && listed > 0 {
            return Err(GraphError::parameter(format!(
                "`{}` is bound but `{PYRAMID_SLOT}` is not: bind last frame's pyramid to test occlusion, or unbind it",
                mine[0]
            )));
        }
        Ok(occlusion)
    }
}

/// The walk's kernels, in the order a frame dispatches them.
const ENTRIES: [&str; 4] = ["walk_dispatch", "prepare", "roots", "fill"];

/// The one-view programs a walk over several views also compiles, entry by entry.
const ONE_VIEW_PROGRAMS: [&str; 4] = [
    "one_view:walk_dispatch",
    "one_view:prepare",
    "one_view:roots",
    "one_view:fill",
];

/// The programs a one-view first walk with a pyramid also compiles without occlusion,
/// entry by entry (`prepare` and `walk_dispatch` are not among them: the occlusion
/// variant's `prepare` also zeroes the hidden-node count a second walk may read).
const UNTESTED_PROGRAMS: [(&str, &str); 2] =
    [("roots", "untested:roots"), ("fill", "untested:fill")];

impl HierarchyFill {
    /// The one view a walk over several is given this frame, when only one has a
    /// viewport (the camera while every cascade keeps its map, or one cascade drawn)
    /// and, with a pyramid, it is the pyramid's view: the walk then runs the one-view
    /// programs on that view's list. The multi-view kernels' per-view bookkeeping (a
    /// mask per entry, a reservation per view) made the camera's walk alone 0.04 ms
    /// slower on the default scene (NVIDIA H200, docs/BENCHMARKS.md).
    fn lone_view(&self, views: &[View], occlusion: bool) -> Option<u32> {
        if self.views < 2 {
            return None;
        }
        let mut given = (0..self.views).filter(|&v| views[v as usize].viewport_size != [0.0; 2]);
        let v = given.next()?;
        let alone = given.next().is_none() && (!occlusion || v == self.occlusion_view);
        alone.then_some(v)
    }

    /// The frame's Views: one, or with several views [`MAX_VIEWS`] (the uniform's
    /// length), those the input does not give left zero (not walked).
    fn frame_views(&self, ctx: &RecordContext<'_>) -> Result<Vec<View>> {
        if self.views == 1 {
            return Ok(vec![frame_view(ctx, VIEW_INPUT, None)?]);
        }
        let bytes = ctx.frame_bytes(VIEW_INPUT)?;
        let size = size_of::<View>();
        if bytes.len() != self.views as usize * size {
            return Err(GraphError::Record {
                pass: ctx.pass_name().to_string(),
                message: format!(
                    "frame input `{VIEW_INPUT}` must hold {} Views back to back ({} bytes) for `views` = {}, got {} bytes",
                    self.views,
                    self.views as usize * size,
                    self.views,
                    bytes.len()
                ),
            });
        }
        let mut views = vec![View::zeroed(); MAX_VIEWS as usize];
        for (v, chunk) in views.iter_mut().zip(bytes.chunks_exact(size)) {
            *v = bytemuck::pod_read_unaligned(chunk);
        }
        Ok(views)
    }
}

impl Pass for HierarchyFill {
    fn implementation(&self) -> Implementation {
        Implementation::new(IMPLEMENTATION, hierarchy_contract())
    }
    fn setup(&self, ctx: &mut SetupContext) -> Result<()> {
        self.check()?;
        if let Some(slot) = DATA_SLOTS.iter().find(|s| !ctx.is_bound(s)) {
            return Err(GraphError::parameter(format!(
                "`{STAGE}` implementation `{IMPLEMENTATION}` walks the culling hierarchy: bind slot `{slot}` to the GPU scene's buffer of that name (GpuScene::import_hierarchy, or gpu::import_hierarchy_for)"
            )));
        }
        let occlusion = self.check_phase(ctx)?;
        let second = self.phase == Phase::Second;
        let multi_view = self.views > 1;
        let defs = WalkDefs {
            occlusion,
            second,
            multi_view,
        };
        ctx.min_bytes("cluster_count", self.part.count_bytes());
        ctx.frame_input(VIEW_INPUT);
        let count_words = if occlusion { OCCLUSION_COUNT_WORDS } else { 4 };
        // A scratch buffer holds the entry counters too; a bound one holds them when
        // it has room (the kernel checks its length). Either binds by its name.
        if ctx.is_bound(COUNTS_SLOT) {
            ctx.min_bytes(COUNTS_SLOT, count_words * 4);
        } else {
            ctx.scratch_buffer(
                COUNTS_SLOT,
                BufferDesc::array(Element::U32, ENTRY_COUNT_WORDS),
                &[Access::ClearedReadWrite],
            );
        }
        // The lists (at least one entry, so the binding exists with no spreading step).
        ctx.scratch_buffer(
            LIST_COUNTS,
            BufferDesc::array(Element::U32, MAX_STEPS as u64 + 1),
            &[Access::ClearedReadWrite],
        );
        ctx.scratch_buffer(
            ROOTS,
            BufferDesc::array(Element::U32, ROOT_CAPACITY as u64 * 3),
            &[Access::StorageReadWrite],
        );
        ctx.scratch_buffer(
            WALK_ARGS,
            BufferDesc::array(Element::DISPATCH_ARGS, 1),
            &[Access::StorageWrite, Access::Indirect],
        );
        let words = (self.list_capacity() as u64 * self.spread_steps as u64).max(1) * 3;
        ctx.scratch_buffer(
            LISTS,
            BufferDesc::array(Element::U32, words),
            &[Access::ClearedReadWrite],
        );
        // Bindings from the shader; one WGSL variable, `node_list`, is the first walk's
        // output slot or the second walk's input slot, so those two are named here.
        let mut layout = BindingLayout::from_shader("fill_clusters::hierarchy");
        if occlusion {
            if second {
                ctx.min_bytes(CANDIDATE_NODE_COUNT_SLOT, 4);
                layout = layout
                    .slot(12, CANDIDATE_NODES_SLOT)
                    .slot(13, CANDIDATE_NODE_COUNT_SLOT);
            } else {
                ctx.min_bytes(OCCLUDED_NODE_COUNT_SLOT, 8);
                ctx.frame_input(CAMERA_CUT_INPUT);
                layout = layout
                    .slot(12, OCCLUDED_NODES_SLOT)
                    .slot(13, OCCLUDED_NODE_COUNT_SLOT);
            }
        }
        // Only `walk_dispatch` uses `walk_args` as storage; `fill` is dispatched with it.
        instance_programs(ctx, &SHADER, &ENTRIES, layout.clone(), &defs);
        if occlusion && !second && !multi_view {
            // A frame that tests nothing (no history, a camera cut, a renderer leaving
            // occlusion out) walks without the occlusion test compiled in: the
            // variant with it carried the walk 0.009 ms slower on an NVIDIA H200 (15³
            // bunnies, docs/BENCHMARKS.md). Its bindings are the shader's own.
            let untested = WalkDefs {
                occlusion: false,
                ..defs
            };
            let table = meshlight_gpu_scene::instance_table::InstanceTable::of(ctx);
            for (entry, name) in UNTESTED_PROGRAMS {
                ctx.program(
                    name,
                    ProgramDesc::compute(&SHADER, entry)
                        .defs(&untested)
                        .defs(&table)
                        .layout(BindingLayout::from_shader("fill_clusters::hierarchy")),
                );
            }
        }
        if multi_view {
            // The one-view programs, for a frame that gives one view a viewport.
            let one = WalkDefs {
                multi_view: false,
                ..defs
            };
            let table = meshlight_gpu_scene::instance_table::InstanceTable::of(ctx);
            for (entry, name) in ENTRIES.into_iter().zip(ONE_VIEW_PROGRAMS) {
                ctx.program(
                    name,
                    ProgramDesc::compute(&SHADER, entry)
                        .defs(&one)
                        .defs(&table)
                        .layout(layout.clone()),
                );
            }
        }
        Ok(())
    }
    fn record(&self, ctx: &mut RecordContext<'_>) -> Result<()> {
        let views = self.frame_views(ctx)?;
        let occlusion = ctx.is_bound(PYRAMID_SLOT);
        // The programs, their view uniform (WGSL `views`, an array, with MULTI_VIEW;
        // `view` without), and the first list and pyramid's view they are told.
        let (programs, uniform_name, uniform, walked, list, occlusion_view) =
            match self.lone_view(&views, occlusion) {
                Some(v) => (
                    ONE_VIEW_PROGRAMS,
                    "view",
                    bytemuck::bytes_of(&views[v as usize]),
                    1,
                    self.part.list + v,
                    0,
                ),
                None if self.views > 1 => (
                    ENTRIES,
                    "views",
                    bytemuck::cast_slice(&views),
                    self.views,
                    self.part.list,
                    self.occlusion_view,
                ),
                None => (
                    ENTRIES,
                    "view",
                    bytemuck::cast_slice(&views),
                    1,
                    self.part.list,
                    0,
                ),
            };
        let InstanceGrid {
            instance_count,
            limit,
            ..
        } = instance_grid(ctx, self.instance_count)?;
        let spread = self.spread_groups.unwrap_or(SPREAD_GROUPS).min(limit);
        let test_occlusion = occlusion
            && match self.phase {
                Phase::Second => true,
                Phase::First => {
                    ctx.history_valid(PYRAMID_SLOT)? && ctx.frame_u32(CAMERA_CUT_INPUT)? == 0
                }
            };
        // A one-view first walk with a pyramid that tests nothing this frame runs the
        // kernels compiled without the test (setup made them).
        let untested =
            occlusion && !test_occlusion && self.phase == Phase::First && self.views == 1;
        // The roots a thread each: every instance's (a grid over them), or the second
        // walk's nodes, whose count only the GPU knows (a fixed grid striding over them).
        let roots_grid = match self.phase {
            Phase::First => crate::workgroup_grid(instance_count.div_ceil(64), limit),
            Phase::Second => [ROOT_GROUPS.min(limit), 1],
        };
        // The counters and list lengths zeroed, the roots, step 0's arguments, step 0
        // (a workgroup per entry of the roots list), then each later step over the list
        // the one before wrote; each dispatch sees the writes of those before it.
        let (args, _) = ctx.scratch(WALK_ARGS)?;
        let args = args.clone();
        let mut dispatches = vec![
            ("prepare", 0, Workgroups::Direct([1, 1, 1])),
            (
                "roots",
                0,
                Workgroups::Direct([roots_grid[0], roots_grid[1], 1]),
            ),
            ("walk_dispatch", 0, Workgroups::Direct([1, 1, 1])),
            ("fill", 0, Workgroups::Indirect(&args, 0)),
        ];
        for step in 1..=self.spread_steps {
            dispatches.push(("fill", step, Workgroups::Direct([spread, 1, 1])));
        }
        for (entry, step, grid) in dispatches {
            let grid_x = match grid {
                Workgroups::Direct([x, ..]) => x,
                Workgroups::Indirect(..) => 0,
            };
            let params = GpuParams {
                capacity: self.capacity.unwrap_or(u32::MAX),
                instance_count,
                groups_x: grid_x,
                queue_capacity: self.queue_capacity.unwrap_or(QUEUE).min(QUEUE),
                lod_threshold_px: self.lod_threshold_px,
                step,
                steps: self.spread_steps,
                list_capacity: self.list_capacity(),
                test_occlusion: test_occlusion as u32,
                node_capacity: u32::MAX,
                root_capacity: ROOT_CAPACITY,
                max_per_dimension: limit,
                occlusion_min_clusters: self.occlusion_min_clusters,
                views: walked,
                list,
                lists: self.part.lists,
                occlusion_view,
                first_cleared: self.part.list,
                cleared_lists: self.views,
                pad_a: 0,
            };
            let uniforms: [(&str, &[u8]); 2] = [
                (uniform_name, uniform),
                ("params", bytemuck::bytes_of(&params)),
            ];
            let at = ENTRIES.iter().position(|e| *e == entry).unwrap_or(0);
            let program = (UNTESTED_PROGRAMS.iter())
                .find(|(e, _)| untested && *e == entry)
                .map_or(programs[at], |(_, name)| *name);
            ctx.dispatch_compute(program, &uniforms, grid)?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use meshlight_scene::asset::format::NodeRecord;
    use meshlight_shaders::{Capabilities, ShaderLibrary};
    use meshlight_testing::shader_variants::wgsl_constant;

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
        let constant = |name| wgsl_constant::<f64>(&SHADER, name);
        assert_eq!(constant("QUEUE"), QUEUE as f64);
        assert_eq!(constant("MAX_ROUNDS"), MAX_ROUNDS as f64);
        // Two levels a round: the deepest tree the loader lets through is one the walk
        // finishes.
        assert_eq!(
            2 * MAX_ROUNDS,
            meshlight_scene::hierarchy::MAX_DEPTH,
            "the loader's depth limit follows the walk's rounds"
        );
        assert_eq!(constant("SLACK"), SLACK as f64);
        assert_eq!(constant("MAX_STEPS"), MAX_STEPS as f64);
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
        // Accepted params are checked above: a lone walk may stop at an unbound slot.
        meshlight_testing::assert_params(
            pass,
            &[],
            &[
                ("lod_threshold_px = -1.0", "lod_threshold_px"),
                ("queue_capacity = 5000", "queue_capacity"),
                ("queu_capacity = 4", "queu_capacity"),
                ("spread_steps = 5", "spread_steps"),
                ("spread_groups = 70000", "spread_groups"),
                ("views = 6", "views"),
                ("views = 2, occlusion_view = 2", "occlusion_view"),
                ("mode = \"second\", views = 2", "views"),
                ("views = 0", "views"),
                ("views = 3, lists = 2", "lists"),
                ("views = 2, list = 3, lists = 4", "list"),
            ],
        );
    }
}
