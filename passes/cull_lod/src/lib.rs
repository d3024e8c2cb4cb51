//! Stage `cull_lod`, implementation `compute`: per cluster, the frustum test, the LOD
//! cut, the occlusion test against a depth pyramid, and the choice of rasteriser, into
//! one shared slot buffer.
//!
//! Every cluster of every level arrives here (from `fill_clusters`); exactly one level of
//! each part of a mesh survives the LOD cut, because errors and LOD spheres grow up the
//! DAG. Small clusters go to the software rasteriser and fill the slot buffer from the
//! left, the rest go to the hardware rasteriser from the right, so one buffer of `C`
//! slots serves both however the split falls, and one reservation counter keeps the two
//! sides from ever meeting: past `C` a cluster is dropped and counted, never written.
//!
//! # Contract
//!
//! | slot              | access             | holds   | |
//! |-------------------|--------------------|---------|---|
//! | `clusters`        | storage read       | Cluster | candidates; `cluster_count[0]` of them are valid |
//! | `cluster_count`   | storage read       | u32     | `[0]`: clusters in the list |
//! | `instances`       | storage read       | Instance | the GPU scene |
//! | `instances_high`  | storage read, optional | Instance | the instances past one binding's limit (`meshlight_gpu_scene::instance_table`) |
//! | `meshes`          | storage read       | Mesh    | the GPU scene's read set; `compute` reads nothing of it and binds it to nothing |
//! | `meshlets`        | storage read       | Meshlet | bounds, groups, triangle counts |
//! | `meshlet_groups`  | storage read       | MeshletGroup | LOD spheres and errors |
//! | `raster_clusters` | storage write      | Cluster | `C` slots: software in `0..[0]`, hardware in `C-[1]..C` |
//! | `raster_counts`   | cleared read-write | u32 × 8 (12 with `pyramid`) | the words below |
//! | `hw_args`         | cleared read-write | DrawIndirectArgs | `[384, hardware clusters, 0, 0]` for `draw_indirect` |
//! | `pyramid`         | sampled (optional) | R32Float, all mips | the depth pyramid; bound: occlusion is tested |
//! | `occluded`        | storage write (optional) | Cluster | `first` with a pyramid: the clusters found hidden, the second pass's candidates |
//! | `occluded_count`  | cleared read-write (optional) | u32 × 2 | `first` with a pyramid: `[0]` candidates written, `[1]` found (`cluster_count`'s layout) |
//! | `first_counts`    | storage read (optional) | u32 × 12 | `second`: the first pass's `raster_counts` |
//! | `occluded_per_instance` | cleared read-write (optional) | u32 × 2 per instance | `first` with a pyramid: `[2i]` clusters of instance `i` in the LOD cut, `[2i + 1]` of those found hidden |
//! | `still_occluded_per_instance` | storage read-write (optional) | u32 × 2 per instance | `second`: the same buffer; `[2i + 1]` less each candidate found visible |
//! | `walked_clusters` | storage read (optional) | Cluster | `second`: the second hierarchy walk's list (`fill_clusters` `hierarchy`, `mode = "second"`), tested after `clusters` |
//! | `walked_cluster_count` | storage read (optional) | u32 × 2 | `second`: its `cluster_count` |
//! | `page_errors`     | storage read (optional) | f32 per group | streaming: a group's error while its page is missing, else 0 (the streamed scene's `stream_errors`) |
//! | `page_marks`      | storage read-write (optional) | u32 per group | streaming: 1 + the last frame the group's page was wanted; kept across frames |
//! | `page_requests`   | storage write (optional) | PageRequest (group, priority bits) | streaming: the pages wanted this frame, each once |
//! | `page_request_count` | cleared read-write (optional) | u32 × 2 | streaming: `[0]` requests written, `[1]` found |
//!
//! `raster_counts`: `[0]` software clusters, `[1]` hardware clusters, `[2]` clusters
//! that passed frustum, LOD and occlusion (slots requested, may exceed the slots the
//! pass has), `[3]` `C`, `[4]` clusters that passed the frustum test, `[5]` software
//! triangles, `[6]` hardware triangles, `[7]` the first slot of this pass's software
//! clusters (0 but in a second pass). Overflow = `max(0, [2] - [3])`.
//! With a pyramid the buffer has 12 words: `[8]` clusters in the LOD cut (0 when the
//! test is skipped), `[9]` of those found hidden, `[10]` the slots this pass has
//! (overflow = `max(0, [2] - [10])`), `[11]` clusters whose sphere could be tested (in
//! front of the near plane, wholly on the screen; 0 when the test is skipped). Frame
//! input `view` (`meshlight_shaders::cpu::layout::View`); a `first` pass with a pyramid
//! also reads frame input `camera_cut` (u32, non-zero: last frame's depth says nothing
//! of this one).
//!
//! # Two-pass occlusion
//!
//! `mode = "first"` with `pyramid` bound to a history's `prev` (last frame's pyramid)
//! projects each cluster in the LOD cut with `View::previous_view_projection` and the
//! instance's `previous_world_from_local`, and sends it to `occluded` instead of a raster
//! slot when the pyramid proves it hidden. When the history is not valid (first frame,
//! resize; `RecordContext::history_valid`) or the frame input `camera_cut` is set, it
//! tests nothing and behaves as without a pyramid: without per-instance counters it
//! then dispatches `cull` compiled without the test (its `prepare` still the occlusion
//! variant's, which zeroes `occluded_count`), so such a frame costs what a frame without
//! a pyramid does. A pyramid that is not a history resource is never valid for the
//! first pass.
//!
//! `mode = "second"` takes the first pass's `occluded` list as its `clusters` and
//! `occluded_count` as its `cluster_count`, binds this frame's pyramid (built from what
//! the first pass drew) and the first pass's `raster_counts` as `first_counts`, and has
//! its own `raster_counts`, `hw_args` (and `sw_args` from its own `remap_dispatch`). It
//! tests with the current view and transforms and appends what is visible to the same
//! `raster_clusters`, in the free slots between the first pass's software clusters
//! (`[0, sw1)`) and hardware clusters (`[C - hw1, C)`), split as the first pass splits:
//! software from the left (its `raster_counts[7]` is `sw1`, where `sw_raster` with
//! `accumulate` starts), hardware from the right (its `raster_counts[3]` is `C - hw1`,
//! so `hw_raster` bound to its `raster_counts` and `hw_args` draws instance `j` into
//! slot `C - hw1 - 1 - j`). Every visibility id of the frame indexes one list.
//!
//! With the hierarchy walk testing occlusion per node (`fill_clusters` `hierarchy`), the
//! first walk hands the nodes last frame's pyramid hides to a second walk, which runs
//! after this frame's pyramid is built and lists the clusters below the nodes still
//! visible. The second pass takes that list as `walked_clusters` and
//! `walked_cluster_count`, after its candidates: its clusters were never tested, and get
//! every test (frustum, LOD, occlusion against this frame's pyramid).
//!
//! # Streaming
//!
//! On a streamed scene (`meshlight_gpu_scene::streaming`) the LOD test needs nothing
//! new: a group whose page is missing has error 0 there, so the cut already keeps its
//! result. What the pass adds, with the four streaming slots bound to a first pass, is
//! the list of pages the frame wants: for each cluster in the frustum and the cut
//! (before the occlusion test, so a page is kept while its clusters are hidden for a
//! moment), the page of its source group when that group's real error
//! (`page_errors`) shows, with the error in pixels as its priority; and the page a run
//! of candidates lies on (the walk lists a leaf's meshlets together), in use when its
//! group's error shows (priority 0), asked by the run's first cluster only. A per-group
//! mark (`page_marks`, `view.frame_index + 1`) lists each page once a frame; a load
//! skips the atomic write when the page is marked already. Marking in use from every
//! cluster of the cut cost the default scene's cull 0.028 ms on an H200 (0.035 →
//! 0.063 ms: some 117,000 atomics on a few hundred words); from the runs' first, less
//! (docs/BENCHMARKS.md).
//! The renderer reads the list back and hands it to the streamer
//! (`meshlight_stream::Streamer::frame`). [`cpu::wanted_pages`] is the reference. The
//! second pass lists nothing: a cluster drawn only through the second walk asks for its
//! pages the next frame.
//!
//! # Per-instance occlusion counters (for the `occlusion` debug view)
//!
//! With `occluded_per_instance` bound, the first pass clears it (a fill inside the
//! batch) and, per cluster of instance `i` in the LOD cut, adds 1 to `[2i]` and, when
//! the pyramid hides it, 1 to `[2i + 1]`. The second pass, given the same buffer as
//! `still_occluded_per_instance`, subtracts 1 from `[2i + 1]` per candidate it finds
//! visible, and for each cluster of `walked_clusters` in the cut adds 1 to `[2i]` and,
//! when it is still hidden, 1 to `[2i + 1]`. After both, `[2i + 1]` is what occlusion
//! culled of instance `i` at the cluster level this
//! frame and `[2i + 1] / [2i]` its share, which `resolve`'s `occlusion` view shows.
//! Instances past the buffer's length are not counted. Two atomics per cluster of the
//! cut plus a clear: a frame binds the buffer only for that view.
//! [`cpu::occluded_per_instance`] is the reference.
//!
//! The candidates are a list, not a bitmask over the first pass's input: the second
//! pass then runs over the candidates alone (usually a few per cent of the cut), not over
//! every cluster again, and needs no scan to find them.
//!
//! The pyramid is read by the rule of `depth_pyramid` (level `L` is `ceil(W / 2^(L+1))`
//! × `ceil(H / 2^(L+1))`, each texel the farthest depth of its footprint); each mip of the
//! texture must be at least its level's size, as `depth_pyramid::texture_desc` pads it.
//!
//! The test (`meshlight::occlusion`): the eight corners of the sphere's world-space
//! bounding cube (radius grown by 1e-5 of the coordinates) projected; any corner not in
//! front of the near plane, or the rectangle (grown by a pixel) not wholly on the screen:
//! not tested, kept. Else the pyramid level where the rectangle spans at most 2 × 2
//! texels, and the cluster is hidden when its nearest depth times 1 + 2^-8 is farther
//! than the farthest depth of those texels.
//!
//! | param               | default | |
//! |---------------------|---------|---|
//! | `lod_threshold_px`  | 1.0     | screen-space error (pixels) a cluster may show |
//! | `sw_threshold_px`   | 128.0   | screen-box size under which a cluster goes to software; `"auto"`: the adapter class's split ([`sw_threshold_on`], measured: docs/BENCHMARKS.md) |
//! | `hardware`          | true    | false: every cluster to software, those crossing the near plane too (sw_raster clips them; a pipeline with no `hw_raster`); `"auto"`: where the adapter class rasterises in hardware (`AdapterClass::hardware_raster`, the rule `hw_raster`'s `run = "auto"` follows) |
//! | `mode`              | `"first"` | `first`: every candidate, occlusion against last frame's pyramid when one is bound; `second`: the re-test of the first pass's occluded clusters against this frame's |
//! | `capacity`          | 0 (all of `raster_clusters`) | `C`, at most the buffer's size / 8 |
//! | `max_per_dimension` | 0 (the adapter's) | workgroup limit per dimension of the indirect cull dispatch |
//! | `append_requests`   | false   | streaming: add the pass's page requests to those of the culls before it (a shadow view's cull after the camera's) instead of starting the frame's list |
//! | `list`, `lists`     | 0, 1    | the candidate buffers hold `lists` lists (one per view) and the pass reads list `list` (`meshlight_gpu_scene::ListPart`) |
//!
//! # Definitions the tests pin down
//!
//! - Frustum: `sphere_in_frustum(view, M·bounds.xyz, bounds.w · instance_max_scale)`.
//! - LOD cut: `lod_cut` with the own sphere and error of the source group (the bounds and
//!   0 at LOD 0) and the parent group's (`F32_MAX` for roots), threshold
//!   `lod_threshold_px`. With every cluster of an instance in view, every path from a
//!   LOD-0 meshlet to a root through the DAG (meshlet → its parent group → any meshlet
//!   that group produced → …) holds exactly one cluster of the cut.
//! - Software when the world sphere lies wholly beyond the near plane
//!   (`dot(near.xyz, c) + near.w > r`) and the screen box of the 8 corners of its
//!   view-space bounding cube, through `projection`, with screen =
//!   `((ndc.x · 0.5 + 0.5) · width, (0.5 − ndc.y · 0.5) · height)`, is narrower and
//!   shorter than `sw_threshold_px`; hardware otherwise.
//! - Slots: `total = atomicAdd([2], 1)`; `total >= C`: dropped; else software writes slot
//!   `atomicAdd([0], 1)`, hardware slot `C − 1 − atomicAdd(hw_args[1], 1)` (and counts
//!   `[1]`). So `[0] + [1] = min([2], C)` and no slot is written twice. A second pass
//!   does the same inside its free range: `C` is its `[10]` slots, software starts at
//!   `[7]` and hardware below `[3]`.
//! - The cull runs as an indirect dispatch of 64-thread workgroups over
//!   `cluster_count[0]` (plus `walked_cluster_count[0]` when that list is bound), `x × y`
//!   with both under the per-dimension limit (a one-thread dispatch writes the arguments
//!   into a scratch buffer and resets the counters).
//! - [`cpu::cpu_cull`] is the reference, mirroring the WGSL's f32 operations in order.
//!   The GPU tests compare sets exactly, allowing only clusters whose deciding value lies
//!   within a relative 1e-5 of its threshold ([`cpu::Decision::closeness`]); they count
//!   such clusters and assert there are at most 2 per view.

