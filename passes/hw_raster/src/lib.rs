//! Stage `hw_raster`: the clusters culling sent to the hardware rasteriser (large on
//! screen, or crossing the near plane) drawn into the same 64-bit visibility buffer the
//! software rasteriser fills, with no count read back to the CPU. Two implementations:
//!
//! - `indirect_draw`: culling appends hardware clusters from the right end of the shared
//!   slot buffer and counts them in `hw_args[1]`, so `draw_indirect` of
//!   `[384, count, 0, 0]` draws one instance of 128 × 3 vertices per cluster. Instance
//!   `j` draws slot `C - 1 - j` (`C = raster_counts[3]`); the vertex shader pulls its
//!   corner from the compressed payload, and corners of triangles past the meshlet's
//!   triangle count become NaN, which the rasteriser drops. Every vertex is transformed
//!   once per triangle using it.
//! - `mesh_shader` (`EXPERIMENTAL_MESH_SHADER`): one mesh workgroup (a warp of 32
//!   threads) per hardware cluster decodes and transforms each of the meshlet's vertices
//!   once and
//!   emits its triangles, with the slot and triangle as per-primitive values. A
//!   one-thread dispatch first turns `raster_counts[1]` into a mesh dispatch
//!   `[row, rows, 1]` under the adapter's mesh-dispatch limits (a scratch buffer), so
//!   cluster `j` is workgroup `wg.y * row + wg.x`. No task stage: culling already chose
//!   the clusters.
//!
//! The fragment shader of both does the software rasteriser's
//! `atomicMax(depth << 32 | slot << 7 | triangle)`, into a `u64` buffer or, where the
//! target is an `R64Uint` texture (bound by a `texture` software rasteriser), with a
//! 64-bit texture atomic. The colour target exists only because a render pipeline needs
//! one and is never written. `auto` takes `mesh_shader` where the adapter has it.
//!
//! # Contract
//!
//! | slot | access | holds | |
//! |------|--------|-------|---|
//! | `raster_clusters` | storage read | Cluster | hardware clusters in slots `C - hw_count .. C` |
//! | `raster_counts` | storage read | u32 | word 1: hardware clusters, word 3: `C`, the slot capacity |
//! | `hw_args` | indirect | DrawIndirectArgs | `[384, hw_count, 0, 0]` from `cull_lod` |
//! | `instances`, `meshes`, `meshlets`, `payload`, `materials`, `textures` | storage read | scene | the GPU scene (materials with `two_sided` or `alpha_mask`, textures with `alpha_mask`) |
//! | `instances_high` | storage read, optional | Instance | the instances past one binding's limit (`meshlight_gpu_scene::instance_table`) |
//! | `visbuffer` | storage read-write | u64 / r64uint | `width × height`, row-major buffer or texture; atomicMax onto what `sw_raster` left |
//!
//! | param    | default    | |
//! |----------|------------|---|
//! | `width`, `height` | required | the visibility buffer's size |
//! | `run`    | `"always"` | `"auto"`: skipped (kept in the plan, recording nothing) where the adapter class rasterises nothing in hardware (`AdapterClass::hardware_raster`), the rule `cull_lod`'s `hardware = "auto"` follows, so culling then sends it nothing |
//! | `two_sided`, `alpha_mask` | false | act on double-sided and MASK materials (below); off, no material is read |
//!
//! Frame input `view` (`meshlight_shaders::cpu::layout::View`): its `viewport_size` must
//! equal the params `width` × `height` (a record error names both otherwise).
//! Scratch: `target`, an `R8Unorm` colour target of the viewport size, masked, cleared
//! and discarded; `mesh_shader` also `mesh_args`. Needs `SHADER_INT64` and
//! `SHADER_INT64_ATOMIC_MIN_MAX` (buffer target) or `TEXTURE_ATOMIC |
//! TEXTURE_INT64_ATOMIC` (texture target).
//!
//! # Definitions the tests pin down
//!
//! - The visibility id of a hardware cluster is its slot, `C - 1 - j` for cluster `j`.
//! - Clip position: `view_projection * (world_from_local * position).xyz1`, the software
//!   rasteriser's operations, so both rasterisers start from the same bits.
//! - Front faces are counter-clockwise in NDC (clockwise on the y-down screen); back
//!   faces are culled. No depth attachment: the visibility buffer's atomicMax is the
//!   depth test. Depth is the fragment's `position.z` (NDC z, interpolated by the
//!   hardware linearly in screen space).
//! - Coverage is the hardware's: pixel centres, top-left rule, its sub-pixel precision
//!   (8 bits on lavapipe, like the software rasteriser's fixed point). The two differ on
//!   pixels whose centre lies within rounding of an edge and in the last bits of depth;
//!   the GPU test states the tolerance. Both clip triangles at the near plane: the
//!   hardware in fixed function, the software rasteriser in clip space.
//! - Materials (params `two_sided`, `alpha_mask`; `sw_raster`'s, set alike): a
//!   double-sided material's back faces are turned to face the eye; a MASK material's
//!   fragments whose base colour alpha at the pixel centre is below the cutoff
//!   (`meshlight::surface`'s `cut_out`, the software rasteriser's test) write nothing.
//!   `mesh_shader` refuses `alpha_mask` (naga_oil 0.23 cannot compose its mesh entry
//!   point with the sampler); a renderer draws such scenes with `indirect_draw`.
//! - The two implementations feed the rasteriser the same triangles in the same
//!   positions; they may differ only where the hardware orders equal-depth writes.
//! - [`cpu::rasterize`] is the reference (float edge functions at pixel centres).

