//! Stage `resolve`, implementation `compute`: the visibility buffer turned into what
//! the screen and later passes use: a shaded colour image (or a debug view of the ids),
//! and, only where a pipeline asks for them, a depth buffer and a material-depth buffer.
//!
//! The rasterisers store only `depth | cluster | triangle` per pixel; everything else is
//! recomputed here once per pixel instead of once per overdrawn fragment. Shading is a
//! compute dispatch that fetches the pixel's triangle from the payload again, transforms
//! its three corners again, and reconstructs perspective-correct barycentrics and their
//! screen-space derivatives at the pixel centre analytically from the clip-space corners
//! (no quad neighbours exist in a compute shader). The derivatives choose each
//! texture's mip level and box-filter the generated scenes' UV checkerboard.
//!
//! # Depth targets: off unless a pipeline composites with raster geometry
//!
//! `depth` and `material_depth` are optional slots. Depth formats cannot be storage
//! textures, so each is written by a fullscreen render pass with `frag_depth`; on GPUs
//! where few units run fragment work (an H100 or H200: two TPCs) the two cost ~6× the
//! shading itself (docs/BENCHMARKS.md). The frame needs neither: the depth pyramid is
//! built in compute from the visibility buffer. Left unbound, the pass declares no
//! render program and records no render pass: the frame's resolve is one compute
//! dispatch. A pipeline that draws raster geometry over the image (depth-tested
//! overlays, transparent passes, material passes with `CompareFunction::Equal`) turns
//! them on by declaring a resource of the slot's name, which binds it; in a pipeline
//! file:
//!
//! ```toml
//! [[resource]]
//! name = "depth"            # and/or "material_depth"
//! kind = "exported"
//! texture = { format = "depth32float", width_param = "width", height_param = "height" }
//! ```
//!
//! and in code `g.create_texture("depth", TextureDesc::d2(DEPTH_FORMAT, w, h))` (exported,
//! or read by a later pass) before `add_pass`, or `.bind("depth", handle)` in the
//! pass's bindings. Each bound target adds one fullscreen pass and nothing else changes:
//! the colour is the same either way (tested).
//!
//! # Contract
//!
//! | slot | access | holds | |
//! |------|--------|-------|---|
//! | `visbuffer` | storage read | u64 | `width × height` visibility values, row-major |
//! | `raster_clusters` | storage read | Cluster | the slots the visibility ids index |
//! | `raster_counts` | storage read | u32 | word 0: software clusters (ids below it) |
//! | `instances`, `meshes`, `meshlets`, `payload`, `materials` | storage read | scene | the GPU scene |
//! | `textures` | storage read | u32 | every texture's mip chain, one RGBA8 texel a word (`layout::TextureRef`) |
//! | `instances_high` | storage read, optional | Instance | the instances past one binding's limit (`meshlight_gpu_scene::instance_table`) |
//! | `depth` | depth target (optional) | Depth32Float | reverse-Z NDC depth; 0 where empty |
//! | `material_depth` | depth target (optional) | Depth32Float | [`material_depth`] of the instance's material; 0 where empty |
//! | `color` | storage write | Rgba8Unorm | the [`DebugView`] chosen; alpha 1 |
//! | `objects` | storage read (optional) | ClusterableObject | light clustering's objects |
//! | `cluster_grid` | storage read (optional) | ClusterGrid | the froxel grid |
//! | `cluster_offsets`, `cluster_counts` | storage read (optional) | u32 | per froxel and kind: list start and length |
//! | `cluster_objects` | storage read (optional) | u32 | the lists: indices into `objects` |
//! | `pyramid` | sampled (optional) | R32Float, mip chain | a depth pyramid, for the `pyramid` view |
//! | `second_counts` | storage read (optional) | u32 × 8 or 12 | the second `cull_lod` pass's `raster_counts`, for the `occlusion` view |
//! | `occluded_per_instance` | storage read (optional) | u32 × 2 per instance | `[2i]` clusters of instance `i` in the first pass's LOD cut, `[2i + 1]` of those left hidden after both passes |
//!
//! With light clustering's five outputs bound (all or none), the shaded view adds the point
//! and spot lights of each pixel's froxel, and the `light-count` view can show them.
//!
//! Frame input `view` (`meshlight_shaders::cpu::layout::View`), whose `viewport_size`
//! must equal the params `width` × `height`. The three targets are `width` × `height`.
//!
//! The `pyramid` view reads the depth pyramid's convention: reverse-Z minimum depth; mip
//! `L` is `⌈width / 2^(L+1)⌉ × ⌈height / 2^(L+1)⌉` and its texel `(x, y)` covers pixels
//! `[x·2^(L+1), (x+1)·2^(L+1))` on each axis, so pixel `p` shows texel `p >> (L+1)` of
//! mip `pyramid_mip` (clamped to the mip's size), as `depth^(1/4)` grey like the
//! `depth` view. A `pyramid_mip` past the bound chain is a record error naming its
//! length; the view without a `pyramid` bound is a setup error.
//!
//! # The `occlusion` view
//!
//! Each covered pixel is coloured by the culling pass that drew its cluster, tinted by
//! how much of its instance occlusion culled, and scaled by the shaded image's
//! brightness (`0.45 + 0.55 · min(luma(shaded), 1)`) so shapes stay readable:
//!
//! | colour | meaning |
//! |--------|---------|
//! | green `(0.35, 0.85, 0.4)` | drawn by the first pass (visible in last frame's pyramid, or not testable) |
//! | blue `(0.3, 0.55, 1.0)` | drawn by the second pass: hidden last frame, visible in this frame's pyramid |
//! | towards red `(1.0, 0.2, 0.15)` | `mix(pass colour, red, 0.7 · culled / cut)`: the share of the instance's LOD cut left hidden after both passes |
//! | black | empty |
//!
//! The pass is read from the pixel's slot: the second pass writes the free slots
//! between the first pass's software clusters (`[0, sw1)`) and hardware clusters
//! (`[C − hw1, C)`), and its counts hold both ends (`[7]` = `sw1`, `[3]` = `C − hw1`),
//! so slot `id` is the second pass's iff `[7] ≤ id < [3]`. Without `second_counts`
//! bound (a one-pass frame) every pixel is first-pass green; without
//! `occluded_per_instance` nothing is tinted (an instance with a zero cut neither).
//! Both slots are optional and cost one binding each; a frame binds them only for this
//! view.
//!
//! # Definitions the tests pin down
//!
//! - Material depth: material `m` ↦ `(min(m, 2^24 - 2) + 1) · 2^-24`, exact in f32, never
//!   0; a material pass draws at that depth with `CompareFunction::Equal` to touch only
//!   its pixels.
//! - Barycentrics (`meshlight::surface`, which the rasterisers share for MASK
//!   materials): with `ndc_i = clip_i.xy / clip_i.w` and the pixel centre `p` in NDC,
//!   screen-linear `λ` of `p` in the NDC triangle, then `b_i = λ_i / w_i / Σ λ_j / w_j`;
//!   `∂b/∂x`, `∂b/∂y` per pixel by the quotient rule from `∂λ/∂ndc` and the NDC size of
//!   a pixel (`2 / width`, `-2 / height`).
//! - Shading: normal `Σ b_i n_i` to world space with the inverse transpose, UV `Σ b_i
//!   uv_i` (0 without UVs) and its derivatives `Σ ∂b_i/∂x uv_i`, `Σ ∂b_i/∂y uv_i`; each of
//!   the material's maps sampled there (`meshlight::texture`): base colour `factor · texel`
//!   (times the interpolated vertex colour `Σ b_i c_i` with the param `vertex_colors`,
//!   which the renderer sets for a scene with a coloured mesh; off, the shader holds no
//!   code for them),
//!   checkered where the material asks (`· mix(0.55, 1, filtered_checker(uv · scale,
//!   ∂uv · scale))`, a box filter of the square wave over the pixel's footprint);
//!   metalness and roughness times the texel's B and G; the normal map's `(2·texel − 1)
//!   · (scale, scale, 1)` in the triangle's tangent frame (tangent `t` from its world and
//!   UV edges, bitangent `n × t`, negated where the UVs are mirrored); the ambient times
//!   `1 + strength · (occlusion − 1)`; emission times the emissive texel. Then GGX and
//!   Lambert ([`brdf`]) for the sun, the ambient and the clustered lights, plus emission,
//!   clamped, stored linear. `lights` (with clustering
//!   bound): over the point and spot lists of the froxel `cluster_of_pixel(pixel,
//!   view_z)`, `colour · intensity · window² / d² · max(n̂ · l, 0)` with `window =
//!   saturate(1 − (d² / range²)²)`, spots also times `smoothstep(cos_outer, mix(cos_outer,
//!   1, 0.2), −l · axis)`. Empty pixels: a vertical sky
//!   gradient from the horizon colour at the bottom to the zenith colour at the top.
//! - Debug views: `clusters` = colour of the scene cluster, `cluster_key` =
//!   `hash(instance) ^ meshlet` of the slot the id names (raster slots come from atomics
//!   and change from frame to frame; the scene cluster does not), `triangles` = of
//!   `cluster_key · 131 + triangle`, `lod` = of the meshlet's LOD level, `raster` = two fixed
//!   colours (software: id < `raster_counts[0]`), `depth` = `depth^(1/4)` grey; id
//!   colours are [`cpu::id_color`], empty pixels black; `pyramid` as above; `uv` =
//!   `(fract(u), fract(v), 0)`; `normal` = the shading normal `· 0.5 + 0.5`; `mip` = the
//!   id colour of `floor(level)` of the base colour texture (black without one);
//!   `base-color` = the base colour before lighting.
//! - Texture sampling (`meshlight::texture`, [`meshlight_gpu_scene::texture`] on the
//!   CPU): level `λ = clamp(log2(max(|∂uv/∂x|, |∂uv/∂y|) ·
//!   S), 0, log2 S)` for a texture of side `S`; bilinear in levels `⌊λ⌋` and `⌊λ⌋ + 1`
//!   mixed by `fract(λ)`; texel centres at `(i + 0.5) / s`; sRGB texels decoded to linear
//!   light before they are weighed; U and V wrap (repeat, clamp, mirror) on their own.
//! - [`cpu`] is the reference: depth, material depth and debug views exact (the depth
//!   and pyramid views within 1/255), shading within 2/255 per channel on ≥ 99% of
//!   pixels.