#![warn(missing_docs)]

pub mod cpu;

use meshlight_graph::AdapterClass;

/// A split larger than any viewport: every cluster to software but those crossing the
/// near plane.
pub const EVERY_CLUSTER_PX: f32 = 16384.0;

/// The `sw_threshold_px` that `"auto"` takes on an adapter of `class`, and why. Where
/// clusters switch from the software to the hardware rasteriser depends on how many of
/// the GPU's units run graphics work: the H100 and H200 run vertex and fragment work on
/// 2 of their TPCs only, so the compute rasteriser wins up to large clusters there.
pub fn sw_threshold_on(class: AdapterClass) -> (f32, &'static str) {
    match class {
        // Measured on an H200 (docs/BENCHMARKS.md): with big triangles tiled in
        // software, sending every cluster there (all but those crossing the near plane)
        // took the default scene at 3840×2160 from 3.49 to 1.62 ms and at 1920×1080
        // from 1.28 to 0.87 ms.
        AdapterClass::FewGraphicsUnits => (
            EVERY_CLUSTER_PX,
            "measured on an H200: hardware raster runs on 2 TPCs, and software with big triangles tiled wins at every cluster size, so only clusters crossing the near plane go to hardware",
        ),
        AdapterClass::Cpu => (
            EVERY_CLUSTER_PX,
            "a CPU adapter runs both rasterisers on the CPU; the data-centre split keeps its images comparable",
        ),
        // Not measured here: Nanite's rule of thumb sends clusters whose triangles are
        // about a pixel or smaller to software; a 128-triangle cluster under 32 px has
        // triangles of a few pixels.
        AdapterClass::Graphics => (
            32.0,
            "not measured on such a GPU: hardware raster is fast where every unit runs graphics, so only small clusters go to software",
        ),
    }
}

