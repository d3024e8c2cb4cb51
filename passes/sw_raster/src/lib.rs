//! Stage `sw_raster`: clusters too small for the hardware rasteriser drawn in a compute
//! shader into the 64-bit visibility buffer. Two implementations share everything but
//! the target: `buffer` (a storage buffer of `u64`, 64-bit buffer atomics: every adapter
//! with `SHADER_INT64_ATOMIC_MIN_MAX`, lavapipe too) and `texture` (an `R64Uint` storage
//! texture, 64-bit texture atomics: `TEXTURE_INT64_ATOMIC`, cleared by a dispatch of
//! stores, since wgpu clears a texture that cannot be a render target by copying from a
//! buffer, which costs several times more).
//! `auto` takes `texture` where the adapter has it. Declare the target as `visibility`
//! in a pipeline file and it takes the form the implementation writes, so the swap is one
//! line and `hw_raster` and `resolve` follow.
//!
//! One workgroup per cluster (linear id `wg.y * sw_args[0] + wg.x`; ids at or past
//! `raster_counts[0]` return). With `accumulate` (the second pass of two-pass occlusion
//! culling) the visibility buffer is not cleared and workgroup `j` draws slot
//! `raster_counts[7] + j`, the first slot `cull_lod`'s second pass gave its software
//! clusters; the slot is the cluster id written, so resolve reads one list. The meshlet's vertices are decoded from the payload,
//! transformed (instance `world_from_local`, then `view_projection`, each product summed
//! column by column as `m[0] * x + m[1] * y + m[2] * z + m[3]`, [`cpu::affine`]) and
//! snapped into workgroup memory; then one thread per triangle culls back faces and covers pixels
//! with fixed-point edge functions, writing `visbuffer64_pack(depth, cluster, triangle)`
//! with a 64-bit atomicMax.
//!
//! # Contract
//!
//! | slot | access | holds | |
//! |------|--------|-------|---|
//! | `raster_clusters` | storage read | Cluster | software clusters in slots `0..raster_counts[0]` (from `raster_counts[7]` with `accumulate`) |
//! | `raster_counts` | storage read | u32 | word 0: software cluster count; with `accumulate`, word 7: their first slot |
//! | `sw_args` | storage read + indirect | DispatchIndirectArgs | `[x, y, 1]` from `remap_dispatch` |
//! | `instances`, `meshes`, `meshlets`, `payload`, `materials`, `textures` | storage read | scene | the GPU scene (materials with `two_sided` or `alpha_mask`, textures with `alpha_mask`) |
//! | `instances_high` | storage read, optional | Instance | the instances past one binding's limit (`meshlight_gpu_scene::instance_table`) |
//! | `visbuffer` | cleared read-write | u64 / r64uint | `width × height`, row-major buffer or texture; cleared (a buffer fill, or a dispatch for the texture) then atomicMax |
//!
//! Frame input `view` (`meshlight_shaders::cpu::layout::View`): its `viewport_size` must
//! equal the params `width` × `height` (a record error names both otherwise).
//! `buffer` needs `SHADER_INT64 | SHADER_INT64_ATOMIC_MIN_MAX`; `texture` needs
//! `SHADER_INT64 | TEXTURE_ATOMIC | TEXTURE_INT64_ATOMIC`. Both give the
//! same values pixel for pixel: only the atomic's target differs.
//!
//! # Definitions the tests pin down
//!
//! - Screen: `((ndc.x * 0.5 + 0.5) * width, (0.5 - ndc.y * 0.5) * height)`, snapped to
//!   8 sub-pixel bits with round-half-even; pixel (x, y) is sampled at its centre.
//! - Clipping, as a hardware rasteriser clips: a triangle with a corner outside the
//!   clip volume — in front of the near plane (reverse Z: `z > w`), or past the guard
//!   band `|x|, |y| <= 63 w` — is clipped in clip space against the near plane, then
//!   the band's left, right, bottom and top sides (Sutherland–Hodgman; an edge's
//!   crossing is always found from its inside corner, so neighbours agree), and its
//!   polygon is covered as a fan of pieces `(0, k + 1, k + 2)` with the triangle's id.
//!   So clusters crossing the near plane, and triangles reaching far off screen, need
//!   no hardware rasteriser. The main dispatch only lists the clusters holding such a
//!   triangle (at most [`CLIP_CLUSTERS`] a frame); a second dispatch clips them, so the
//!   clipping code's registers never slow the main kernel (they did, by 40%, inline). The band keeps every snapped coordinate under 2^20 pixels
//!   for viewports up to 16,384 pixels; below 2^20 the fixed-point coordinates are
//!   under 2^28 and every edge-function product under 2^58, computed in i64: no
//!   overflow. (A corner that still does not snap drops its piece.)
//! - Front faces are the mesh's: counter-clockwise in NDC (y up), which is
//!   counter-clockwise as the screen shows it too. Corners go to the edge functions as
//!   (0, 2, 1), which makes front faces clockwise on the y-down screen (edge area > 0);
//!   others are culled.
//! - Top-left rule (Vulkan/D3D, y down): a pixel centre exactly on an edge is covered
//!   only when the edge is a top edge (horizontal, going right) or a left edge (going up).
//! - Depth: `z0 + e1 * g1 + e2 * g2` in f32, summed left to right, with the gradients
//!   `g1 = (z1 - z0) / area` and `g2 = (z2 - z0) / area` computed once per triangle.
//! - Loop shape: a triangle whose corners lie within fewer than `small_triangle_px`
//!   pixels of each other on both axes (param, default and most [`SMALL_TRIANGLE_PX`];
//!   0: none) loops over its box with 32-bit edge functions stepped by adds, exact
//!   there. Others: if the widest clipped triangle box of the workgroup is at least
//!   `scanline_width` pixels (param, default 16) every thread loops per scanline over
//!   that row's edge span (bounded in f32, one pixel wider than the span), else over
//!   its whole box, with 64-bit edge functions. All cover the same pixels.
//! - Big triangles (param `big_triangle_px`, default [`BIG_TRIANGLE_PX`]; 0: off): a
//!   triangle whose clipped box is at least that many pixels wide or tall is cut into
//!   64 × 64-pixel tiles of its box, listed, and covered by a second dispatch, a
//!   workgroup per tile whose 128 threads stride over its pixels (32 each), instead of
//!   by its one thread. It writes
//!   the pixels and values the thread would have (the same setup, the same edge and
//!   depth arithmetic), so the reference is unchanged; a clipped triangle's pieces are
//!   tiled one by one. This is what lets culling send
//!   large clusters to software on GPUs where few units run graphics. When the list
//!   (a scratch buffer of [`BIG_TILE_CAPACITY`] tiles) is full, the thread covers its
//!   triangle itself. The optional slot `big_triangle_count` (u32 × 2) receives `[0]`
//!   tiles listed and `[1]` tiles asked for.
//! - Materials (params `two_sided` and `alpha_mask`, default false; a renderer sets them
//!   for a scene that has such a material, and without them no material is read): a
//!   double-sided material's back faces are turned to face the eye; a MASK material's
//!   covered pixels whose base colour alpha (`meshlight::surface`: the triangle's
//!   perspective-correct UV at the pixel centre, the resolve's texture filter) is below
//!   its cutoff are not written. A MASK triangle is set up once (`cut_out_setup`: its
//!   corners decoded and transformed, its barycentrics' constants) and each covered
//!   pixel evaluated (`cut_at`), after coverage and depth.
//! - [`cpu::rasterize`] is the reference, equal bit for bit (the GPU test checks every
//!   pixel). Every f32 operation is rounded as IEEE 754 rounds it, on any driver:
//!   Vulkan requires that of adds and multiplies, but lets a compiler fuse a multiply
//!   and an add into one rounding and lets a division be 2.5 ulp off. So products pass
//!   through an xor with a uniform zero before they are added (no fusing), and with
//!   `exact_division` (param, default false) divisions are done on the significands in
//!   integers. Without that an NVIDIA H100 moved hundreds of depths per 96 × 64 frame
//!   by an ulp; lavapipe matches either way. Off by default because it costs: the
//!   H100 figures are in docs/BENCHMARKS.md.