#![warn(missing_docs)]

pub mod brdf;
pub mod cpu;
pub mod settings;
pub mod shadows;

pub use settings::{DebugView, Resolve};

use meshlight_gpu_scene::gpu::elements;
use meshlight_gpu_scene::instance_table::InstanceTable;
use meshlight_gpu_scene::view::frame_view;
use meshlight_gpu_scene::{SceneBuffer::*, scene_reads};
use meshlight_graph::prelude::*;
use meshlight_shaders::cpu::layout::{ClusterGrid, ClusterableObject};

/// `meshlight::light::ClusterableObject`, as light clustering's stages declare it.
const CLUSTERABLE_OBJECT: Element =
    Element::named("ClusterableObject", size_of::<ClusterableObject>() as u32);
/// `meshlight::light::ClusterGrid`.
const CLUSTER_GRID: Element = Element::named("ClusterGrid", size_of::<ClusterGrid>() as u32);

/// The stage name pipelines use.
pub const STAGE: &str = "resolve";
/// The frame input holding the `View`.
pub const VIEW_INPUT: &str = "view";
/// The format of `color`.
pub const COLOR_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8Unorm;
/// The format of `depth` and `material_depth`.
pub const DEPTH_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;
/// The format of the `pyramid` the `pyramid` view reads.
pub const PYRAMID_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::R32Float;