pub use cpu::{CullResult, Decision, Thresholds, cpu_cull};

use meshlight_gpu_scene::gpu::elements;
use meshlight_gpu_scene::instance_table::InstanceTable;
use meshlight_gpu_scene::view::frame_view;
use meshlight_gpu_scene::{ListPart, Phase, SceneBuffer::*, scene_reads};
use meshlight_graph::prelude::*;

/// The stage name pipelines use.
pub const STAGE: &str = "cull_lod";
/// The implementation name pipelines use.
pub const IMPLEMENTATION: &str = "compute";
/// The frame input holding the `View`.
pub const VIEW_INPUT: &str = "view";
/// The frame input (u32) a `first` pass with a pyramid reads: non-zero when the camera
/// jumped, so last frame's depth cannot hide anything.
pub const CAMERA_CUT_INPUT: &str = "camera_cut";
/// The pyramid's format.
pub const PYRAMID_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::R32Float;
/// Words of `raster_counts` with occlusion (8 without).
pub const OCCLUSION_COUNT_WORDS: u64 = 12;
/// The first pass's per-instance counter slot (see the crate docs).
pub const PER_INSTANCE_FIRST: &str = "occluded_per_instance";
/// The second pass's slot for the same buffer, read-write and not cleared.
pub const PER_INSTANCE_SECOND: &str = "still_occluded_per_instance";
/// The second pass's optional second list: the second hierarchy walk's clusters.
pub const WALKED_SLOT: &str = "walked_clusters";
/// The count words of `walked_clusters`: the second walk's `cluster_count`.
pub const WALKED_COUNT_SLOT: &str = "walked_cluster_count";
/// Streaming: per group, its error while its page is missing (bind the streamed scene's
/// `stream_errors` buffer). The streaming slots are named unlike the resources a frame
/// gives them, so that only the pass they are bound to takes them.
pub const STREAM_ERRORS_SLOT: &str = "page_errors";
/// Streaming: per group, 1 + the last frame its page was wanted; kept across frames.
pub const PAGE_MARKS_SLOT: &str = "page_marks";
/// Streaming: the pages wanted this frame, (group, priority bits) each.
pub const PAGE_REQUESTS_SLOT: &str = "page_requests";
/// Streaming: `[0]` requests written, `[1]` found.
pub const PAGE_REQUEST_COUNT_SLOT: &str = "page_request_count";
/// The element of `page_requests`: a group and its priority (f32 bits).
pub const PAGE_REQUEST: Element = Element::named("PageRequest", 8);

