//! Stage `cull_lod`, implementation `compute`: per cluster, the frustum test, the LOD
//! cut, and the choice of rasteriser, into one shared slot buffer.
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
//! | `meshes`          | storage read       | Mesh    | the GPU scene (reserved for the occlusion pass; `compute` binds it to nothing) |
//! | `meshlets`        | storage read       | Meshlet | bounds, groups, triangle counts |
//! | `meshlet_groups`  | storage read       | MeshletGroup | LOD spheres and errors |
//! | `raster_clusters` | storage write      | Cluster | `C` slots: software in `0..[0]`, hardware in `C-[1]..C` |
//! | `raster_counts`   | cleared read-write | u32 × 8 | the words below |
//! | `hw_args`         | cleared read-write | DrawIndirectArgs | `[384, hardware clusters, 0, 0]` for `draw_indirect` |
//!
//! `raster_counts`: `[0]` software clusters, `[1]` hardware clusters, `[2]` clusters
//! that passed frustum and LOD (slots requested, may exceed `C`), `[3]` `C`, `[4]`
//! clusters that passed the frustum test, `[5]` software triangles, `[6]` hardware
//! triangles, `[7]` 0. Overflow = `max(0, [2] - [3])`. Frame input `view`
//! (`meshlight_shaders::cpu::layout::View`).
//!
//! | param               | default | |
//! |---------------------|---------|---|
//! | `lod_threshold_px`  | 1.0     | screen-space error (pixels) a cluster may show |
//! | `sw_threshold_px`   | 128.0   | screen-box size under which a cluster goes to software (tuned on an H100, where few units run graphics: docs/BENCHMARKS.md) |
//! | `hardware`          | true    | false: every cluster to software (a pipeline with no `hw_raster`) |
//! | `mode`              | `"first"` | `first`: every candidate, no occlusion. Reserved: `second`, the re-test of the first pass's occluded clusters against this frame's depth pyramid |
//! | `capacity`          | 0 (all of `raster_clusters`) | `C`, at most the buffer's size / 8 |
//! | `max_per_dimension` | 0 (the adapter's) | workgroup limit per dimension of the indirect cull dispatch |
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
//!   `[1]`). So `[0] + [1] = min([2], C)` and no slot is written twice.
//! - The cull runs as an indirect dispatch of 64-thread workgroups over
//!   `cluster_count[0]`, `x × y` with both under the per-dimension limit (a one-thread
//!   dispatch writes the arguments into a scratch buffer and resets the counters).
//! - [`cpu::cpu_cull`] is the reference, mirroring the WGSL's f32 operations in order.
//!   The GPU tests compare sets exactly, allowing only clusters whose deciding value lies
//!   within a relative 1e-5 of its threshold ([`cpu::Decision::closeness`]); they count
//!   such clusters and assert there are at most 2 per view.

pub mod cpu;

pub use cpu::{CullResult, Decision, Thresholds, cpu_cull};

use meshlight_gpu_scene::gpu::elements;
use meshlight_gpu_scene::view::frame_view;
use meshlight_graph::file::{Params, Registry};
use meshlight_graph::{
    Access, BindingLayout, BufferDesc, Element, GraphError, Pass, ProgramDesc, RecordContext,
    Result, SetupContext, Slot, StageContract,
};
use meshlight_shaders::{PassShader, pass_shader};

/// The stage name pipelines use.
pub const STAGE: &str = "cull_lod";
/// The implementation name pipelines use.
pub const IMPLEMENTATION: &str = "compute";
/// The frame input holding the `View`.
pub const VIEW_INPUT: &str = "view";
/// Threads per cull workgroup.
pub const WORKGROUP_SIZE: u32 = 64;

pub const SHADER: PassShader = pass_shader!("cull_lod::cull", "cull.wgsl");

