// Kernels and raster stages for the frame-graph feature tests: each result is easy to
// predict exactly on the CPU.

// ---- raster: rectangles drawn into a masked target; the fragment shader keeps the
// largest 64-bit key per pixel in a storage buffer.

#import test::rect_vertices::{VOut, rect_vertex}

struct RasterParams {
    // Width of the visibility buffer in pixels.
    width: u32,
    _pad: vec3<u32>,
}

// Binding 0 is the rectangles' vertices, in the imported module.
@group(0) @binding(1) var<storage, read_write> vis: array<atomic<u64>>;
@group(0) @binding(2) var<uniform> raster: RasterParams;

@vertex
fn rect_vs(@builtin(vertex_index) v: u32) -> VOut {
    return rect_vertex(v);
}

@fragment
fn rect_fs(in: VOut) -> @location(0) vec4<f32> {
    let x = u32(in.pos.x);
    let y = u32(in.pos.y);
    let key = (u64(in.key.x) << 32u) | u64(in.key.y);
    atomicMax(&vis[y * raster.width + x], key);
    return vec4<f32>(1.0);
}