/// A WGSL module beside this file, named for its import path.
macro_rules! local_module {
    ($name:literal, $file:literal) => {
        meshlight_shaders::LocalModule {
            name: $name,
            source: include_str!($file),
            file_path: concat!(env!("CARGO_PKG_NAME"), "/", $file),
        }
    };
}

/// The depth resolves' WGSL (`depth.wgsl`), public so the shader tests compose and
/// validate every entry point.
pub const DEPTH_SHADER: PassShader = pass_shader!(
    "resolve::depth",
    "depth.wgsl",
    params: DepthParams,
    modules: [("resolve::visibility", "visibility.wgsl")]
);
/// The shading program's WGSL (`shade.wgsl`), public so the shader tests compose and
/// validate every entry point.
pub const SHADE_SHADER: PassShader = PassShader {
    name: "resolve::shade",
    source: include_str!("shade.wgsl"),
    file_path: concat!(env!("CARGO_PKG_NAME"), "/shade.wgsl"),
    // What `pass_shader!` writes, by hand: the shader has two uniform blocks, which the
    // macro does not take.
    modules: &[
        ShadeParams::MODULE,
        shadows::ShadowParams::MODULE,
        local_module!("resolve::visibility", "visibility.wgsl"),
        local_module!("resolve::brdf", "brdf.wgsl"),
        local_module!("resolve::shadows", "shadows.wgsl"),
    ],
};