#![warn(missing_docs)]

pub mod cpu;

use meshlight_gpu_scene::gpu::elements;
use meshlight_gpu_scene::instance_table::InstanceTable;
use meshlight_gpu_scene::view::frame_view;
use meshlight_gpu_scene::{SceneBuffer::*, scene_reads};
use meshlight_graph::AdapterClass;
use meshlight_graph::prelude::*;

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

/// The stage's WGSL (`raster.wgsl`) with its uniform block, public so the shader tests
/// compose and validate every entry point.
pub const SHADER: PassShader = pass_shader!("hw_raster::raster", "raster.wgsl", params: GpuParams);

/// raster.wgsl with the mesh-shader extension enabled (compose it with `MESH_SHADER`):
/// an `enable` directive must be the first line and cannot depend on a def.
pub const MESH_SHADER_SOURCE: PassShader = PassShader {
    name: "hw_raster::raster_mesh",
    source: concat!("enable wgpu_mesh_shader;\n", include_str!("raster.wgsl")),
    file_path: concat!(env!("CARGO_PKG_NAME"), "/raster.wgsl (mesh variant)"),
    modules: &[GpuParams::MODULE],
};

/// The slots every implementation of `hw_raster` shares.
pub fn contract() -> StageContract {
    contract_with(false)
}

/// The stage's slots; with `depth_only` ([`HwRaster::depth_only`]), `visbuffer` is a
/// buffer of `u32` depths, drawn onto what the software rasteriser's layer holds.
fn contract_with(depth_only: bool) -> StageContract {
    let target = if depth_only {
        Slot::buffer(
            "visbuffer",
            Access::StorageReadWrite,
            Element::U32,
            "layers of width × height reverse-Z depth bits; atomicMax onto layer `layer`",
        )
    } else {
        Slot::visibility64(
            "visbuffer",
            Access::StorageReadWrite,
            "width × height visibility values (u64 buffer or r64uint texture); atomicMax onto the software raster's",
        )
    };
    StageContract {
        stage: STAGE,
        slots: [
            vec![
                Slot::read(
                    "raster_clusters",
                    elements::CLUSTER,
                    "hardware clusters from the right end",
                ),
                Slot::read(
                    "raster_counts",
                    Element::U32,
                    "word 1: hardware clusters, word 3: the slot capacity C",
                ),
                Slot::buffer(
                    "hw_args",
                    Access::Indirect,
                    Element::DRAW_ARGS,
                    "[384, hardware cluster count, 0, 0]",
                ),
            ],
            scene_reads(&[Instances, Meshes, Meshlets, Payload, Materials, Textures]),
            vec![target],
        ]
        .concat(),
    }
}

/// The implementations and how each feeds clusters, best first (the order `auto` tries
/// them in).
pub const IMPLEMENTATIONS: [(&str, Feed); 2] = [
    ("mesh_shader", Feed::MeshShader),
    ("indirect_draw", Feed::IndirectDraw),
];

/// How clusters reach the rasteriser.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Feed {
    /// `indirect_draw`: 384 vertices per cluster instance.
    IndirectDraw,
    /// `mesh_shader`: one mesh workgroup per cluster.
    MeshShader,
}

