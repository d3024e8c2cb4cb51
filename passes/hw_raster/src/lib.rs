//! Stage `hw_raster`, implementation `indirect_draw`: the clusters culling sent to the
//! hardware rasteriser (large on screen, or crossing the near plane) drawn with one
//! indirect draw into the same 64-bit visibility buffer the software rasteriser fills.
//!
//! Culling appends hardware clusters from the right end of the shared slot buffer and
//! counts them in `hw_args[1]`, so `draw_indirect` of `[384, count, 0, 0]` draws one
//! instance of 128 × 3 vertices per cluster, with no count read back to the CPU.
//! Instance `j` draws slot `C - 1 - j` (`C = raster_counts[3]`); the vertex shader pulls
//! its corner from the compressed payload, and corners of triangles past the meshlet's
//! triangle count become NaN, which the rasteriser drops. The fragment shader does the
//! software rasteriser's `atomicMax(depth << 32 | slot << 7 | triangle)`; the colour
//! target exists only because a render pipeline needs one and is never written.
//!
//! # Contract
//!
//! | slot | access | holds | |
//! |------|--------|-------|---|
//! | `raster_clusters` | storage read | Cluster | hardware clusters in slots `C - hw_count .. C` |
//! | `raster_counts` | storage read | u32 | word 3: `C`, the slot capacity |
//! | `hw_args` | indirect | DrawIndirectArgs | `[384, hw_count, 0, 0]` from `cull_lod` |
//! | `instances`, `meshes`, `meshlets`, `payload` | storage read | scene | the GPU scene |
//! | `visbuffer` | storage read-write | u64 | `width × height`, row-major; atomicMax onto what `sw_raster` left |
//!
//! Frame input `view` (`meshlight_shaders::cpu::layout::View`): its `viewport_size` must
//! equal the params `width` × `height` (a record error names both otherwise).
//! Scratch: `target`, an `R8Unorm` colour target of the viewport size, masked, cleared
//! and discarded. Needs `SHADER_INT64 | SHADER_INT64_ATOMIC_MIN_MAX`.
//!
//! # Definitions the tests pin down
//!
//! - The visibility id of a hardware cluster is its slot, `C - 1 - j` for instance `j`.
//! - Clip position: `view_projection * (world_from_local * position).xyz1`, the software
//!   rasteriser's operations, so both rasterisers start from the same bits.
//! - Front faces are counter-clockwise in NDC (clockwise on the y-down screen); back
//!   faces are culled. No depth attachment: the visibility buffer's atomicMax is the
//!   depth test. Depth is the fragment's `position.z` (NDC z, interpolated by the
//!   hardware linearly in screen space).
//! - Coverage is the hardware's: pixel centres, top-left rule, its sub-pixel precision
//!   (8 bits on lavapipe, like the software rasteriser's fixed point). The two differ on
//!   pixels whose centre lies within rounding of an edge and in the last bits of depth;
//!   the GPU test states the tolerance. Unlike the software rasteriser, the hardware
//!   clips triangles at the near plane instead of skipping them.
//! - [`cpu::rasterize`] is the reference (float edge functions at pixel centres).

pub mod cpu;

use meshlight_gpu_scene::gpu::elements;
use meshlight_gpu_scene::view::frame_view;
use meshlight_graph::file::{Params, Registry};
use meshlight_graph::{
    Access, BindingLayout, ColorAttachment, ColorTarget, Element, GraphError, Pass, Primitive,
    ProgramDesc, RecordContext, Result, SetupContext, Slot, StageContract, TextureDesc,
};
use meshlight_shaders::{PassShader, pass_shader};

/// The stage name pipelines use.
pub const STAGE: &str = "hw_raster";
/// The frame input holding the `View`.
pub const VIEW_INPUT: &str = "view";
/// Vertices per cluster instance: 128 triangles of 3 corners.
pub const VERTICES_PER_CLUSTER: u32 = 384;
/// The bits of the NaN that discarded corners take (a quiet NaN).
pub const NAN_BITS: u32 = 0x7fc0_0000;
/// The scratch colour target.
const TARGET: &str = "target";

pub const SHADER: PassShader = pass_shader!("hw_raster::raster", "raster.wgsl");

