// The rectangle raster of features.wgsl with a 64-bit atomic texture as visibility target.

struct RectVertex {
    // x, y in clip space; z, w unused.
    pos: vec4<f32>,
    // x: high word of the key (depth), y: low word (rectangle id).
    key: vec4<u32>,
}

@group(0) @binding(0) var<storage, read> rect_vertices: array<RectVertex>;
@group(0) @binding(1) var vis: texture_storage_2d<r64uint, atomic>;

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
    let key = (u64(in.key.x) << 32u) | u64(in.key.y);
    textureAtomicMax(vis, vec2<u32>(u32(in.pos.x), u32(in.pos.y)), key);
    return vec4<f32>(1.0);
}