#![warn(missing_docs)]

pub mod cpu;

use meshlight_gpu_scene::gpu::elements;
use meshlight_gpu_scene::instance_table::InstanceTable;
use meshlight_gpu_scene::view::frame_view;
use meshlight_gpu_scene::{SceneBuffer::*, scene_reads};
use meshlight_graph::prelude::*;

/// The stage name pipelines use.
pub const STAGE: &str = "sw_raster";
/// The frame input holding the `View`.
pub const VIEW_INPUT: &str = "view";

/// The stage's WGSL (`raster.wgsl`) with its uniform block, public so the shader tests
/// compose and validate every entry point.
pub const SHADER: PassShader = pass_shader!("sw_raster::raster", "raster.wgsl", params: GpuParams);
/// The `texture` implementation's clear: a dispatch of plain stores.
pub const CLEAR_SHADER: PassShader = pass_shader!("sw_raster::clear", "clear.wgsl");
/// The clear's workgroup edge (16 × 16 pixels).
const CLEAR_TILE: u32 = 16;

/// The slots every implementation of `sw_raster` shares.
pub fn contract() -> StageContract {
    contract_with(None)
}

/// The stage's slots; with a depth-only layer ([`SwRaster::depth_only`]), `visbuffer` is
/// a buffer of `u32` depths instead of a 64-bit visibility target. Layer 0's pass starts
/// the stack (it depends on nothing drawn before it); a later layer's keeps what the
/// passes before it drew, so the layers are drawn in order.
fn contract_with(depth_layer: Option<u32>) -> StageContract {
    let target = if let Some(layer) = depth_layer {
        Slot::buffer(
            "visbuffer",
            if layer == 0 {
                Access::ClearedReadWrite
            } else {
                Access::StorageReadWrite
            },
            meshlight_graph::Element::U32,
            "layers of width × height reverse-Z depth bits; layer `layer` cleared, then atomicMax",
        )
    } else {
        Slot::visibility64(
            "visbuffer",
            Access::ClearedReadWrite,
            "width × height visibility values (u64 buffer or r64uint texture); cleared, then atomicMax",
        )
    };
    StageContract {
        stage: STAGE,
        slots: [
            vec![
                Slot::read(
                    "raster_clusters",
                    elements::CLUSTER,
                    "software clusters first",
                ),
                Slot::read(
                    "raster_counts",
                    meshlight_graph::Element::U32,
                    "word 0: software cluster count",
                ),
                Slot::read(
                    "sw_args",
                    meshlight_graph::Element::DISPATCH_ARGS,
                    "[x, y, 1] over the software clusters",
                )
                .also(Access::Indirect),
            ],
            scene_reads(&[Instances, Meshes, Meshlets, Payload, Materials, Textures]),
            vec![
                target,
                Slot::buffer(
                    BIG_COUNT_SLOT,
                    Access::ClearedReadWrite,
                    meshlight_graph::Element::U32,
                    "[0] big-triangle tiles listed, [1] asked for (a scratch buffer when unbound)",
                )
                .optional(),
            ],
        ]
        .concat(),
    }
}