/// The program a first pass with a pyramid culls with when it tests nothing.
const UNTESTED_CULL: &str = "untested:cull";

/// The binding of the per-instance counters in cull.wgsl.
const PER_INSTANCE_BINDING: u32 = 16;

/// Threads per cull workgroup.
pub const WORKGROUP_SIZE: u32 = 64;

/// The stage's WGSL (`cull.wgsl`) with its uniform block, public so the shader tests
/// compose and validate every entry point.
pub const SHADER: PassShader = pass_shader!("cull_lod::cull", "cull.wgsl", params: GpuParams);

/// The slots every implementation of `cull_lod` shares.
pub fn contract() -> StageContract {
    StageContract {
        stage: STAGE,
        slots: [
            vec![
                    Slot::read("clusters", elements::CLUSTER, "candidate clusters"),
                    Slot::read(
                        "cluster_count",
                        Element::U32,
                        "[0]: valid entries of `clusters`",
                    ),
            ],
            scene_reads(&[Instances, Meshes, Meshlets, Groups]),
            vec![
                Slot::buffer(
                    "raster_clusters",
                    Access::StorageWrite,
                    elements::CLUSTER,
                    "software clusters from the left, hardware from the right",
                ),
                Slot::buffer(
                    "raster_counts",
                    Access::ClearedReadWrite,
                    Element::U32,
                    "sw, hw, requested, capacity, in frustum, sw triangles, hw triangles, first sw slot; with a pyramid: in cut, hidden, slots, testable",
                ),
                Slot::buffer(
                    "hw_args",
                    Access::ClearedReadWrite,
                    Element::DRAW_ARGS,
                    "[384, hardware clusters, 0, 0]",
                ),
                Slot::texture(
                    "pyramid",
                    Access::Sampled,
                    Some(PYRAMID_FORMAT),
                    "depth pyramid (farthest depth per texel, all mips): last frame's in the first pass, this frame's in the second",
                )
                .optional(),
                Slot::buffer(
                    "occluded",
                    Access::StorageWrite,
                    elements::CLUSTER,
                    "first pass: clusters found hidden, the second pass's candidates",
                )
                .optional(),
                Slot::buffer(
                    "occluded_count",
                    Access::ClearedReadWrite,
                    Element::U32,
                    "first pass: [0] candidates written, [1] found",
                )
                .optional(),
                Slot::read(
                    "first_counts",
                    Element::U32,
                    "second pass: the first pass's raster_counts",
                )
                .optional(),
                Slot::buffer(
                    PER_INSTANCE_FIRST,
                    Access::ClearedReadWrite,
                    Element::U32,
                    "first pass: per instance [2i] clusters in the LOD cut, [2i+1] found hidden",
                )
                .optional(),
                Slot::read(
                    WALKED_SLOT,
                    elements::CLUSTER,
                    "second pass: the second hierarchy walk's clusters, tested after `clusters`",
                )
                .optional(),
                Slot::read(
                    WALKED_COUNT_SLOT,
                    Element::U32,
                    "second pass: the second walk's cluster_count",
                )
                .optional(),
                Slot::buffer(
                    PER_INSTANCE_SECOND,
                    Access::StorageReadWrite,
                    Element::U32,
                    "second pass: the first pass's per-instance counters; [2i+1] less the candidates drawn",
                )
                .optional(),
                Slot::read(
                    STREAM_ERRORS_SLOT,
                    Element::F32,
                    "streaming: per group, its error while its page is missing, else 0",
                )
                .optional(),
                Slot::buffer(
                    PAGE_MARKS_SLOT,
                    Access::StorageReadWrite,
                    Element::U32,
                    "streaming: per group, 1 + the last frame its page was wanted (kept across frames)",
                )
                .optional(),
                Slot::buffer(
                    PAGE_REQUESTS_SLOT,
                    Access::StorageWrite,
                    PAGE_REQUEST,
                    "streaming: the pages wanted this frame, once each: (group, priority)",
                )
                .optional(),
                Slot::buffer(
                    PAGE_REQUEST_COUNT_SLOT,
                    Access::ClearedReadWrite,
                    Element::U32,
                    "streaming: [0] requests written, [1] found",
                )
                .optional(),
            ],
        ]
        .concat(),
    }
}

