//! Pixel-aligned rectangles and their CPU visibility: what the raster tests draw. Edges
//! lie on pixel boundaries, so no pixel centre is ambiguous and every rasteriser agrees.
#![allow(dead_code)]

use meshlight_graph::{
    Access, Bindings, Buffer, BufferDesc, ColorAttachment, ColorTarget, Element, GraphBuilder,
    Handle, ProgramDesc, RecordContext, Result, SetupContext, Slot, Texture, TextureDesc,
    synthetic,
};
use meshlight_shaders::LocalModule;

/// Pixel rectangles (x0, y0, x1, y1) with a depth word and an id.
pub const RECTS: [([u32; 4], u32, u32); 4] = [
    ([0, 0, 40, 30], 100, 1),
    ([10, 5, 64, 20], 300, 2),
    ([20, 10, 50, 64], 200, 3),
    ([30, 0, 34, 64], 300, 4),
];
pub const W: u32 = 64;
pub const H: u32 = 48;

pub fn cpu_rects() -> Vec<u64> {
    let mut vis = vec![0u64; (W * H) as usize];
    for ([x0, y0, x1, y1], depth, id) in RECTS {
        for y in y0..y1.min(H) {
            for x in x0..x1.min(W) {
                let key = (depth as u64) << 32 | id as u64;
                let px = &mut vis[(y * W + x) as usize];
                *px = (*px).max(key);
            }
        }
    }
    vis
}

/// One vertex of the rectangles as the raster shaders read it from storage.
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
pub struct RectVertex {
    pub pos: [f32; 4],
    pub key: [u32; 4],
}

/// Two triangles per rectangle, clockwise in clip space, keyed `[depth, id]`.
pub fn rect_vertices() -> Vec<RectVertex> {
    let ndc = |x: u32, y: u32| {
        [
            x as f32 / W as f32 * 2.0 - 1.0,
            1.0 - y.min(H) as f32 / H as f32 * 2.0,
        ]
    };
    let mut v = Vec::new();
    for ([x0, y0, x1, y1], depth, id) in RECTS {
        let corners = [ndc(x0, y0), ndc(x1, y0), ndc(x1, y1), ndc(x0, y1)];
        for i in [0, 1, 2, 0, 2, 3] {
            v.push(RectVertex {
                pos: [corners[i][0], corners[i][1], 0.0, 1.0],
                key: [depth, id, 0, 0],
            });
        }
    }
    v
}

/// The WGSL of the rectangles' vertices (`#import test::rect_vertices`): the layout of a
/// [`RectVertex`], its binding and the vertex stage the rasters share.
pub const RECT_VERTICES_WGSL: LocalModule = LocalModule {
    name: "test::rect_vertices",
    source: crate::support::support_text!("rect_vertices.wgsl"),
    file_path: "graph/tests/support/rect_vertices.wgsl",
};

/// How the raster passes' slots name a [`RectVertex`].
pub const RECT_VERTEX: Element = Element::named("RectVertex", 32);

/// Imports the storage buffer `rects` of `count` vertices.
pub fn import_rect_vertices(g: &mut GraphBuilder, count: u32) -> Handle<Buffer> {
    let desc = BufferDesc::array(RECT_VERTEX, count as u64);
    g.import_buffer("rects", desc, wgpu::BufferUsages::STORAGE)
}

/// The slot a raster pass reads the vertices through.
pub fn rects_slot() -> Slot {
    Slot::buffer("rects", Access::StorageRead, RECT_VERTEX, "")
}

/// Adds pass `name` copying the `W × H` texture `texture` of `format` into `out` and
/// exports `out`, so the test can read what was drawn.
pub fn copy_out(
    g: &mut GraphBuilder,
    name: &str,
    format: wgpu::TextureFormat,
    texture: Handle<Texture>,
    out: Handle<Buffer>,
) {
    let copy = synthetic::CopyTextureToBuffer {
        format,
        width: W,
        height: H,
    };
    let bindings = Bindings::new().bind("texture", texture).bind("buffer", out);
    let copied = g.add_pass(name, copy, bindings).unwrap();
    g.export(copied.buffer("buffer").unwrap());
}

/// Declares a raster into `vis` through a masked colour target: the `W × H` dummy target a
/// render pipeline must have, and `program`, drawing into it, as the program `rects`.
pub fn declare_masked_raster(ctx: &mut SetupContext, program: ProgramDesc) {
    ctx.scratch_texture(
        "dummy",
        TextureDesc::d2(wgpu::TextureFormat::R8Unorm, W, H),
        &[Access::RenderTarget],
    );
    ctx.program("rects", program.target(ColorTarget::masked("dummy")));
}

/// Clears `vis` and records the program `rects` into the dummy target, bind group 0 built
/// with `uniforms`; `draw` issues the draw.
pub fn record_masked_raster(
    ctx: &mut RecordContext<'_>,
    uniforms: &[(&str, &[u8])],
    draw: impl FnOnce(&mut wgpu::RenderPass<'_>),
) -> Result<()> {
    ctx.clear("vis")?;
    let dummy = [ColorAttachment::new("dummy")];
    super::render_once(ctx, "rects", uniforms, &dummy, None, draw)
}