/// The fullscreen passes that write the depth targets: (program, fragment entry, slot).
/// Each is declared and recorded only when its slot is bound (see the crate docs).
const DEPTH_RESOLVES: [(&str, &str, &str); 2] = [
    ("depth", "depth_fs", "depth"),
    ("material_depth", "material_depth_fs", "material_depth"),
];

/// Pixels a shading workgroup covers across and down (shade.wgsl's `@workgroup_size`).
/// 16 × 8 (a warp of 32 on two rows) beat 8 × 8, 32 × 4, 64 × 2 and 16 × 16 on an
/// H200: the colour target's stores cost half as much on wide rows, while taller tiles
/// keep more of a triangle's pixels in one warp (docs/BENCHMARKS.md).
const TILE: [u32; 2] = [16, 8];

/// The depth a material pass tests with `Equal` for material `m`: `(m + 1) · 2^-24`
/// (ids past `2^24 - 2` share the last value); 0 is left for empty pixels.
pub fn material_depth(material: u32) -> f32 {
    (material.min(0xff_fffe) + 1) as f32 * (1.0 / 16_777_216.0)
}

/// The slots every implementation of `resolve` shares.
pub fn contract() -> StageContract {
    StageContract {
        stage: STAGE,
        slots: [
            vec![
                Slot::visibility64(
                    "visbuffer",
                    Access::StorageRead,
                    "width × height visibility values from the rasterisers (u64 buffer or r64uint texture)",
                ),
                Slot::read(
                    "raster_clusters",
                    elements::CLUSTER,
                    "the slots visibility ids index",
                ),
                Slot::read(
                    "raster_counts",
                    Element::U32,
                    "word 0: software clusters (ids below it)",
                ),
            ],
            scene_reads(&[Instances, Meshes, Meshlets, Payload, Materials, Textures]),
            vec![
                Slot::texture(
                    "depth",
                    Access::DepthTarget,
                    Some(DEPTH_FORMAT),
                    "reverse-Z depth; 0 where empty",
                )
                .optional(),
                Slot::texture(
                    "material_depth",
                    Access::DepthTarget,
                    Some(DEPTH_FORMAT),
                    "(material + 1) · 2^-24; 0 where empty",
                )
                .optional(),
                Slot::texture(
                    "color",
                    Access::StorageWrite,
                    Some(COLOR_FORMAT),
                    "shaded colour or a debug view",
                ),
                Slot::read("objects", CLUSTERABLE_OBJECT, "light clustering's objects").optional(),
                Slot::read("cluster_grid", CLUSTER_GRID, "the froxel grid").optional(),
                Slot::read(
                    "cluster_offsets",
                    Element::U32,
                    "per froxel and kind: list start",
                )
                .optional(),
                Slot::read(
                    "cluster_counts",
                    Element::U32,
                    "per froxel and kind: list length",
                )
                .optional(),
                Slot::read("cluster_objects", Element::U32, "the lists: object indices").optional(),
                Slot::texture(
                    "pyramid",
                    Access::Sampled,
                    Some(PYRAMID_FORMAT),
                    "a reverse-Z min-depth pyramid (mip L: ⌈size / 2^(L+1)⌉), for the `pyramid` view",
                )
                .optional(),
                Slot::read(
                    SECOND_COUNTS,
                    Element::U32,
                    "the second culling pass's raster_counts ([3], [7]), for the `occlusion` view",
                )
                .optional(),
                Slot::read(
                    OCCLUDED_PER_INSTANCE,
                    Element::U32,
                    "per instance: [2i] clusters in the LOD cut, [2i+1] left hidden, for the `occlusion` view",
                )
                .optional(),
                Slot::read(
                    shadows::SHADOW_MAPS,
                    Element::U32,
                    "the sun's cascades: resolution² reverse-Z depth bits each, with the frame input `shadows`",
                )
                .optional(),
                Slot::read(
                    STREAM_ERRORS,
                    Element::F32,
                    "per group: its error while its page is not in the streaming pool, else 0 (the scene's `stream_errors`), for the `residency` view",
                )
                .optional(),
            ],
        ]
        .concat(),
    }
}