shader_defs! {
    /// The variant of cull.wgsl a pass runs.
    #[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
    pub struct CullDefs {
        /// A pyramid is bound and tested.
        pub occlusion: bool => "OCCLUSION",
        /// [`Phase::Second`].
        pub second: bool => "SECOND_PASS",
        /// The per-instance occlusion counters are bound.
        pub per_instance: bool => "PER_INSTANCE",
        /// A second pass with the second walk's list bound.
        pub walked: bool => "WALKED",
        /// The streaming slots are bound: clusters of the cut ask for their pages.
        pub streaming: bool => "STREAMING",
    }
}

/// The `compute` implementation.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct CullLod {
    /// The LOD and software thresholds, and whether a hardware rasteriser follows.
    pub thresholds: Thresholds,
    /// `sw_threshold_px = "auto"`: the split of the adapter's class
    /// ([`sw_threshold_on`]) instead of `thresholds.sw_threshold_px`.
    pub auto_split: bool,
    /// `hardware = "auto"`: a hardware rasteriser follows where the adapter's class
    /// rasterises in hardware at all (`AdapterClass::hardware_raster`, the rule
    /// `hw_raster`'s `run = "auto"` follows too), instead of `thresholds.hardware`.
    pub auto_hardware: bool,
    /// Which culling pass of the frame this is (`mode` in a pipeline file): the first
    /// tests against last frame's pyramid, the second re-tests what the first hid.
    pub phase: Phase,
    /// Raster slots `C`; `None`: as many as `raster_clusters` holds.
    pub capacity: Option<u32>,
    /// A per-dimension limit below the adapter's (tests use small ones); `None`: the
    /// adapter's `max_compute_workgroups_per_dimension`.
    pub max_per_dimension: Option<u32>,
    /// The list of `clusters` and `cluster_count` it reads, where the buffers hold one
    /// list per view (params `list` and `lists`; one list by default).
    pub part: ListPart,
    /// Streaming: add this pass's page requests to those of the culls before it (a
    /// shadow view's after the camera's) instead of starting the frame's list
    /// (`append_requests`; off by default). The page marks keep each page listed once a
    /// frame across the views, whose Views carry the same frame index.
    pub append_requests: bool,
}

uniform_block! {
    /// The uniform of cull.wgsl, which imports the struct from this declaration.
    struct GpuParams as "Params" in "cull_lod::params" {
        /// Slots the raster list may use; clamped to the bound list's length.
        capacity: u32,
        /// The per-dimension workgroup limit the indirect dispatch must stay under.
        max_per_dimension: u32,
        /// A cluster is in the LOD cut when its own error projects to at most this many
        /// pixels and its parent's to more.
        lod_threshold_px: f32,
        /// Clusters whose screen box is narrower and shorter than this go to software.
        sw_threshold_px: f32,
        /// 0: every cluster of the cut goes to software (no hardware rasteriser).
        hardware: u32,
        /// 1: test occlusion against `pyramid`; 0: skip it (no valid history, camera cut).
        test_occlusion: u32,
        /// The list of the candidate buffers read ([`ListPart`]), and how many they hold.
        list: u32,
        lists: u32,
        /// 1: keep the page requests of the culls before (`append_requests`).
        append_requests: u32,
        pad_a: u32,
        pad_b: u32,
        pad_c: u32,
    }
}

const PARAM_KEYS: [&str; 9] = [
    "append_requests",
    "list",
    "lists",
    "lod_threshold_px",
    "sw_threshold_px",
    "hardware",
    "mode",
    "capacity",
    "max_per_dimension",
];

impl CullLod {
    /// Reads the params of the table in the crate docs.
    pub fn from_params(params: &Params) -> Result<Self> {
        params.only(&PARAM_KEYS)?;
        let defaults = Thresholds::default();
        let phase = Phase::from_params(params)?;
        let split = params.f32_or_auto("sw_threshold_px", Some(defaults.sw_threshold_px))?;
        let hardware = params.bool_or_auto("hardware", Some(defaults.hardware))?;
        let nonzero = |v: u32| (v > 0).then_some(v);
        let pass = Self {
            thresholds: Thresholds {
                lod_threshold_px: params.f32("lod_threshold_px", defaults.lod_threshold_px)?,
                sw_threshold_px: split.unwrap_or(defaults.sw_threshold_px),
                hardware: hardware.unwrap_or(defaults.hardware),
            },
            auto_split: split.is_none(),
            auto_hardware: hardware.is_none(),
            phase,
            capacity: nonzero(params.u32("capacity", 0)?),
            max_per_dimension: nonzero(params.u32("max_per_dimension", 0)?),
            part: ListPart::from_params(params, 1)?,
            append_requests: params.bool("append_requests", false)?,
        };
        pass.check_thresholds()?;
        Ok(pass)
    }