/// The optional slot of the big-triangle counters.
pub const BIG_COUNT_SLOT: &str = "big_triangle_count";
/// Scratch: the big triangles' tiles, two words each.
const BIG_TILES: &str = "big_triangle_tiles";
/// Boxes this many pixels wide or tall are tiled by default: the best of 8 to 64 px on
/// an H200 (the default scene at 3840×2160: sw_raster 0.72 ms at 24 px, 0.74 at 32,
/// 0.81 at 48, 1.57 at 8, 2.11 untiled; docs/BENCHMARKS.md).
pub const BIG_TRIANGLE_PX: u32 = 24;
/// Triangles whose corners lie within fewer than this many pixels of each other are
/// covered with 32-bit edge functions by default, which is also the most allowed: 2^14
/// fixed-point units, under which every edge function of a pixel of the triangle's box
/// stays under 2^30 (raster.wgsl's `cover_small`).
pub const SMALL_TRIANGLE_PX: u32 = 64;
/// Tiles the list holds: a 3840 × 2160 triangle is 2,040 of them.
pub const BIG_TILE_CAPACITY: u32 = 1 << 18;
/// Workgroups of the big-triangle dispatch, striding over the tiles listed.
const BIG_GROUPS: u32 = 2048;
/// Scratch: the clusters with a triangle to clip, then the big pieces of clipped
/// triangles (raster.wgsl's `clip_list`, sized by the same constants).
const CLIP_LIST: &str = "clip_list";
/// Scratch: `[0]` clusters listed, `[1]` asked for, `[2]` pieces stored, `[3]` asked for.
const CLIP_COUNT: &str = "clip_count";
/// Clusters with a triangle crossing the near plane or the guard band one frame can
/// clip; the clipped triangles of clusters past it are not drawn. Such clusters lie
/// along the near plane's slice of the scene: thousands at most.
pub const CLIP_CLUSTERS: u32 = 16_384;
/// Big pieces of clipped triangles stored for tiling; past it their thread covers them.
const CLIP_PIECES: u32 = 16_384;
const PIECE_WORDS: u32 = 10;
/// Workgroups of the clipping dispatch, striding over the clusters listed.
const CLIP_GROUPS: u32 = 256;