uniform_block! {
    /// The uniform of the depth resolves (`Params` in depth.wgsl), which import the struct
    /// from this declaration.
    struct DepthParams as "Params" in "resolve::depth_params" {
        /// Visibility buffer size in pixels.
        width: u32,
        height: u32,
        pad_a: u32,
        pad_b: u32,
    }
}

uniform_block! {
    /// The uniform of the shading program (`Params` in shade.wgsl), which imports the
    /// struct from this declaration.
    struct ShadeParams as "Params" in "resolve::shade_params" {
        /// Unit vector towards the light, world space.
        light_direction: [f32; 4],
        /// Linear RGB radiance of the light and of the ambient term.
        light_color: [f32; 4],
        ambient_color: [f32; 4],
        width: u32,
        height: u32,
        view_mode: u32,
        /// Checker squares per UV unit.
        checker_scale: f32,
        /// The mip the pyramid view shows.
        pyramid_mip: u32,
        /// The LOD threshold the residency view measures missing detail against.
        lod_threshold_px: f32,
        /// Scalars, not a vec2 (whose alignment would grow the struct).
        pad_b: u32,
        pad_c: u32,
    }
}

impl Pass for Resolve {
    fn implementation(&self) -> Implementation {
        Implementation::new("compute", contract())
    }
    fn setup(&self, ctx: &mut SetupContext) -> Result<()> {
        ctx.min_bytes("visbuffer", self.width as u64 * self.height as u64 * 8);
        ctx.min_bytes("raster_counts", 4);
        ctx.frame_input(VIEW_INPUT);
        // A `texture` software rasteriser's target: read as an R64Uint storage texture.
        let texture = ctx.is_texture("visbuffer");
        if texture {
            ctx.require_features(
                wgpu::Features::SHADER_INT64 | wgpu::Features::TEXTURE_INT64_ATOMIC,
            );
        }
        let table = InstanceTable::of(ctx);
        ctx.shader_defs(&table);
        let depth_layout = BindingLayout::from_shader_render("resolve_depth");
        for (program, entry, target) in DEPTH_RESOLVES {
            if !ctx.is_bound(target) {
                continue;
            }
            ctx.program(
                program,
                ProgramDesc::render(&DEPTH_SHADER, "fullscreen_vs")
                    .defs(&DepthDefs { texture })
                    .defs(&table)
                    .fragment(entry)
                    .depth(DepthTarget {
                        target,
                        compare: wgpu::CompareFunction::Always,
                        write: true,
                    })
                    .layout(depth_layout.clone()),
            );
        }
        let lit = self.clustered_lights(ctx)?;
        let pyramid = ctx.is_bound("pyramid");
        if self.settings.view.needs_pyramid() && !pyramid {
            return Err(GraphError::parameter(
                "the `pyramid` view shows a depth pyramid, and none is bound; bind an R32Float mip chain (the depth_pyramid stage's output) to the `pyramid` slot or pick another view",
            ));
        }
        let second_counts = ctx.is_bound(SECOND_COUNTS);
        if second_counts {
            ctx.min_bytes(SECOND_COUNTS, 32);
        }
        let occluded_per_instance = ctx.is_bound(OCCLUDED_PER_INSTANCE);
        let residency = ctx.is_bound(STREAM_ERRORS);
        let shadowed = ctx.is_bound(shadows::SHADOW_MAPS);
        if shadowed {
            ctx.frame_input(shadows::SHADOWS_INPUT);
        } else if self.settings.view.needs_shadows() {
            return Err(GraphError::parameter(
                "the `shadow` view shows the sun's shadow cascades, and none are bound; bind the cascades' depth maps to the `shadow_maps` slot (the shipped frame does, with shadows on) or pick another view",
            ));
        }
        let defs = ShadeDefs {
            residency,
            vertex_colors: self.vertex_colors,
            clustered_lights: lit,
            texture,
            pyramid,
            second_counts,
            occluded_per_instance,
            shadows: shadowed,
        };
        ctx.shader_defs(&defs);
        // Bindings from the shader: the defs above decide which of the optional slots
        // (lights, pyramid, occlusion records) it declares.
        let shade_layout = BindingLayout::from_shader("resolve_shade");
        ctx.program(
            "shade",
            ProgramDesc::compute(&SHADE_SHADER, "shade_pixels")
                .defs(&defs)
                .defs(&table)
                .layout(shade_layout),
        );
        ctx.dispatch(
            "shade",
            [
                self.width.div_ceil(TILE[0]),
                self.height.div_ceil(TILE[1]),
                1,
            ],
        );
        Ok(())
    }
    fn record(&self, ctx: &mut RecordContext<'_>) -> Result<()> {
        let view = frame_view(ctx, VIEW_INPUT, Some([self.width, self.height]))?;
        let depth_params = DepthParams {
            width: self.width,
            height: self.height,
            ..DepthParams::default()
        };
        for (program, _, target) in DEPTH_RESOLVES {
            if !ctx.is_bound(target) {
                continue;
            }
            let program = ctx.render(program)?;
            let bind_group = ctx.bind_group(
                &program,
                0,
                &[("params", bytemuck::bytes_of(&depth_params))],
            )?;
            let mut pass = ctx.render_pass(&[], Some(DepthAttachment { target, clear: 0.0 }))?;
            pass.set_pipeline(&program.pipeline);
            pass.set_bind_group(0, &bind_group, &[]);
            pass.draw(0..3, 0..1);
        }
        let s = &self.settings;
        let shade_params = ShadeParams {
            light_direction: s.light_direction.normalize_or_zero().extend(0.0).to_array(),
            light_color: s.light_color.extend(0.0).to_array(),
            ambient_color: s.ambient_color.extend(0.0).to_array(),
            width: self.width,
            height: self.height,
            view_mode: s.view as u32,
            checker_scale: s.checker_scale,
            pyramid_mip: s.pyramid_mip,
            lod_threshold_px: s.lod_threshold_px,
            ..ShadeParams::default()
        };
        if s.view.needs_pyramid()
            && let ResourceDesc::Texture(t) = ctx.desc("pyramid")?
            && s.pyramid_mip >= t.mip_levels
        {
            return Err(GraphError::parameter(format!(
                "`pyramid_mip` = {} is past the bound pyramid, which has {} mips (0 to {}); pick one of those",
                s.pyramid_mip,
                t.mip_levels,
                t.mip_levels - 1
            )));
        }
        let shadow_params = if ctx.is_bound(shadows::SHADOW_MAPS) {
            Some(self.shadow_params(ctx)?)
        } else {
            None
        };
        let mut uniforms = vec![
            ("view", bytemuck::bytes_of(&view)),
            ("params", bytemuck::bytes_of(&shade_params)),
        ];
        if let Some(p) = &shadow_params {
            uniforms.push(("shadows", bytemuck::bytes_of(p)));
        }
        ctx.dispatch_compute(
            "shade",
            &uniforms,
            Workgroups::Direct([
                self.width.div_ceil(TILE[0]),
                self.height.div_ceil(TILE[1]),
                1,
            ]),
        )
    }
}