/// The slots every implementation of `cull_lod` shares.
pub fn contract() -> StageContract {
    let read = |name, element, doc| Slot::buffer(name, Access::StorageRead, element, doc);
    StageContract {
        stage: STAGE,
        slots: vec![
            read("clusters", elements::CLUSTER, "candidate clusters"),
            read(
                "cluster_count",
                Element::U32,
                "[0]: valid entries of `clusters`",
            ),
            read("instances", elements::INSTANCE, "the scene's instances"),
            read("meshes", elements::MESH, "the scene's meshes"),
            read("meshlets", elements::MESHLET, "the scene's meshlets"),
            read(
                "meshlet_groups",
                elements::GROUP,
                "the scene's simplification groups",
            ),
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
                "sw, hw, requested, capacity, in frustum, sw triangles, hw triangles, 0",
            ),
            Slot::buffer(
                "hw_args",
                Access::ClearedReadWrite,
                Element::DRAW_ARGS,
                "[384, hardware clusters, 0, 0]",
            ),
        ],
    }
}

/// Which culling pass of the frame this is.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Mode {
    /// Every candidate, with no occlusion test.
    #[default]
    First,
}

impl Mode {
    pub fn name(self) -> &'static str {
        match self {
            Mode::First => "first",
        }
    }
}

/// The `compute` implementation.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct CullLod {
    pub thresholds: Thresholds,
    pub mode: Mode,
    /// Raster slots `C`; `None`: as many as `raster_clusters` holds.
    pub capacity: Option<u32>,
    /// A per-dimension limit below the adapter's (tests use small ones); `None`: the
    /// adapter's `max_compute_workgroups_per_dimension`.
    pub max_per_dimension: Option<u32>,
}

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct GpuParams {
    capacity: u32,
    max_per_dimension: u32,
    lod_threshold_px: f32,
    sw_threshold_px: f32,
    hardware: u32,
    _pad: [u32; 3],
}

const PARAM_KEYS: [&str; 6] = [
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
        let mode = match params.string("mode", "first")?.as_str() {
            "first" => Mode::First,
            other => {
                return Err(GraphError::parameter(format!(
                    "`mode` = \"{other}\" is not built; the only mode is \"first\" (the second, occlusion pass is not available yet)"
                )));
            }
        };
        let nonzero = |v: u32| (v > 0).then_some(v);
        let pass = Self {
            thresholds: Thresholds {
                lod_threshold_px: params.f32("lod_threshold_px", defaults.lod_threshold_px)?,
                sw_threshold_px: params.f32("sw_threshold_px", defaults.sw_threshold_px)?,
                hardware: params.bool("hardware", true)?,
            },
            mode,
            capacity: nonzero(params.u32("capacity", 0)?),
            max_per_dimension: nonzero(params.u32("max_per_dimension", 0)?),
        };
        pass.check_thresholds()?;
        Ok(pass)
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
    fn contract(&self) -> StageContract {
        contract()
    }
    fn implementation(&self) -> &'static str {
        IMPLEMENTATION
    }
    fn setup(&self, ctx: &mut SetupContext) -> Result<()> {
        self.check_thresholds()?;
        let limit = ctx.limits().max_compute_workgroups_per_dimension;
        if let Some(m) = self.max_per_dimension
            && m > limit
        {
            return Err(GraphError::parameter(format!(
                "`max_per_dimension` = {m} is above the adapter's limit of {limit}; leave it out to use the limit"
            )));
        }
        ctx.min_bytes("cluster_count", 4);
        ctx.min_bytes("raster_counts", 32);
        ctx.min_bytes("hw_args", 16);
        ctx.frame_input(VIEW_INPUT);
        ctx.scratch_buffer(
            "dispatch",
            BufferDesc::array(Element::DISPATCH_ARGS, 1),
            &[Access::StorageWrite, Access::StorageRead, Access::Indirect],
        );
        let prepare = BindingLayout::compute("cull_lod::prepare")
            .slot(0, "clusters")
            .slot(1, "cluster_count")
            .slot(5, "raster_clusters")
            .slot(6, "raster_counts")
            .slot(7, "hw_args")
            .scratch(8, "dispatch", Access::StorageWrite)
            .uniform(11);
        let cull = BindingLayout::compute("cull_lod::cull")
            .slot(0, "clusters")
            .slot(1, "cluster_count")
            .slot(2, "instances")
            .slot(3, "meshlets")
            .slot(4, "meshlet_groups")
            .slot(5, "raster_clusters")
            .slot(6, "raster_counts")
            .slot(7, "hw_args")
            .scratch(9, "dispatch", Access::StorageRead)
            .uniform(10)
            .uniform(11);
        ctx.program(
            "prepare",
            ProgramDesc::compute(&SHADER, "prepare").layout(prepare),
        );
        ctx.program("cull", ProgramDesc::compute(&SHADER, "cull").layout(cull));
        Ok(())
    }
    fn record(&self, ctx: &mut RecordContext<'_>) -> Result<()> {
        let view = frame_view(ctx, VIEW_INPUT, None)?;
        let limit = ctx.device().limits().max_compute_workgroups_per_dimension;
        let params = GpuParams {
            capacity: self.capacity.unwrap_or(u32::MAX),
            max_per_dimension: self.max_per_dimension.unwrap_or(limit).min(limit),
            lod_threshold_px: self.thresholds.lod_threshold_px,
            sw_threshold_px: self.thresholds.sw_threshold_px,
            hardware: self.thresholds.hardware as u32,
            _pad: [0; 3],
        };
        let prepare = ctx.compute("prepare")?;
        let cull = ctx.compute("cull")?;
        let prepare_group = ctx.bind_group(&prepare, 0, &[(11, bytemuck::bytes_of(&params))])?;
        let cull_group = ctx.bind_group(
            &cull,
            0,
            &[
                (10, bytemuck::bytes_of(&view)),
                (11, bytemuck::bytes_of(&params)),
            ],
        )?;
        let (dispatch, _) = ctx.scratch("dispatch")?;
        {
            let mut pass = ctx.compute_pass();
            pass.set_pipeline(&prepare.pipeline);
            pass.set_bind_group(0, &prepare_group, &[]);
            pass.dispatch_workgroups(1, 1, 1);
        }
        // A second compute pass: the counters and arguments are written before any
        // cluster reads them.
        let mut pass = ctx.compute_pass();
        pass.set_pipeline(&cull.pipeline);
        pass.set_bind_group(0, &cull_group, &[]);
        pass.dispatch_workgroups_indirect(dispatch, 0);
        Ok(())
    }
}