    fn check_phase(&self, ctx: &SetupContext) -> Result<bool> {
        let bound = |slot| ctx.is_bound(slot);
        let occlusion = bound("pyramid");
        match self.phase {
            Phase::First if occlusion && !(bound("occluded") && bound("occluded_count")) => {
                Err(GraphError::parameter(
                    "a first pass with a `pyramid` needs `occluded` and `occluded_count` bound: the clusters it finds hidden go there for the second pass",
                ))
            }
            Phase::First if !occlusion && (bound("occluded") || bound("first_counts")) => {
                Err(GraphError::parameter(
                    "`occluded` or `first_counts` is bound but `pyramid` is not: bind last frame's pyramid to test occlusion, or unbind them",
                ))
            }
            Phase::First if bound("first_counts") => Err(GraphError::parameter(
                "`first_counts` is for `mode = \"second\"`; unbind it from the first pass",
            )),
            Phase::Second if !(occlusion && bound("first_counts")) => Err(GraphError::parameter(
                "`mode = \"second\"` needs `pyramid` (this frame's) and `first_counts` (the first pass's raster_counts) bound",
            )),
            Phase::Second if bound("occluded") || bound("occluded_count") => {
                Err(GraphError::parameter(
                    "`occluded` and `occluded_count` are the first pass's outputs, to bind to the second pass as `clusters` and `cluster_count`; give them resource names other than the slots' (e.g. `candidates`, `candidate_count`), or the second pass binds them by name",
                ))
            }
            _ if self.phase == Phase::First && (bound(WALKED_SLOT) || bound(WALKED_COUNT_SLOT)) => {
                Err(GraphError::parameter(format!(
                    "`{WALKED_SLOT}` is the second walk's list, for `mode = \"second\"`; unbind it from the first pass"
                )))
            }
            _ if bound(WALKED_SLOT) != bound(WALKED_COUNT_SLOT) => {
                Err(GraphError::parameter(format!(
                    "bind `{WALKED_SLOT}` and `{WALKED_COUNT_SLOT}` together (the second walk's `clusters` and `cluster_count`), or neither"
                )))
            }
            _ => Ok(occlusion),
        }
    }

    /// The per-instance counter slot this pass uses, if bound: `occluded_per_instance`
    /// in a first pass with a pyramid, `still_occluded_per_instance` in a second.
    fn per_instance_slot(
        &self,
        ctx: &SetupContext,
        occlusion: bool,
    ) -> Result<Option<&'static str>> {
        let (mine, other) = match self.phase {
            Phase::First => (PER_INSTANCE_FIRST, PER_INSTANCE_SECOND),
            Phase::Second => (PER_INSTANCE_SECOND, PER_INSTANCE_FIRST),
        };
        if ctx.is_bound(other) {
            return Err(GraphError::parameter(format!(
                "`{other}` is bound to a `mode = \"{}\"` pass, which counts per instance in `{mine}`; a first pass clears and fills `{PER_INSTANCE_FIRST}`, the second updates the same buffer as `{PER_INSTANCE_SECOND}` (name the resource unlike both slots, or the second pass binds it by name)",
                self.phase.name()
            )));
        }
        if !ctx.is_bound(mine) {
            return Ok(None);
        }
        if !occlusion {
            return Err(GraphError::parameter(format!(
                "`{mine}` counts what occlusion culls, and this pass has no `pyramid` bound; bind one or unbind `{mine}`"
            )));
        }
        Ok(Some(mine))
    }

    /// Whether the streaming slots are bound (all four, to a first pass), or an error
    /// saying what to bind.
    fn check_streaming(&self, ctx: &SetupContext) -> Result<bool> {
        let slots = [
            STREAM_ERRORS_SLOT,
            PAGE_MARKS_SLOT,
            PAGE_REQUESTS_SLOT,
            PAGE_REQUEST_COUNT_SLOT,
        ];
        let bound = slots.iter().filter(|s| ctx.is_bound(s)).count();
        match bound {
            0 => Ok(false),
            4 if self.phase == Phase::First => Ok(true),
            4 => Err(GraphError::parameter(
                "the streaming slots are bound to a `mode = \"second\"` pass; the first pass asks for the pages of the whole cut, so bind them there only",
            )),
            _ => Err(GraphError::parameter(format!(
                "bind all four streaming slots ({}) or none: {bound} of them are bound",
                slots.join(", ")
            ))),
        }
    }

    /// The thresholds the pass uses on an adapter of `class`: its own, with those it
    /// left `auto` taken from the class.
    pub fn thresholds_on(&self, class: AdapterClass) -> Thresholds {
        Thresholds {
            sw_threshold_px: if self.auto_split {
                sw_threshold_on(class).0
            } else {
                self.thresholds.sw_threshold_px
            },
            hardware: if self.auto_hardware {
                class.hardware_raster().0
            } else {
                self.thresholds.hardware
            },
            ..self.thresholds
        }
    }

    fn check_thresholds(&self) -> Result<()> {
        for (key, v) in [
            ("lod_threshold_px", self.thresholds.lod_threshold_px),
            ("sw_threshold_px", self.thresholds.sw_threshold_px),
        ] {
            if !(v.is_finite() && v >= 0.0) {
                return Err(GraphError::parameter(format!(
                    "`{key}` = {v} must be a finite number of pixels >= 0"
                )));
            }
        }
        Ok(())
    }
}

