// The brute-force baseline: every instance draws the whole LOD-0 mesh with one instanced
// indexed draw; the fixed-function depth test (Greater, reverse-Z) keeps the nearest
// surface and the colour target its instance id. `cpu::draw` (Rust) is the reference.

#import meshlight::instance::Instance
#import meshlight::view::View

// Mesh-space LOD-0 positions, indexed by the index buffer's values; w is ignored.
@group(0) @binding(0) var<storage, read> positions: array<vec4<f32>>;
// The scene's instances; instance_index picks one, and its mesh field is ignored.
@group(0) @binding(1) var<storage, read> instances: array<Instance>;
// The frame's camera; its viewport equals the targets' size.
@group(0) @binding(2) var<uniform> view: View;

struct VertexOut {
    @builtin(position) position: vec4<f32>,
    // instance + 1, the same at every corner of a triangle.
    @location(0) @interpolate(flat) id: u32,
}

// With an indexed draw and base vertex 0, vertex_index is the index buffer's value.
@vertex
fn draw_vs(@builtin(vertex_index) v: u32, @builtin(instance_index) i: u32) -> VertexOut {
    let instance = instances[i];
    // The same operations as the other rasterisers, so all see the same clip position.
    let world = instance.world_from_local * vec4(positions[v].xyz, 1.0);
    var out: VertexOut;
    out.position = view.view_projection * vec4(world.xyz, 1.0);
    out.id = i + 1u;
    return out;
}

@fragment
fn draw_fs(in: VertexOut) -> @location(0) u32 {
    return in.id;
}