/// The implementations and the visibility target each writes, best first (the order
/// `auto` tries them in).
pub const IMPLEMENTATIONS: [(&str, Visibility64); 2] = [
    ("texture", Visibility64::Texture),
    ("buffer", Visibility64::Buffer),
];

/// The `buffer` and `texture` implementations ([`SwRaster::target`] tells them apart).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SwRaster {
    /// The visibility buffer's width in pixels, which the view's viewport must equal.
    pub width: u32,
    /// The visibility buffer's height in pixels.
    pub height: u32,
    /// What the visibility buffer is: `Buffer` (implementation `buffer`) or `Texture`
    /// (`texture`).
    pub target: Visibility64,
    /// Workgroups whose widest triangle box reaches this many pixels loop per scanline.
    pub scanline_width: u32,
    /// Divide in integers, rounded as IEEE 754 divides, so every driver matches the
    /// reference bit for bit; off, the driver's division (within 2.5 ulp on some).
    pub exact_division: bool,
    /// Draw on top of what the visibility buffer holds instead of clearing it, taking
    /// the clusters from slot `raster_counts[7]` on: the second pass of two-pass
    /// occlusion culling, whose software clusters `cull_lod` (mode `second`) puts after
    /// the first pass's and whose first slot it writes into word 7. Off: cleared, slots
    /// from 0.
    pub accumulate: bool,
    /// Triangles whose box is this many pixels wide or tall are tiled and covered by a
    /// workgroup per tile; 0: every triangle by its thread.
    pub big_triangle_px: u32,
    /// Triangles whose corners lie within fewer than this many pixels of each other on
    /// both axes are covered with 32-bit edge functions stepped by adds, the others with
    /// 64-bit products per pixel; the same pixels and depths either way. At most
    /// [`SMALL_TRIANGLE_PX`], the bound under which the 32-bit functions cannot
    /// overflow; 0: every triangle takes the 64-bit path.
    pub small_triangle_px: u32,
    /// Draw the back faces of clusters whose material is double-sided (turned to face
    /// the eye). Off, every back face is culled and the kernel reads no material: the
    /// lookup and the turn cost about 2% of the pass on an H200, so a renderer turns it
    /// on only for a scene that has such a material.
    pub two_sided: bool,
    /// Leave undrawn the pixels of clusters whose material is MASK where the base
    /// colour's alpha is below its cutoff (`meshlight::surface`'s `cut_at`, the alpha
    /// the resolve would read). Off, no material is read for it: a renderer turns it on
    /// only for a scene that has such a material.
    pub alpha_mask: bool,
    /// Write only the depth: `visbuffer` is a buffer of `u32`, the reverse-Z depth's
    /// bits (the visibility value's high word), in layers of `width × height`; the pass
    /// clears and draws layer [`Self::layer`] only. A shadow map: no cluster id is
    /// needed, and half the bytes are cleared and written. Both implementations write
    /// it alike, with 32-bit buffer atomics.
    pub depth_only: bool,
    /// With [`Self::depth_only`], the layer drawn (`layer = "{view}"` in a view set).
    pub layer: u32,
}

shader_defs! {
    /// The variant of raster.wgsl a pass runs.
    #[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
    pub struct RasterDefs {
        /// See [`SwRaster::exact_division`].
        pub exact_division: bool => "EXACT_DIVISION",
        /// The visibility buffer is an R64Uint storage texture.
        pub texture: bool => "VIS_TEXTURE",
        /// Clusters start at slot `raster_counts[7]` ([`SwRaster::accumulate`]).
        pub slot_base: bool => "SLOT_BASE",
        /// [`SwRaster::big_triangle_px`] is not 0.
        pub big_triangles: bool => "BIG_TRIANGLES",
        /// See [`SwRaster::two_sided`].
        pub two_sided: bool => "TWO_SIDED",
        /// See [`SwRaster::alpha_mask`].
        pub alpha_mask: bool => "ALPHA_MASK",
        /// See [`SwRaster::depth_only`].
        pub depth_only: bool => "DEPTH_ONLY",
    }
}

/// What the `texture` implementation asks of the adapter besides 64-bit integers.
pub const TEXTURE_FEATURES: wgpu::Features =
    wgpu::Features::TEXTURE_ATOMIC.union(wgpu::Features::TEXTURE_INT64_ATOMIC);

