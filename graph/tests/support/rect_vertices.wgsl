#define_import_path test::rect_vertices

// The rectangles of `rects.rs` as the raster tests read them from storage, and the vertex
// stage every raster of them shares: each vertex carries its 64-bit key, flat, to the
// fragment stage that keeps the largest one per pixel.

struct RectVertex {
    // x, y in clip space (pixel edges, so no pixel centre lies on an edge); z, w unused.
    pos: vec4<f32>,
    // x: high word of the key (depth), y: low word (rectangle id).
    key: vec4<u32>,
}

@group(0) @binding(0) var<storage, read> rect_vertices: array<RectVertex>;

struct VOut {
    @builtin(position) pos: vec4<f32>,
    @location(0) @interpolate(flat) key: vec2<u32>,
}

// Vertex `v` of the rectangles, at a depth no test reads.
fn rect_vertex(v: u32) -> VOut {
    let r = rect_vertices[v];
    return VOut(vec4<f32>(r.pos.xy, 0.5, 1.0), r.key.xy);
}