impl Pass for CullLod {
    fn implementation(&self) -> Implementation {
        let mut contract = contract();
        if self.append_requests {
            // The requests of the culls before are kept: the list is read, not restarted.
            for slot in contract
                .slots
                .iter_mut()
                .filter(|s| [PAGE_REQUESTS_SLOT, PAGE_REQUEST_COUNT_SLOT].contains(&s.name))
            {
                slot.access = Access::StorageReadWrite;
            }
        }
        Implementation::new(IMPLEMENTATION, contract)
    }
    fn setup(&self, ctx: &mut SetupContext) -> Result<()> {
        self.check_thresholds()?;
        let class = ctx.adapter_class();
        let on = self.thresholds_on(class);
        if self.auto_split {
            let why = sw_threshold_on(class).1;
            ctx.note(format!(
                "`sw_threshold_px = \"auto\"`: {} px on a {} ({why})",
                on.sw_threshold_px,
                class.name()
            ));
        }
        if self.auto_hardware {
            let why = class.hardware_raster().1;
            ctx.note(format!(
                "`hardware = \"auto\"`: {} on a {} ({why})",
                if on.hardware {
                    "clusters go to hardware"
                } else {
                    "every cluster to software"
                },
                class.name()
            ));
        }
        ctx.check_max_per_dimension(self.max_per_dimension)?;
        let occlusion = self.check_phase(ctx)?;
        let second = self.phase == Phase::Second;
        let per_instance = self.per_instance_slot(ctx, occlusion)?;
        let walked = second && ctx.is_bound(WALKED_SLOT);
        let streaming = self.check_streaming(ctx)?;
        let defs = CullDefs {
            occlusion,
            second,
            per_instance: per_instance.is_some(),
            walked,
            streaming,
        };
        if streaming {
            ctx.min_bytes(PAGE_REQUEST_COUNT_SLOT, 8);
        }
        ctx.shader_defs(&defs);
        let table = InstanceTable::of(ctx);
        ctx.shader_defs(&table);
        ctx.min_bytes("cluster_count", 8 * u64::from(self.part.list) + 4);
        let words = if occlusion { OCCLUSION_COUNT_WORDS } else { 8 };
        ctx.min_bytes("raster_counts", words * 4);
        ctx.min_bytes("hw_args", 16);
        ctx.frame_input(VIEW_INPUT);
        if occlusion && !second {
            ctx.min_bytes("occluded_count", 8);
            ctx.frame_input(CAMERA_CUT_INPUT);
        }
        if second {
            ctx.min_bytes("first_counts", OCCLUSION_COUNT_WORDS * 4);
        }
        ctx.scratch_buffer(
            "dispatch",
            BufferDesc::array(Element::DISPATCH_ARGS, 1),
            &[Access::StorageWrite, Access::StorageRead, Access::Indirect],
        );
        // Bindings from the shader. Named here: the dispatch arguments, which `prepare`
        // writes as `dispatch_out` and `cull` reads as `dispatch_in` (two variables, one
        // scratch buffer), and the per-instance counters, one variable for the two slots
        // of the two modes.
        let prepare = BindingLayout::from_shader("cull_lod::prepare").scratch(
            8,
            "dispatch",
            Access::StorageWrite,
        );
        let mut cull = BindingLayout::from_shader("cull_lod::cull").scratch(
            9,
            "dispatch",
            Access::StorageRead,
        );
        if occlusion {
            if second && walked {
                ctx.min_bytes(WALKED_COUNT_SLOT, 4);
            }
            if let Some(slot) = per_instance {
                cull = cull.slot(PER_INSTANCE_BINDING, slot);
            }
        }
        ctx.program(
            "prepare",
            ProgramDesc::compute(&SHADER, "prepare")
                .defs(&defs)
                .defs(&table)
                .layout(prepare),
        );
        ctx.program(
            "cull",
            ProgramDesc::compute(&SHADER, "cull")
                .defs(&defs)
                .defs(&table)
                .layout(cull),
        );
        if occlusion && !second && per_instance.is_none() {
            // A frame that tests nothing (no history, a camera cut, a renderer leaving
            // occlusion out) culls without the test compiled in; `prepare` is the
            // occlusion variant's, which zeroes the candidates' count a second pass
            // may read.
            let untested = CullDefs {
                occlusion: false,
                ..defs
            };
            ctx.program(
                UNTESTED_CULL,
                ProgramDesc::compute(&SHADER, "cull")
                    .defs(&untested)
                    .defs(&table)
                    .layout(BindingLayout::from_shader("cull_lod::cull").scratch(
                        9,
                        "dispatch",
                        Access::StorageRead,
                    )),
            );
        }
        Ok(())
    }
    fn record(&self, ctx: &mut RecordContext<'_>) -> Result<()> {
        let view = frame_view(ctx, VIEW_INPUT, None)?;
        let test_occlusion = ctx.is_bound("pyramid")
            && match self.phase {
                Phase::Second => true,
                Phase::First => {
                    ctx.history_valid("pyramid")? && ctx.frame_u32(CAMERA_CUT_INPUT)? == 0
                }
            };
        let thresholds = self.thresholds_on(ctx.adapter_class());
        let params = GpuParams {
            capacity: self.capacity.unwrap_or(u32::MAX),
            max_per_dimension: ctx.max_per_dimension(self.max_per_dimension),
            lod_threshold_px: thresholds.lod_threshold_px,
            sw_threshold_px: thresholds.sw_threshold_px,
            hardware: thresholds.hardware as u32,
            test_occlusion: test_occlusion as u32,
            list: self.part.list,
            lists: self.part.lists,
            append_requests: self.append_requests as u32,
            ..GpuParams::default()
        };
        let (view, params) = (bytemuck::bytes_of(&view), bytemuck::bytes_of(&params));
        if self.phase == Phase::First && ctx.is_bound(PER_INSTANCE_FIRST) {
            ctx.clear(PER_INSTANCE_FIRST)?;
        }
        let (dispatch, _) = ctx.scratch("dispatch")?;
        ctx.dispatch_compute(
            "prepare",
            &[("params", params)],
            Workgroups::Direct([1, 1, 1]),
        )?;
        // A second dispatch: the counters and arguments are written before any cluster
        // reads them.
        let untested = ctx.is_bound("pyramid")
            && self.phase == Phase::First
            && !test_occlusion
            && !ctx.is_bound(PER_INSTANCE_FIRST);
        ctx.dispatch_compute(
            if untested { UNTESTED_CULL } else { "cull" },
            &[("view", view), ("params", params)],
            Workgroups::Indirect(dispatch, 0),
        )
    }
}