uniform_block! {
    /// The uniform of raster.wgsl, which imports the struct from this declaration.
    struct GpuParams as "Params" in "sw_raster::params" {
        /// Visibility buffer size in pixels.
        width: u32,
        height: u32,
        /// Workgroups whose widest triangle box reaches this many pixels loop per scanline.
        scanline_width: u32,
        /// Always 0 (see `unfused`): the kernel xors products with it so that no compiler
        /// fuses them into an fma the reference does not do.
        zero: u32,
        /// BIG_TRIANGLES: boxes this wide or tall are tiled for `raster_big`.
        big_triangle_px: u32,
        /// Entries `big_triangle_tiles` may hold (clamped to its length too).
        big_capacity: u32,
        /// DEPTH_ONLY: the layer of `visbuffer` drawn.
        layer: u32,
        /// Triangles whose corners lie within this many fixed-point units (256 a
        /// pixel) of each other on both axes take `cover_small`: at most 2^14.
        small_extent: u32,
    }
}

const PARAM_KEYS: [&str; 11] = [
    "depth_only",
    "layer",
    "big_triangle_px",
    "small_triangle_px",
    "width",
    "height",
    "scanline_width",
    "exact_division",
    "accumulate",
    "two_sided",
    "alpha_mask",
];

impl SwRaster {
    /// Reads `width`, `height` (required, > 0), `scanline_width` (default 16),
    /// `big_triangle_px` (default [`BIG_TRIANGLE_PX`]), `small_triangle_px` (default and
    /// most [`SMALL_TRIANGLE_PX`]) and `exact_division`,
    /// `accumulate`, `two_sided`, `alpha_mask` and `depth_only` (default false), and
    /// `layer` (default 0, only with `depth_only`); `target` picks the implementation.
    pub fn from_params(params: &Params, target: Visibility64) -> Result<Self> {
        params.only(&PARAM_KEYS)?;
        let [width, height] = params.size("the visibility buffer")?;
        let depth_only = params.bool("depth_only", false)?;
        let layer = params.u32("layer", 0)?;
        if layer > 0 && !depth_only {
            return Err(GraphError::parameter(format!(
                "`layer = {layer}` draws one layer of a stack of depth maps, which only `depth_only = true` writes; set it, or drop `layer`"
            )));
        }
        let layer_bytes = u64::from(width) * u64::from(height) * 4;
        if depth_only && !layer_bytes.is_multiple_of(256) {
            return Err(GraphError::parameter(format!(
                "a depth-only layer of {width} × {height} is {layer_bytes} bytes, not a multiple of 256, so it cannot be cleared alone; give sizes whose product is a multiple of 64 (sides that are multiples of 8)"
            )));
        }
        let small_triangle_px = params.u32("small_triangle_px", SMALL_TRIANGLE_PX)?;
        if small_triangle_px > SMALL_TRIANGLE_PX {
            return Err(GraphError::parameter(format!(
                "`small_triangle_px = {small_triangle_px}` is past {SMALL_TRIANGLE_PX}, above which the 32-bit edge functions of the small-triangle path can overflow; give {SMALL_TRIANGLE_PX} or less (0 turns the path off)"
            )));
        }
        let accumulate = params.bool("accumulate", false)?;
        if depth_only && accumulate {
            return Err(GraphError::parameter(
                "`depth_only` and `accumulate` together are not supported: a depth-only layer is drawn by one pass; drop `accumulate`".to_string(),
            ));
        }
        Ok(Self {
            width,
            height,
            target,
            scanline_width: params.u32("scanline_width", 16)?,
            exact_division: params.bool("exact_division", false)?,
            accumulate,
            big_triangle_px: params.u32("big_triangle_px", BIG_TRIANGLE_PX)?,
            small_triangle_px,
            two_sided: params.bool("two_sided", false)?,
            alpha_mask: params.bool("alpha_mask", false)?,
            depth_only,
            layer,
        })
    }
}

