//! Stage `brute_force`, implementation `instanced_draw`: the baseline the virtual-geometry
//! renderer is measured against. Every instance draws the full-resolution (LOD 0) mesh
//! with one instanced indexed draw into a depth and an id target: no culling beyond the
//! hardware's back-face and clip tests, no LOD, no visibility buffer.
//!
//! It answers "what does the naive renderer cost for this scene and camera", so it is
//! kept as plain as a renderer without virtual geometry would be: indices from an index
//! buffer, so the hardware's post-transform vertex cache shares vertices between
//! triangles as it would for any indexed mesh, and the depth test in fixed function.
//!
//! # Contract
//!
//! | slot | access | holds | |
//! |------|--------|-------|---|
//! | `positions` | storage read | vec4<f32> | mesh-space LOD-0 positions, `w` ignored ([`lod0_buffers`]) |
//! | `indices` | index | u32 | three per triangle, counter-clockwise front faces; `index_count` of them |
//! | `instances` | storage read | Instance | the GPU scene's instances; `instance_count` of them are drawn |
//! | `depth` | depth target | Depth32Float | `width × height`, reverse-Z NDC depth; 0 where empty |
//! | `ids` | render target | R32Uint | `width × height`, `instance + 1`; 0 where empty |
//!
//! Frame input `view` (`meshlight_shaders::cpu::layout::View`): its `viewport_size` must
//! equal the params `width` × `height`, and so must both targets' sizes (record errors
//! name both otherwise). Params `width`, `height`, `index_count` (a multiple of 3) and
//! `instance_count`, all > 0. Needs no optional device feature.
//!
//! # Definitions the tests pin down
//!
//! - Every drawn instance draws the same mesh, the one `positions` and `indices` hold;
//!   the instance's own `mesh` field is ignored (the baseline scene is copies of one mesh).
//! - Clip position: `view_projection * (world_from_local * position).xyz1`, the
//!   operations of the other rasterisers, so all start from the same bits.
//! - Depth: reverse-Z as everywhere in the project (the near plane at 1, infinity at 0):
//!   both targets are cleared every frame, depth to 0, and a fragment is kept when its
//!   depth is `Greater` than what is stored. Ties keep the earlier fragment: instance
//!   order, then triangle order, the draw's rasterisation order.
//! - Ids: `instance + 1` with 0 for empty pixels. Not a triangle id: an indexed draw gives
//!   the vertex shader no triangle number, `primitive_index` needs a device feature, and
//!   LOD 0 of the default mesh has more than 2^20 triangles, so no (instance, triangle)
//!   split of 32 bits fits every scene. Together with depth, the instance pins down what
//!   each pixel shows, which is what the baseline's image must get right.
//! - Front faces are counter-clockwise in NDC; back faces are culled, as in `hw_raster`.
//!   Coverage is the hardware's (pixel centres, top-left rule, its sub-pixel precision).
//! - [`cpu::draw`] is the reference (float edge functions at pixel centres).

#![warn(missing_docs)]

pub mod cpu;

use meshlight_gpu_scene::gpu::elements;
use meshlight_gpu_scene::view::frame_view;
use meshlight_graph::prelude::*;
use meshlight_shaders::cpu::layout::Instance;

/// The stage name pipelines use.
pub const STAGE: &str = "brute_force";
/// The implementation name pipelines use.
pub const IMPLEMENTATION: &str = "instanced_draw";
/// The frame input holding the `View`.
pub const VIEW_INPUT: &str = "view";
/// The format of `depth`.
pub const DEPTH_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;
/// The format of `ids`.
pub const IDS_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::R32Uint;
/// The id of a pixel no triangle covers.
pub const EMPTY_ID: u32 = 0;

/// The baseline's WGSL (`draw.wgsl`), public so the shader tests compose and validate
/// every entry point.
pub const SHADER: PassShader = pass_shader!("brute_force::draw", "draw.wgsl");

/// The id the `ids` target holds where `instance` is the nearest surface.
pub fn instance_id(instance: u32) -> u32 {
    instance + 1
}

/// The slots every implementation of `brute_force` shares.
pub fn contract() -> StageContract {
    StageContract {
        stage: STAGE,
        slots: vec![
            Slot::read(
                "positions",
                Element::VEC4_F32,
                "mesh-space LOD-0 positions, w ignored",
            ),
            Slot::buffer(
                "indices",
                Access::Index,
                Element::U32,
                "three per triangle, counter-clockwise front faces",
            ),
            Slot::read("instances", elements::INSTANCE, "the scene's instances"),
            Slot::texture(
                "depth",
                Access::DepthTarget,
                Some(DEPTH_FORMAT),
                "reverse-Z depth; 0 where empty",
            ),
            Slot::texture(
                "ids",
                Access::RenderTarget,
                Some(IDS_FORMAT),
                "instance + 1; 0 where empty",
            ),
        ],
    }
}

