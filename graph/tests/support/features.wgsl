// Kernels and raster stages for the frame-graph feature tests: each result is easy to
// predict exactly on the CPU.

// ---- raster: rectangles drawn into a masked target; the fragment shader keeps the
// largest 64-bit key per pixel in a storage buffer.

struct RectVertex {
    // x, y in clip space (pixel edges, so no pixel centre lies on an edge); z, w unused.
    pos: vec4<f32>,
    // x: high word of the key (depth), y: low word (rectangle id).
    key: vec4<u32>,
}

struct RasterParams {
    // Width of the visibility buffer in pixels.
    width: u32,
    _pad: vec3<u32>,
}

@group(0) @binding(0) var<storage, read> rect_vertices: array<RectVertex>;
@group(0) @binding(1) var<storage, read_write> vis: array<atomic<u64>>;
@group(0) @binding(2) var<uniform> raster: RasterParams;

struct VOut {
    @builtin(position) pos: vec4<f32>,
    @location(0) @interpolate(flat) key: vec2<u32>,
}

@vertex
fn rect_vs(@builtin(vertex_index) v: u32) -> VOut {
    let r = rect_vertices[v];
    return VOut(vec4<f32>(r.pos.xy, 0.5, 1.0), r.key.xy);
}

@fragment
fn rect_fs(in: VOut) -> @location(0) vec4<f32> {
    let x = u32(in.pos.x);
    let y = u32(in.pos.y);
    let key = (u64(in.key.x) << 32u) | u64(in.key.y);
    atomicMax(&vis[y * raster.width + x], key);
    return vec4<f32>(1.0);
}