impl Pass for SwRaster {
    fn implementation(&self) -> Implementation {
        Implementation::new(
            match self.target {
                Visibility64::Buffer => "buffer",
                Visibility64::Texture => "texture",
            },
            contract_with(self.depth_only.then_some(self.layer)),
        )
    }
    fn visibility64(&self) -> Option<Visibility64> {
        (!self.depth_only).then_some(self.target)
    }
    fn setup(&self, ctx: &mut SetupContext) -> Result<()> {
        let texture = self.target == Visibility64::Texture && !self.depth_only;
        if self.depth_only {
            // 64-bit integers for the edge functions; the depth atomics are 32-bit.
            ctx.require_features(wgpu::Features::SHADER_INT64);
            let layer_bytes = self.layer_bytes();
            ctx.min_bytes("visbuffer", layer_bytes * (u64::from(self.layer) + 1));
        } else {
            ctx.require_features(self.target.atomic_max_features());
            ctx.min_bytes("visbuffer", self.width as u64 * self.height as u64 * 8);
        }
        // With a slot base the first slot is word 7.
        ctx.min_bytes("raster_counts", if self.accumulate { 32 } else { 4 });
        ctx.min_bytes("sw_args", 12);
        ctx.frame_input(VIEW_INPUT);
        if texture {
            // The texture is cleared by the `clear` dispatch below (or, accumulating,
            // not at all), never by a clear command: the pass stays in its batch.
            ctx.clears_itself("visbuffer");
        }
        let big = self.big_triangle_px > 0;
        let table = InstanceTable::of(ctx);
        ctx.shader_defs(&table);
        // Bindings from the shader; the big-triangle count is a slot when bound, else a
        // scratch buffer of the same name.
        let layout = BindingLayout::from_shader("sw_raster");
        if big {
            ctx.scratch_buffer(
                BIG_TILES,
                meshlight_graph::BufferDesc::array(
                    meshlight_graph::Element::U64,
                    BIG_TILE_CAPACITY as u64,
                ),
                &[Access::StorageReadWrite],
            );
            if ctx.is_bound(BIG_COUNT_SLOT) {
                ctx.min_bytes(BIG_COUNT_SLOT, 8);
            } else {
                ctx.scratch_buffer(
                    BIG_COUNT_SLOT,
                    meshlight_graph::BufferDesc::array(meshlight_graph::Element::U32, 2),
                    &[Access::ClearedReadWrite],
                );
            }
        }
        ctx.scratch_buffer(
            CLIP_LIST,
            meshlight_graph::BufferDesc::array(
                meshlight_graph::Element::U32,
                u64::from(CLIP_CLUSTERS + CLIP_PIECES * PIECE_WORDS),
            ),
            &[Access::StorageReadWrite],
        );
        ctx.scratch_buffer(
            CLIP_COUNT,
            meshlight_graph::BufferDesc::array(meshlight_graph::Element::U32, 4),
            &[Access::ClearedReadWrite],
        );
        let defs = RasterDefs {
            exact_division: self.exact_division,
            texture,
            slot_base: self.accumulate,
            big_triangles: big,
            two_sided: self.two_sided,
            alpha_mask: self.alpha_mask,
            depth_only: self.depth_only,
        };
        ctx.shader_defs(&defs);
        for kernel in kernels(big) {
            ctx.program(
                kernel.entry,
                ProgramDesc::compute(&SHADER, kernel.entry)
                    .defs(&defs)
                    .defs(&table)
                    .layout(layout.clone()),
            );
        }
        if texture && !self.accumulate {
            let clear = BindingLayout::from_shader("sw_raster::clear");
            ctx.program(
                "clear",
                ProgramDesc::compute(&CLEAR_SHADER, "clear").layout(clear),
            );
        }
        Ok(())
    }
    fn record(&self, ctx: &mut RecordContext<'_>) -> Result<()> {
        let view = frame_view(ctx, VIEW_INPUT, Some([self.width, self.height]))?;
        let params = GpuParams {
            width: self.width,
            height: self.height,
            scanline_width: self.scanline_width,
            zero: 0,
            big_triangle_px: self.big_triangle_px,
            big_capacity: BIG_TILE_CAPACITY,
            layer: self.layer,
            small_extent: self.small_triangle_px * 256,
        };
        let big = self.big_triangle_px > 0;
        ctx.clear_scratch(CLIP_COUNT)?;
        if big {
            if ctx.is_bound(BIG_COUNT_SLOT) {
                ctx.clear(BIG_COUNT_SLOT)?;
            } else {
                ctx.clear_scratch(BIG_COUNT_SLOT)?;
            }
        }
        let clear = match self.target {
            _ if self.accumulate => None,
            _ if self.depth_only => {
                let bytes = self.layer_bytes();
                ctx.clear_part("visbuffer", bytes * u64::from(self.layer), bytes)?;
                None
            }
            Visibility64::Buffer => {
                ctx.clear("visbuffer")?;
                None
            }
            Visibility64::Texture => {
                let program = ctx.compute("clear")?;
                let group = ctx.bind_group(&program, 0, &[])?;
                Some((program, group))
            }
        };
        let uniforms: [(&str, &[u8]); 2] = [
            ("view", bytemuck::bytes_of(&view)),
            ("params", bytemuck::bytes_of(&params)),
        ];
        // `buffer` gives the buffer and its size; the arguments start at its beginning.
        let (args, _) = ctx.buffer("sw_args")?;
        if let Some((clear, group)) = clear {
            let mut pass = ctx.compute_pass();
            pass.set_pipeline(&clear.pipeline);
            pass.set_bind_group(0, &group, &[]);
            pass.dispatch_workgroups(
                self.width.div_ceil(CLEAR_TILE),
                self.height.div_ceil(CLEAR_TILE),
                1,
            );
        }
        // Each program binds what its entry point uses: a bind group each.
        let mut programs = Vec::new();
        for kernel in kernels(big) {
            let program = ctx.compute(kernel.entry)?;
            let group = ctx.bind_group(&program, 0, &uniforms)?;
            programs.push((kernel.groups, program, group));
        }
        // After the clear: wgpu's barrier before each dependent dispatch (in the batch's
        // pass or in a pass of its own) makes it visible before any cluster writes.
        let mut pass = ctx.compute_pass();
        for (groups, program, group) in &programs {
            pass.set_pipeline(&program.pipeline);
            pass.set_bind_group(0, group, &[]);
            match groups {
                KernelGroups::FromArgs => pass.dispatch_workgroups_indirect(args, 0),
                KernelGroups::Fixed(n) => pass.dispatch_workgroups(*n, 1, 1),
            }
        }
        Ok(())
    }
}