impl Feed {
    /// The implementation name pipelines use for this feed.
    pub const fn implementation(self) -> &'static str {
        match self {
            Feed::IndirectDraw => "indirect_draw",
            Feed::MeshShader => "mesh_shader",
        }
    }
}

/// The `indirect_draw` and `mesh_shader` implementations ([`HwRaster::feed`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct HwRaster {
    /// The visibility buffer's width in pixels, which the view's viewport must equal.
    pub width: u32,
    /// The visibility buffer's height in pixels.
    pub height: u32,
    /// How clusters reach the rasteriser: the implementation.
    pub feed: Feed,
    /// `run = "auto"`: skipped where the adapter class rasterises nothing in hardware.
    pub auto_skip: bool,
    /// Draw the back faces of clusters whose material is double-sided (turned to face
    /// the eye); off, the shaders read no material and every back face is culled
    /// (`sw_raster`'s parameter of the same name, which a renderer sets alike).
    pub two_sided: bool,
    /// Leave undrawn the fragments of MASK materials whose base colour alpha is below
    /// the cutoff (`sw_raster`'s parameter of the same name, the same test); off, no
    /// material is read for it.
    pub alpha_mask: bool,
    /// Write only the depth into layer [`Self::layer`] of a buffer of `u32` layers, as
    /// `sw_raster`'s `depth_only` does (a shadow map; that pass clears the layer).
    pub depth_only: bool,
    /// With [`Self::depth_only`], the layer drawn.
    pub layer: u32,
}

impl HwRaster {
    /// The `indirect_draw` implementation.
    pub fn indirect(width: u32, height: u32) -> Self {
        Self {
            width,
            height,
            feed: Feed::IndirectDraw,
            auto_skip: false,
            two_sided: false,
            alpha_mask: false,
            depth_only: false,
            layer: 0,
        }
    }
}

shader_defs! {
    /// The variant of raster.wgsl a pass runs.
    #[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
    pub struct RasterDefs {
        /// The mesh-stage entry points exist (they need the extension).
        pub mesh_shader: bool => "MESH_SHADER",
        /// The visibility buffer is an R64Uint storage texture.
        pub texture: bool => "VIS_TEXTURE",
        /// See [`HwRaster::two_sided`].
        pub two_sided: bool => "TWO_SIDED",
        /// See [`HwRaster::alpha_mask`].
        pub alpha_mask: bool => "ALPHA_MASK",
        /// See [`HwRaster::depth_only`].
        pub depth_only: bool => "DEPTH_ONLY",
    }
}

uniform_block! {
    /// The uniform of raster.wgsl (both variants), which imports the struct from this
    /// declaration. Importing a module of types adds no globals, so the mesh variant's
    /// `mesh_out` keeps its place for naga_oil.
    struct GpuParams as "Params" in "hw_raster::params" {
        /// Visibility buffer size in pixels (the viewport's).
        width: u32,
        height: u32,
        /// 0x7fc00000, a quiet NaN: discarded vertices take it as every coordinate. It
        /// comes from the uniform because shader validation refuses a NaN constant.
        nan_bits: u32,
        /// Mesh workgroups per row of the mesh dispatch, and at most in all (the
        /// adapter's mesh-dispatch limits).
        row: u32,
        total: u32,
        /// DEPTH_ONLY: the layer of `visbuffer` drawn.
        layer: u32,
        pad_b: u32,
        pad_c: u32,
    }
}

const PARAM_KEYS: [&str; 7] = [
    "width",
    "height",
    "run",
    "two_sided",
    "alpha_mask",
    "depth_only",
    "layer",
];

impl HwRaster {
    /// Reads `width` and `height` (required, > 0: the visibility buffer's size), `run`,
    /// `two_sided`, `alpha_mask` and `depth_only` (default false), and `layer` (default
    /// 0, only with `depth_only`).
    pub fn from_params(params: &Params, feed: Feed) -> Result<Self> {
        params.only(&PARAM_KEYS)?;
        let [width, height] = params.size("the visibility buffer")?;
        let auto_skip = match params.string("run", "always")?.as_str() {
            "always" => false,
            "auto" => true,
            other => {
                return Err(GraphError::parameter(format!(
                    "`run` = \"{other}\": use \"always\", or \"auto\" to skip the pass where the adapter class rasterises nothing in hardware"
                )));
            }
        };
        let depth_only = params.bool("depth_only", false)?;
        let layer = params.u32("layer", 0)?;
        if layer > 0 && !depth_only {
            return Err(GraphError::parameter(format!(
                "`layer = {layer}` draws one layer of a stack of depth maps, which only `depth_only = true` writes; set it, or drop `layer`"
            )));
        }
        Ok(Self {
            width,
            height,
            feed,
            auto_skip,
            two_sided: params.bool("two_sided", false)?,
            alpha_mask: params.bool("alpha_mask", false)?,
            depth_only,
            layer,
        })
    }
}