/// Registers `cull_lod` (implementation `compute`) for pipeline files.
pub fn register(registry: &mut Registry) {
    registry.register(STAGE, IMPLEMENTATION, CullLod::from_params);
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Builds a one-pass pipeline with `params` for the pass (`{ … }` contents).
    fn pipeline(params: &str) -> Result<()> {
        pipeline_with(params, &[]).map(drop)
    }

    /// The same with more u32 buffers, which bind to the slots of their names.
    fn pipeline_with(params: &str, extra: &[&str]) -> Result<meshlight_graph::GraphBuilder> {
        let mut registry = Registry::new();
        register(&mut registry);
        let buffer = |name: &str, kind: &str, element: &str, size: u32, count: u32| {
            let usage = if kind == "imported" {
                "usage = [\"STORAGE\"]\n"
            } else {
                ""
            };
            format!(
                "[[resource]]\nname = \"{name}\"\nkind = \"{kind}\"\nbuffer = {{ element = \"{element}\", element_size = {size}, count = {count} }}\n{usage}"
            )
        };
        let text = [
            buffer("clusters", "imported", "Cluster", 8, 16),
            buffer("cluster_count", "imported", "u32", 4, 2),
            buffer("instances", "imported", "Instance", 224, 1),
            buffer("meshes", "imported", "Mesh", 64, 1),
            buffer("meshlets", "imported", "Meshlet", 52, 1),
            buffer("meshlet_groups", "imported", "MeshletGroup", 32, 1),
            buffer("raster_clusters", "exported", "Cluster", 8, 16),
            buffer("raster_counts", "exported", "u32", 4, 8),
            buffer("hw_args", "exported", "DrawIndirectArgs", 16, 1),
            extra
                .iter()
                .map(|name| buffer(name, "exported", "u32", 4, 2))
                .collect(),
            format!(
                "[[pass]]\nname = \"cull\"\nstage = \"cull_lod\"\nimplementation = \"compute\"\nparams = {{ {params} }}\n"
            ),
        ]
        .concat();
        meshlight_graph::file::parse_pipeline(&text, "test.toml", &registry)
    }

    #[test]
    fn params_parse_integers_floats_and_the_mode() {
        meshlight_testing::assert_params(
            pipeline,
            &[
                "",
                "lod_threshold_px = 2",
                "lod_threshold_px = 0.5, sw_threshold_px = 16.0, mode = \"first\"",
                "capacity = 100, max_per_dimension = 7",
            ],
            &[
                ("lod_treshold_px = 1.0", "lod_treshold_px"),
                ("lod_threshold_px = -1.0", "lod_threshold_px"),
                ("sw_threshold_px = nan", "sw_threshold_px"),
                ("sw_threshold_px = true", "sw_threshold_px"),
                ("mode = \"third\"", "mode"),
                ("capacity = 1.5", "capacity"),
                ("hardware = 1", "hardware"),
            ],
        );
    }

    #[test]
    fn per_instance_counters_need_a_pyramid_and_the_slot_of_their_mode() {
        for (extra, wanted) in [
            // Without a pyramid nothing is culled by occlusion: nothing to count.
            (PER_INSTANCE_FIRST, "no `pyramid`"),
            // The second pass's slot bound to a first pass.
            (
                PER_INSTANCE_SECOND,
                "`still_occluded_per_instance` is bound",
            ),
        ] {
            // Setup runs when the graph compiles (planning needs no device).
            let options = meshlight_graph::CompileOptions::new(wgpu::Features::empty());
            match pipeline_with("", &[extra]).and_then(|g| g.compile(&options)) {
                Err(GraphError::Parameter { message, .. }) => {
                    assert!(message.contains(wanted), "{extra}: {message}")
                }
                other => panic!("{extra}: {:?}", other.err()),
            }
        }
    }
}