impl SwRaster {
    /// Bytes of one depth-only layer.
    fn layer_bytes(&self) -> u64 {
        u64::from(self.width) * u64::from(self.height) * 4
    }
}

/// One entry point of the kernel and how many workgroups run it.
struct Kernel {
    entry: &'static str,
    groups: KernelGroups,
}

#[derive(Clone, Copy)]
enum KernelGroups {
    /// The 2-D grid `remap_dispatch` wrote into `sw_args`: one per cluster.
    FromArgs,
    /// A fixed grid that strides over a list the first entry point filled.
    Fixed(u32),
}

/// The kernel's entry points a pass runs, in dispatch order: every cluster, then the
/// clusters with triangles to clip, then, with big triangles, the tiles both listed.
fn kernels(big: bool) -> &'static [Kernel] {
    const ALL: [Kernel; 3] = [
        Kernel {
            entry: "raster",
            groups: KernelGroups::FromArgs,
        },
        Kernel {
            entry: "raster_clipped",
            groups: KernelGroups::Fixed(CLIP_GROUPS),
        },
        Kernel {
            entry: "raster_big",
            groups: KernelGroups::Fixed(BIG_GROUPS),
        },
    ];
    if big { &ALL } else { &ALL[..2] }
}

/// Registers `sw_raster` (implementations `buffer`, `texture` and `auto`) for pipeline
/// files.
pub fn register(registry: &mut Registry) {
    registry.register_best_first(STAGE, &IMPLEMENTATIONS, SwRaster::from_params);
}

#[cfg(test)]
mod tests {
    use super::cpu::{cover_triangle, edge};

    #[test]
    fn the_kernel_sizes_its_clip_list_as_the_pass_allocates_it() {
        let source = include_str!("raster.wgsl");
        for (name, value) in [
            ("CLIP_CLUSTERS", super::CLIP_CLUSTERS),
            ("CLIP_PIECES", super::CLIP_PIECES),
            ("PIECE_WORDS", super::PIECE_WORDS),
        ] {
            let line = format!("const {name}: u32 = {value}u;");
            assert!(source.contains(&line), "raster.wgsl lacks `{line}`");
        }
    }
    use meshlight_shaders::Capabilities;
    use meshlight_testing::shader_variants::compose_and_validate;

    #[test]
    fn the_kernel_composes_and_validates_with_int64_atomics() {
        let caps = Capabilities::SHADER_INT64 | Capabilities::SHADER_INT64_ATOMIC_MIN_MAX;
        compose_and_validate(&super::SHADER, &[], caps).unwrap_or_else(|e| panic!("{e}"));
    }

    #[test]
    fn the_texture_variant_composes_and_validates_with_texture_atomics() {
        use meshlight_shaders::ShaderDefs;
        let caps = Capabilities::SHADER_INT64
            | Capabilities::TEXTURE_ATOMIC
            | Capabilities::TEXTURE_INT64_ATOMIC;
        let defs = super::RasterDefs {
            exact_division: false,
            texture: true,
            slot_base: true,
            big_triangles: true,
            two_sided: true,
            alpha_mask: true,
            depth_only: false,
        };
        compose_and_validate(&super::SHADER, &defs.shader_defs(), caps)
            .unwrap_or_else(|e| panic!("{e}"));
        // Without texture atomics the variant is refused.
        let plain = Capabilities::SHADER_INT64 | Capabilities::SHADER_INT64_ATOMIC_MIN_MAX;
        assert!(compose_and_validate(&super::SHADER, &defs.shader_defs(), plain).is_err());
    }