/// The slots every implementation of `hw_raster` shares.
pub fn contract() -> StageContract {
    let read = |name, element, doc| Slot::buffer(name, Access::StorageRead, element, doc);
    StageContract {
        stage: STAGE,
        slots: vec![
            read(
                "raster_clusters",
                elements::CLUSTER,
                "hardware clusters from the right end",
            ),
            read("raster_counts", Element::U32, "word 3: the slot capacity C"),
            Slot::buffer(
                "hw_args",
                Access::Indirect,
                Element::DRAW_ARGS,
                "[384, hardware cluster count, 0, 0]",
            ),
            read("instances", elements::INSTANCE, "the scene's instances"),
            read("meshes", elements::MESH, "the scene's meshes"),
            read("meshlets", elements::MESHLET, "the scene's meshlets"),
            read("payload", Element::U32, "the scene's meshlet payload"),
            Slot::buffer(
                "visbuffer",
                Access::StorageReadWrite,
                Element::U64,
                "width × height visibility values; atomicMax onto the software raster's",
            ),
        ],
    }
}

/// The `indirect_draw` implementation.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct HwRaster {
    pub width: u32,
    pub height: u32,
}

#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct GpuParams {
    width: u32,
    height: u32,
    nan_bits: u32,
    _pad: u32,
}

const PARAM_KEYS: [&str; 2] = ["width", "height"];

impl HwRaster {
    /// Reads `width` and `height` (required, > 0: the visibility buffer size).
    pub fn from_params(params: &Params) -> Result<Self> {
        params.only(&PARAM_KEYS)?;
        let width = params.u32("width", 0)?;
        let height = params.u32("height", 0)?;
        if width == 0 || height == 0 {
            return Err(GraphError::Parameter {
                pass: String::new(),
                message: format!(
                    "`width` and `height` (the visibility buffer size) must both be > 0, got {width} × {height}"
                ),
            });
        }
        Ok(Self { width, height })
    }
}

impl Pass for HwRaster {
    fn contract(&self) -> StageContract {
        contract()
    }
    fn implementation(&self) -> &'static str {
        "indirect_draw"
    }
    fn setup(&self, ctx: &mut SetupContext) -> Result<()> {
        ctx.require_features(
            wgpu::Features::SHADER_INT64 | wgpu::Features::SHADER_INT64_ATOMIC_MIN_MAX,
        );
        ctx.min_bytes("visbuffer", self.width as u64 * self.height as u64 * 8);
        ctx.min_bytes("raster_counts", 16);
        ctx.min_bytes("hw_args", 16);
        ctx.frame_input(VIEW_INPUT);
        ctx.scratch_texture(
            TARGET,
            TextureDesc::d2(wgpu::TextureFormat::R8Unorm, self.width, self.height),
            &[Access::RenderTarget],
        );
        let vertex = wgpu::ShaderStages::VERTEX;
        let both = wgpu::ShaderStages::VERTEX_FRAGMENT;
        let layout = BindingLayout::render("hw_raster")
            .slot(0, "raster_clusters")
            .visible_in(vertex)
            .slot(1, "raster_counts")
            .visible_in(vertex)
            .slot(2, "instances")
            .visible_in(vertex)
            .slot(3, "meshes")
            .visible_in(vertex)
            .slot(4, "meshlets")
            .visible_in(vertex)
            .slot(5, "payload")
            .visible_in(vertex)
            .slot(6, "visbuffer")
            .visible_in(wgpu::ShaderStages::FRAGMENT)
            .uniform(7)
            .visible_in(vertex)
            .uniform(8)
            .visible_in(both);
        ctx.program(
            "raster",
            ProgramDesc::render(&SHADER, "raster_vs")
                .fragment("raster_fs")
                .target(ColorTarget::masked(TARGET))
                .primitive(Primitive {
                    cull_mode: Some(wgpu::Face::Back),
                    front_face: wgpu::FrontFace::Ccw,
                    ..Primitive::default()
                })
                .layout(layout),
        );
        Ok(())
    }
    fn record(&self, ctx: &mut RecordContext<'_>) -> Result<()> {
        let view = frame_view(ctx, VIEW_INPUT, Some([self.width, self.height]))?;
        let params = GpuParams {
            width: self.width,
            height: self.height,
            nan_bits: NAN_BITS,
            _pad: 0,
        };
        let program = ctx.render("raster")?;
        let bind_group = ctx.bind_group(
            &program,
            0,
            &[
                (7, bytemuck::bytes_of(&view)),
                (8, bytemuck::bytes_of(&params)),
            ],
        )?;
        let (args, _) = ctx.buffer("hw_args")?;
        let mut pass = ctx.render_pass(&[ColorAttachment::new(TARGET)], None)?;
        pass.set_pipeline(&program.pipeline);
        pass.set_bind_group(0, &bind_group, &[]);
        pass.draw_indirect(args, 0);
        Ok(())
    }
}

fn build(params: &Params) -> Result<Box<dyn Pass>> {
    Ok(Box::new(HwRaster::from_params(params)?))
}

/// Registers `hw_raster` (implementation `indirect_draw`) for pipeline files.
pub fn register(registry: &mut Registry) {
    registry.register(STAGE, "indirect_draw", build);
}