impl Resolve {
    /// The frame input `shadows`, checked against the bound maps: at most four
    /// cascades, and maps that hold them all.
    fn shadow_params(&self, ctx: &RecordContext<'_>) -> Result<shadows::ShadowParams> {
        let bytes = ctx.frame_bytes(shadows::SHADOWS_INPUT)?;
        let size = size_of::<shadows::ShadowParams>();
        let p: shadows::ShadowParams = bytes
            .get(..size)
            .map(bytemuck::pod_read_unaligned)
            .ok_or_else(|| {
                GraphError::parameter(format!(
                    "frame input `{}` must hold a ShadowParams ({size} bytes), got {}",
                    shadows::SHADOWS_INPUT,
                    bytes.len()
                ))
            })?;
        let (_, bound) = ctx.buffer(shadows::SHADOW_MAPS)?;
        if p.count > meshlight_gpu_scene::cascades::MAX_CASCADES || p.map_words() * 4 > bound {
            return Err(GraphError::parameter(format!(
                "the frame's shadows ask for {} cascades of {}² texels ({} bytes), but `{}` holds {bound} bytes and at most {} cascades are read; size the maps for the cascades",
                p.count,
                p.resolution,
                p.map_words() * 4,
                shadows::SHADOW_MAPS,
                meshlight_gpu_scene::cascades::MAX_CASCADES
            )));
        }
        Ok(p)
    }
}