    fn px(x: i32, y: i32) -> [i32; 2] {
        [x * 256 + 128, y * 256 + 128]
    }

    fn covered(v: [[i32; 2]; 3], w: u32, h: u32) -> Vec<u32> {
        let mut out = vec![0; (w * h) as usize];
        cover_triangle(v.map(|p| (p, 0.5)), w, h, |x, y, _| {
            out[(y * w + x) as usize] += 1
        });
        out
    }

    #[test]
    fn top_left_rule_on_edges_through_pixel_centres() {
        // Clockwise on the y-down screen: (0,0) → (4,0) → (0,4), corners at pixel centres.
        let tri = [px(0, 0), px(4, 0), px(0, 4)];
        assert!(edge(tri[0], tri[1], tri[2]) > 0);
        let c = covered(tri, 8, 8);
        let at = |x: usize, y: usize| c[y * 8 + x];
        // Top edge (y = 0, going right) and left edge (x = 0, going up) are included.
        assert_eq!(at(1, 0), 1);
        assert_eq!(at(0, 2), 1);
        assert_eq!(at(0, 0), 1);
        // The hypotenuse x + y = 4 goes down-left: a right edge, excluded.
        assert_eq!(at(2, 2), 0);
        assert_eq!(at(4, 0), 0);
        assert_eq!(at(1, 2), 1);
        // The other half of the square, (4,0) → (4,4) → (0,4): its right edge x = 4
        // (going down) and bottom edge y = 4 (going left) are excluded.
        let other = covered([px(4, 0), px(4, 4), px(0, 4)], 8, 8);
        assert_eq!(other[2 * 8 + 4], 0, "right edge");
        assert_eq!(other[4 * 8 + 2], 0, "bottom edge");
        assert_eq!(other[2 * 8 + 2], 1, "shared hypotenuse belongs to this one");
        assert_eq!(other[3 * 8 + 3], 1);
    }

    #[test]
    fn back_faces_cover_nothing() {
        let c = covered([px(0, 0), px(0, 4), px(4, 0)], 8, 8);
        assert!(c.iter().all(|&n| n == 0));
    }

    #[test]
    fn shared_edges_and_fans_cover_every_pixel_once() {
        let (w, h) = (16u32, 16u32);
        // A quad split along a diagonal, then a fan of 8 triangles around a vertex on a
        // pixel centre; corners on and off pixel centres, sub-pixel positions.
        let quads = [
            vec![
                [[3, 5], [1000, 300], [200, 2000]],
                [[1000, 300], [1200, 2100], [200, 2000]],
            ],
            vec![
                [[px(1, 1)[0], px(1, 1)[1]], px(12, 1), px(12, 12)],
                [px(1, 1), px(12, 12), px(1, 12)],
            ],
        ];
        for tris in quads {
            let mut total = vec![0u32; (w * h) as usize];
            for t in &tris {
                for (i, n) in covered(*t, w, h).into_iter().enumerate() {
                    total[i] += n;
                }
            }
            assert!(total.iter().all(|&n| n <= 1), "a pixel covered twice");
            assert!(total.contains(&1));
        }
        // Fan around (8, 8) through 8 rim points: together they cover the octagon.
        let c = px(8, 8);
        let rim = [
            [128 + 256 * 8, 0],
            [3900, 200],
            [4000, 2048 + 128],
            [3900, 3900],
            [128 + 256 * 8, 4000],
            [300, 3900],
            [100, 2048 + 128],
            [200, 300],
        ];
        let mut total = vec![0u32; (w * h) as usize];
        for k in 0..rim.len() {
            let t = [c, rim[k], rim[(k + 1) % rim.len()]];
            for (i, n) in covered(t, w, h).into_iter().enumerate() {
                total[i] += n;
            }
        }
        assert!(total.iter().all(|&n| n <= 1), "a pixel covered twice");
        // Pixels well inside the octagon are all covered.
        for y in 4..12 {
            for x in 4..12 {
                assert_eq!(total[(y * w + x) as usize], 1, "pixel ({x}, {y}) skipped");
            }
        }
    }
}