impl Pass for HwRaster {
    fn implementation(&self) -> Implementation {
        Implementation::new(self.feed.implementation(), contract_with(self.depth_only))
    }
    fn setup(&self, ctx: &mut SetupContext) -> Result<()> {
        if self.auto_skip {
            let (runs, why) = ctx.adapter_class().hardware_raster();
            if !runs {
                ctx.skip(why);
                return Ok(());
            }
        }
        let texture = ctx.is_texture("visbuffer") && !self.depth_only;
        let pixels = self.width as u64 * self.height as u64;
        if self.depth_only {
            // 32-bit atomics onto the layer; 64-bit integers for the shared code.
            ctx.require_features(wgpu::Features::SHADER_INT64);
            ctx.min_bytes("visbuffer", pixels * 4 * (u64::from(self.layer) + 1));
        } else {
            // atomicMax onto the 64-bit target, as sw_raster draws onto it.
            let target = if texture {
                Visibility64::Texture
            } else {
                Visibility64::Buffer
            };
            ctx.require_features(target.atomic_max_features());
            ctx.min_bytes("visbuffer", pixels * 8);
        }
        ctx.min_bytes("raster_counts", 16);
        ctx.min_bytes("hw_args", 16);
        ctx.frame_input(VIEW_INPUT);
        ctx.scratch_texture(
            TARGET,
            TextureDesc::d2(wgpu::TextureFormat::R8Unorm, self.width, self.height),
            &[Access::RenderTarget],
        );
        let mesh = self.feed == Feed::MeshShader;
        if mesh && self.alpha_mask {
            return Err(GraphError::parameter(
                "`alpha_mask` is not available with the `mesh_shader` implementation yet: \
                 naga_oil 0.23 cannot compose a mesh entry point with the texture sampling \
                 the cut-out needs; use implementation = \"indirect_draw\" for scenes with \
                 MASK materials"
                    .to_string(),
            ));
        }
        let defs = RasterDefs {
            mesh_shader: mesh,
            texture,
            two_sided: self.two_sided,
            alpha_mask: self.alpha_mask,
            depth_only: self.depth_only,
        };
        ctx.shader_defs(&defs);
        let table = InstanceTable::of(ctx);
        ctx.shader_defs(&table);
        // Bindings from the shader, each visible in the stages that use it.
        let layout = BindingLayout::from_shader_render("hw_raster");
        let primitive = Primitive {
            cull_mode: Some(wgpu::Face::Back),
            front_face: wgpu::FrontFace::Ccw,
            ..Primitive::default()
        };
        let program = if mesh {
            ProgramDesc::mesh(&MESH_SHADER_SOURCE, None, "raster_ms").fragment("raster_mesh_fs")
        } else {
            ProgramDesc::render(&SHADER, "raster_vs").fragment("raster_fs")
        };
        ctx.program(
            "raster",
            program
                .defs(&defs)
                .defs(&table)
                .target(ColorTarget::masked(TARGET))
                .primitive(primitive)
                .layout(layout),
        );
        if mesh {
            ctx.scratch_buffer(
                MESH_ARGS,
                BufferDesc::array(Element::DISPATCH_ARGS, 1),
                &[Access::StorageWrite, Access::Indirect],
            );
            let args = BindingLayout::from_shader("hw_raster::mesh_dispatch");
            ctx.program(
                "mesh_dispatch",
                ProgramDesc::compute(&MESH_SHADER_SOURCE, "mesh_dispatch")
                    .defs(&defs)
                    .layout(args),
            );
        }
        Ok(())
    }
    fn record(&self, ctx: &mut RecordContext<'_>) -> Result<()> {
        let view = frame_view(ctx, VIEW_INPUT, Some([self.width, self.height]))?;
        let limits = ctx.device().limits();
        let params = GpuParams {
            width: self.width,
            height: self.height,
            nan_bits: NAN_BITS,
            row: limits.max_mesh_workgroups_per_dimension.max(1),
            total: limits.max_mesh_workgroup_total_count,
            layer: self.layer,
            ..GpuParams::default()
        };
        let params = bytemuck::bytes_of(&params);
        let program = ctx.render("raster")?;
        let bind_group = ctx.bind_group(
            &program,
            0,
            &[("view", bytemuck::bytes_of(&view)), ("params", params)],
        )?;
        if self.feed == Feed::MeshShader {
            ctx.dispatch_compute(
                "mesh_dispatch",
                &[("params", params)],
                Workgroups::Direct([1, 1, 1]),
            )?;
            let (args, _) = ctx.scratch(MESH_ARGS)?;
            let mut pass = ctx.render_pass(&[ColorAttachment::new(TARGET)], None)?;
            pass.set_pipeline(&program.pipeline);
            pass.set_bind_group(0, &bind_group, &[]);
            pass.draw_mesh_tasks_indirect(args, 0);
            return Ok(());
        }
        let (args, _) = ctx.buffer("hw_args")?;
        let mut pass = ctx.render_pass(&[ColorAttachment::new(TARGET)], None)?;
        pass.set_pipeline(&program.pipeline);
        pass.set_bind_group(0, &bind_group, &[]);
        pass.draw_indirect(args, 0);
        Ok(())
    }
}

