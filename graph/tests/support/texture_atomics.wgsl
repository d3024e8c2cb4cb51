// The rectangle raster of features.wgsl with a 64-bit atomic texture as visibility target.

#import test::rect_vertices::{VOut, rect_vertex}

// Binding 0 is the rectangles' vertices, in the imported module.
@group(0) @binding(1) var vis: texture_storage_2d<r64uint, atomic>;

@vertex
fn rect_vs(@builtin(vertex_index) v: u32) -> VOut {
    return rect_vertex(v);
}

@fragment
fn rect_fs(in: VOut) -> @location(0) vec4<f32> {
    let key = (u64(in.key.x) << 32u) | u64(in.key.y);
    textureAtomicMax(vis, vec2<u32>(u32(in.pos.x), u32(in.pos.y)), key);
    return vec4<f32>(1.0);
}