/// One mesh's LOD 0 in the layout the `positions` and `indices` slots take.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Lod0Buffers {
    /// Mesh-space positions, `w` = 1: a `vec4` is one aligned 16-byte load in the vertex
    /// shader, where three scalars would be three.
    pub positions: Vec<[f32; 4]>,
    /// Three per triangle, counter-clockwise front faces, indexing `positions`.
    pub indices: Vec<u32>,
}

impl Lod0Buffers {
    /// The positions as the bytes a `positions` buffer is created with.
    pub fn position_bytes(&self) -> &[u8] {
        bytemuck::cast_slice(&self.positions)
    }
    /// The indices as the bytes an `indices` buffer is created with.
    pub fn index_bytes(&self) -> &[u8] {
        bytemuck::cast_slice(&self.indices)
    }
    /// The `index_count` param that draws all of it.
    pub fn index_count(&self) -> u32 {
        self.indices.len() as u32
    }
    /// Triangles drawn per instance, for throughput figures.
    pub fn triangle_count(&self) -> u32 {
        self.index_count() / 3
    }
}

/// The buffers that draw `mesh` at full resolution. Pass the mesh the scene's asset was
/// built from, so the baseline draws the triangles the meshlet DAG's LOD 0 holds (the
/// builder only drops degenerate triangles, which cover nothing). Source meshes are the
/// baker's (the `build` feature).
#[cfg(feature = "build")]
pub fn lod0_buffers(mesh: &meshlight_scene::Mesh) -> Lod0Buffers {
    Lod0Buffers {
        positions: mesh
            .positions
            .iter()
            .map(|p| p.extend(1.0).into())
            .collect(),
        indices: mesh.indices.clone(),
    }
}

/// The `instanced_draw` implementation.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct BruteForce {
    /// The targets' size in pixels, which the view's viewport must equal.
    pub width: u32,
    /// The targets' height in pixels (see `width`).
    pub height: u32,
    /// Indices drawn per instance, from the start of `indices`.
    pub index_count: u32,
    /// Instances drawn, from the start of `instances`.
    pub instance_count: u32,
}

const PARAM_KEYS: [&str; 4] = ["width", "height", "index_count", "instance_count"];

impl BruteForce {
    /// Reads `width`, `height`, `index_count` and `instance_count` (all required).
    pub fn from_params(params: &Params) -> Result<Self> {
        params.only(&PARAM_KEYS)?;
        let pass = Self {
            width: params.u32("width", 0)?,
            height: params.u32("height", 0)?,
            index_count: params.u32("index_count", 0)?,
            instance_count: params.u32("instance_count", 0)?,
        };
        pass.validate()?;
        Ok(pass)
    }

    /// Checks the params, for passes built from a file and in code alike.
    pub fn validate(&self) -> Result<()> {
        Params::positive_size(
            self.width,
            self.height,
            "the size of the depth and id targets",
        )?;
        let n = self.index_count;
        if n == 0 || !n.is_multiple_of(3) {
            return Err(GraphError::parameter(format!(
                "`index_count` must be a positive multiple of 3 (three indices per triangle), got {n}; use the mesh's index count (`Lod0Buffers::index_count`)"
            )));
        }
        if self.instance_count == 0 {
            return Err(GraphError::parameter(
                "`instance_count` must be > 0; set it to the number of instances in the scene's `instances` buffer",
            ));
        }
        Ok(())
    }
}

/// Checks that the texture bound to `slot` has the params' size: the draw maps NDC to the
/// attachment, so a target of another size would hold a stretched image.
fn check_target(ctx: &RecordContext<'_>, slot: &str, width: u32, height: u32) -> Result<()> {
    if let ResourceDesc::Texture(t) = ctx.desc(slot)?
        && (t.width, t.height) != (width, height)
    {
        return Err(GraphError::Record {
            pass: ctx.pass_name().to_string(),
            message: format!(
                "target `{slot}` is {} × {} but the params say {width} × {height}; bind a target of the viewport's size",
                t.width, t.height
            ),
        });
    }
    Ok(())
}

fn store_op(ctx: &RecordContext<'_>, slot: &str) -> wgpu::StoreOp {
    match ctx.attachment_ops(slot).map(|ops| ops.store) {
        Some(StoreOp::Discard) => wgpu::StoreOp::Discard,
        _ => wgpu::StoreOp::Store,
    }
}