/// The mesh dispatch's arguments (`mesh_shader` only).
const MESH_ARGS: &str = "mesh_args";

/// Registers `hw_raster` (implementations `indirect_draw`, `mesh_shader` and `auto`) for
/// pipeline files.
pub fn register(registry: &mut Registry) {
    registry.register_best_first(STAGE, &IMPLEMENTATIONS, HwRaster::from_params);
    // Measured on an H100 (docs/BENCHMARKS.md, rasterisers): the indirect draw ran the
    // same clusters 1.19× faster than mesh shaders on the 2 TPCs that run graphics there.
    registry.prefer_on(
        STAGE,
        AdapterClass::FewGraphicsUnits,
        &[Feed::IndirectDraw.implementation()],
        "measured on an H100: the indirect draw ran the same clusters 1.19x faster than mesh shaders on the 2 TPCs that run graphics",
    );
}

#[cfg(test)]
mod tests {
    use super::RasterDefs;
    use meshlight_shaders::{Capabilities, ShaderDefs, ShaderError};
    use meshlight_testing::shader_variants::compose_and_validate;

    /// The variant `defs` picks, from the source with the mesh-shader extension when it
    /// has the mesh-stage entry points.
    fn compose(defs: RasterDefs, caps: Capabilities) -> Result<(), ShaderError> {
        let shader = if defs.mesh_shader {
            &super::MESH_SHADER_SOURCE
        } else {
            &super::SHADER
        };
        compose_and_validate(shader, &defs.shader_defs(), caps)
    }

    #[test]
    fn every_variant_composes_and_validates_with_its_capabilities() {
        let int64 = Capabilities::SHADER_INT64 | Capabilities::SHADER_INT64_ATOMIC_MIN_MAX;
        let texture = Capabilities::SHADER_INT64
            | Capabilities::TEXTURE_ATOMIC
            | Capabilities::TEXTURE_INT64_ATOMIC;
        for mesh_shader in [false, true] {
            for (on_texture, two_sided, alpha_mask, depth_only) in [
                (false, false, false, false),
                (false, true, true, false),
                (true, false, true, false),
                (true, true, false, false),
                (false, true, true, true),
            ] {
                // `setup` refuses the mesh variant with `alpha_mask` (see there).
                let alpha_mask = alpha_mask && !mesh_shader;
                let defs = RasterDefs {
                    mesh_shader,
                    texture: on_texture,
                    two_sided,
                    alpha_mask,
                    depth_only,
                };
                let mut caps = if on_texture { texture } else { int64 };
                if mesh_shader {
                    caps |= Capabilities::MESH_SHADER;
                }
                compose(defs, caps).unwrap_or_else(|e| panic!("{defs:?}: {e}"));
            }
        }
        // The mesh variant needs the mesh-shader capability.
        let defs = RasterDefs {
            mesh_shader: true,
            texture: false,
            two_sided: false,
            alpha_mask: false,
            depth_only: false,
        };
        assert!(compose(defs, int64).is_err());
    }
}