/// The slot of the second culling pass's `raster_counts`, read by the `occlusion` view.
pub const SECOND_COUNTS: &str = "second_counts";
/// The slot of the per-instance occlusion counters, read by the `occlusion` view.
pub const OCCLUDED_PER_INSTANCE: &str = "occluded_per_instance";
/// The slot of the streamed groups' missing errors, read by the `residency` view.
pub const STREAM_ERRORS: &str = "stream_errors";

/// Light clustering's outputs the shading reads, at bindings 11 to 15.
const LIGHT_SLOTS: [&str; 5] = [
    "objects",
    "cluster_grid",
    "cluster_offsets",
    "cluster_counts",
    "cluster_objects",
];

shader_defs! {
    /// The variant of shade.wgsl a pass runs.
    #[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
    struct ShadeDefs {
        /// The base colour is multiplied by vertex colours (`Resolve::vertex_colors`).
        vertex_colors: bool => "VERTEX_COLORS",
        /// The froxel lists are bound.
        clustered_lights: bool => "CLUSTERED_LIGHTS",
        /// The visibility buffer is an R64Uint texture (depth.wgsl too).
        texture: bool => "VIS_TEXTURE",
        /// A depth pyramid is bound, for the `pyramid` view.
        pyramid: bool => "PYRAMID",
        /// The second culling pass's counts are bound.
        second_counts: bool => "SECOND_COUNTS",
        /// The streamed groups' missing errors are bound, for the `residency` view.
        residency: bool => "RESIDENCY",
        /// The per-instance occlusion counters are bound.
        occluded_per_instance: bool => "OCCLUDED_PER_INSTANCE",
        /// The sun's shadow cascades are bound.
        shadows: bool => "SHADOWS",
    }
}