fn build(params: &Params) -> Result<Box<dyn Pass>> {
    Ok(Box::new(CullLod::from_params(params)?))
}

/// Registers `cull_lod` (implementation `compute`) for pipeline files.
pub fn register(registry: &mut Registry) {
    registry.register(STAGE, IMPLEMENTATION, build);
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Builds a one-pass pipeline with `params` for the pass (`{ … }` contents).
    fn pipeline(params: &str) -> Result<()> {
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
            format!(
                "[[pass]]\nname = \"cull\"\nstage = \"cull_lod\"\nimplementation = \"compute\"\nparams = {{ {params} }}\n"
            ),
        ]
        .concat();
        meshlight_graph::file::parse_pipeline(&text, "test.toml", &registry).map(drop)
    }

    #[test]
    fn params_parse_integers_floats_and_the_mode() {
        for ok in [
            "",
            "lod_threshold_px = 2",
            "lod_threshold_px = 0.5, sw_threshold_px = 16.0, mode = \"first\"",
            "capacity = 100, max_per_dimension = 7",
        ] {
            if let Err(e) = pipeline(ok) {
                panic!("{ok}: {e}");
            }
        }
        for (bad, key) in [
            ("lod_treshold_px = 1.0", "lod_treshold_px"),
            ("lod_threshold_px = -1.0", "lod_threshold_px"),
            ("sw_threshold_px = nan", "sw_threshold_px"),
            ("sw_threshold_px = true", "sw_threshold_px"),
            ("mode = \"second\"", "mode"),
            ("capacity = 1.5", "capacity"),
            ("hardware = 1", "hardware"),
        ] {
            match pipeline(bad) {
                Err(GraphError::Parameter { message, .. }) => {
                    assert!(message.contains(key), "{bad}: {message}")
                }
                other => panic!("{bad}: {:?}", other.err()),
            }
        }
    }
}