impl Pass for BruteForce {
    fn implementation(&self) -> Implementation {
        Implementation::new(IMPLEMENTATION, contract())
    }
    fn setup(&self, ctx: &mut SetupContext) -> Result<()> {
        self.validate()?;
        ctx.min_bytes("indices", self.index_count as u64 * 4);
        ctx.min_bytes(
            "instances",
            self.instance_count as u64 * size_of::<Instance>() as u64,
        );
        // At least one vertex; indices past the end read what wgpu's bounds checks give,
        // so `lod0_buffers` keeps the two consistent.
        ctx.min_bytes("positions", 16);
        ctx.frame_input(VIEW_INPUT);
        let layout = BindingLayout::from_shader_render("brute_force");
        ctx.program(
            "draw",
            ProgramDesc::render(&SHADER, "draw_vs")
                .fragment("draw_fs")
                .target(ColorTarget::new("ids"))
                .depth(DepthTarget {
                    target: "depth",
                    compare: wgpu::CompareFunction::Greater,
                    write: true,
                })
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
        check_target(ctx, "depth", self.width, self.height)?;
        check_target(ctx, "ids", self.width, self.height)?;
        let program = ctx.render("draw")?;
        let bind_group = ctx.bind_group(&program, 0, &[("view", bytemuck::bytes_of(&view))])?;
        let (indices, _) = ctx.buffer("indices")?;
        let (_, depth) = ctx.texture("depth")?;
        let (_, ids) = ctx.texture("ids")?;
        let (depth_store, ids_store) = (store_op(ctx, "depth"), store_op(ctx, "ids"));
        // Both targets are cleared here whatever load op the plan derived (an imported
        // target would be loaded): the baseline's depth test must never see an earlier
        // frame, or it would reject everything and time nothing.
        let mut pass = ctx
            .encoder()
            .begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("brute_force"),
                color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                    view: &ids,
                    depth_slice: None,
                    resolve_target: None,
                    ops: wgpu::Operations {
                        load: wgpu::LoadOp::Clear(wgpu::Color {
                            r: EMPTY_ID as f64,
                            g: 0.0,
                            b: 0.0,
                            a: 0.0,
                        }),
                        store: ids_store,
                    },
                })],
                depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                    view: &depth,
                    depth_ops: Some(wgpu::Operations {
                        load: wgpu::LoadOp::Clear(0.0),
                        store: depth_store,
                    }),
                    stencil_ops: None,
                }),
                timestamp_writes: None,
                occlusion_query_set: None,
                multiview_mask: None,
            });
        pass.set_pipeline(&program.pipeline);
        pass.set_bind_group(0, &bind_group, &[]);
        pass.set_index_buffer(
            indices.slice(..self.index_count as u64 * 4),
            wgpu::IndexFormat::Uint32,
        );
        pass.draw_indexed(0..self.index_count, 0, 0..self.instance_count);
        Ok(())
    }
}

/// Registers `brute_force` (implementation `instanced_draw`) for pipeline files.
pub fn register(registry: &mut Registry) {
    registry.register(STAGE, IMPLEMENTATION, BruteForce::from_params);
}

#[cfg(test)]
mod tests {
    use super::*;
    use meshlight_shaders::{Capabilities, ShaderLibrary};
    use meshlight_testing::params;

    #[test]
    fn params_are_read_and_checked() {
        let ok = "width = 96\nheight = 64\nindex_count = 30\ninstance_count = 4";
        assert_eq!(
            BruteForce::from_params(&params(ok)).unwrap(),
            BruteForce {
                width: 96,
                height: 64,
                index_count: 30,
                instance_count: 4
            }
        );
        let zero_width = "width = 0\nheight = 64\nindex_count = 30\ninstance_count = 4";
        let odd_indices = "width = 96\nheight = 64\nindex_count = 31\ninstance_count = 4";
        meshlight_testing::assert_params(
            |text| BruteForce::from_params(&params(text)),
            &[ok],
            &[
                (zero_width, "`width`"),
                (zero_width, "0 × 64"),
                (odd_indices, "`index_count`"),
                (odd_indices, "31"),
                (
                    "width = 96\nheight = 64\nindex_count = 30",
                    "`instance_count`",
                ),
                // A misspelt key is refused by name.
                (
                    "width = 96\nheight = 64\nindex_count = 30\ninstance_count = 4\ninstances = 4",
                    "`instances`",
                ),
            ],
        );
    }

    #[cfg(feature = "build")]
    #[test]
    fn lod0_buffers_keep_the_mesh() {
        let mesh = meshlight_scene::procedural_mesh(3);
        let b = lod0_buffers(&mesh);
        assert_eq!(b.indices, mesh.indices);
        assert_eq!(b.triangle_count() as usize, mesh.triangle_count());
        assert_eq!(b.positions.len(), mesh.positions.len());
        for (q, p) in b.positions.iter().zip(&mesh.positions) {
            assert_eq!(*q, [p.x, p.y, p.z, 1.0]);
        }
        assert_eq!(b.position_bytes().len(), mesh.positions.len() * 16);
        assert_eq!(b.index_bytes().len(), mesh.indices.len() * 4);
    }

    #[test]
    fn the_shader_composes_and_validates() {
        let mut library = ShaderLibrary::new(Capabilities::empty()).unwrap();
        let entries = library
            .entry_point_names(&SHADER, &[])
            .unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(entries, ["draw_vs", "draw_fs"]);
    }
}