shader_defs! {
    /// The variant of depth.wgsl a pass runs.
    #[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
    struct DepthDefs {
        texture: bool => "VIS_TEXTURE",
    }
}

impl Resolve {
    /// Whether light clustering's outputs are bound: all five or none, and the
    /// `light-count` view only with them.
    fn clustered_lights(&self, ctx: &SetupContext) -> Result<bool> {
        let bound: Vec<&str> = LIGHT_SLOTS
            .into_iter()
            .filter(|s| ctx.is_bound(s))
            .collect();
        let lit = bound.len() == LIGHT_SLOTS.len();
        if !bound.is_empty() && !lit {
            let missing: Vec<&str> = LIGHT_SLOTS
                .into_iter()
                .filter(|s| !bound.contains(s))
                .collect();
            return Err(GraphError::parameter(format!(
                "light clustering's outputs are bound only in part: {} bound, {} missing; bind all five (or none)",
                bound.join(", "),
                missing.join(", ")
            )));
        }
        if self.settings.view.needs_lights() && !lit {
            return Err(GraphError::parameter(format!(
                "the `{}` view shows light clustering's lists, and this frame has none; add the clustering stages (pipelines/light_clustering.toml) or pick another view",
                self.settings.view
            )));
        }
        Ok(lit)
    }
}

/// Registers `resolve` (implementation `compute`) for pipeline files.
pub fn register(registry: &mut Registry) {
    registry.register(STAGE, "compute", Resolve::from_params);
}

#[cfg(test)]
mod tests {
    use super::*;
    use meshlight_shaders::{Capabilities, ShaderDefs, ShaderLibrary};
    use meshlight_testing::shader_variants::compose_and_validate;

    #[test]
    fn the_shaders_compose_and_validate_without_64_bit_integers() {
        let mut library = ShaderLibrary::new(Capabilities::empty()).unwrap();
        for (shader, want) in [
            (
                &DEPTH_SHADER,
                &["fullscreen_vs", "depth_fs", "material_depth_fs"][..],
            ),
            (&SHADE_SHADER, &["shade_pixels"][..]),
        ] {
            let entries = library
                .entry_point_names(shader, &[])
                .unwrap_or_else(|e| panic!("{e}"));
            assert_eq!(entries, want);
        }
    }

    #[test]
    fn the_texture_variants_compose_and_validate_with_64_bit_texture_reads() {
        let caps = Capabilities::SHADER_INT64 | Capabilities::TEXTURE_INT64_ATOMIC;
        let depth = DepthDefs { texture: true }.shader_defs();
        let shade = ShadeDefs {
            vertex_colors: true,
            clustered_lights: true,
            texture: true,
            pyramid: true,
            second_counts: true,
            occluded_per_instance: true,
            residency: true,
            shadows: true,
        }
        .shader_defs();
        for (shader, defs) in [(&DEPTH_SHADER, &depth), (&SHADE_SHADER, &shade)] {
            compose_and_validate(shader, defs, caps).unwrap_or_else(|e| panic!("{e}"));
        }
    }

    #[test]
    fn material_depth_is_exact_distinct_and_never_empty() {
        assert_eq!(material_depth(0), 1.0 / 16_777_216.0);
        assert_eq!(material_depth(1), 2.0 / 16_777_216.0);
        for m in [0, 1, 2, 1000, 0xff_fffd] {
            assert!(material_depth(m) < material_depth(m + 1));
            // Exact: the f32 times 2^24 gives back the integer.
            assert_eq!((material_depth(m) * 16_777_216.0) as u32, m + 1);
        }
        assert_eq!(material_depth(u32::MAX), material_depth(0xff_fffe));
        assert!(material_depth(u32::MAX) < 1.0);
    }
}
