// Decodes every vertex and triangle of every meshlet with the shared meshlet module,
// one thread per (meshlet, vertex) and per (meshlet, triangle), for comparison with the
// asset's CPU decoder. Vertices are read as the passes read them (one window of words
// for the grid offsets, one pair for the normal) and field by field
// (`meshlet_vertex_field`); a vertex whose two readings differ is flagged.

#import meshlight::math::read_bits
#import meshlight::meshlet::{Meshlet, Mesh, meshlet_vertex_count, meshlet_triangle_count, meshlet_vertex_field, meshlet_vertex_location, meshlet_grid_offsets, meshlet_normal_location, meshlet_normal_offsets, meshlet_position, meshlet_normal, meshlet_uv, meshlet_uv_word, meshlet_uv_location, meshlet_triangle_location, meshlet_triangle, MESH_FLAG_UVS}

@group(0) @binding(0) var<storage, read> meshlets: array<Meshlet>;
@group(0) @binding(1) var<storage, read> payload: array<u32>;
@group(0) @binding(2) var<storage, read> meshes: array<Mesh>;
// Per meshlet × 255 vertices: position xyz + uv.x, normal xyz + uv.y, the grid offsets'
// bits.
@group(0) @binding(3) var<storage, read_write> vertices: array<vec4<f32>>;
// Per meshlet × 128 triangles: the three local indices, w = 1.
@group(0) @binding(4) var<storage, read_write> triangles: array<vec4<u32>>;
// Per meshlet × 255 vertices: 1 where the window and the field-by-field readings differ.
@group(0) @binding(5) var<storage, read_write> mismatched: array<u32>;

fn field(m: Meshlet, vertex: u32, f: u32) -> u32 {
    let at = meshlet_vertex_field(m, vertex, f);
    return read_bits(vec2(payload[at.x], payload[at.x + 1u]), at.y, at.z);
}

@compute @workgroup_size(128)
fn decode(@builtin(workgroup_id) wg: vec3<u32>, @builtin(local_invocation_index) t: u32) {
    let index = wg.x + wg.y * 65535u;
    if index >= arrayLength(&meshlets) {
        return;
    }
    let m = meshlets[index];
    let mesh = meshes[0];
    for (var v = t; v < meshlet_vertex_count(m); v += 128u) {
        let at = meshlet_vertex_location(m, v);
        let words = vec4(payload[at.x], payload[at.x + 1u], payload[at.x + 2u], payload[at.x + 3u]);
        let grid = meshlet_grid_offsets(m, words, at.y);
        let n_at = meshlet_normal_location(m, v);
        let octahedral = meshlet_normal_offsets(m, vec2(payload[n_at.x], payload[n_at.x + 1u]), n_at);
        let by_field = vec3(field(m, v, 0u), field(m, v, 1u), field(m, v, 2u));
        if any(grid != by_field) || any(octahedral != vec2(field(m, v, 3u), field(m, v, 4u))) {
            mismatched[index * 255u + v] = 1u;
        }
        let p = meshlet_position(m, mesh.position_grid, grid);
        let n = meshlet_normal(m, octahedral);
        var uv = vec2(0.0);
        if (mesh.flags & MESH_FLAG_UVS) != 0u {
            let block = meshlet_uv_word(m);
            let at = meshlet_uv_location(m, v);
            uv = meshlet_uv(m, mesh.uv_grid, vec2(payload[block], payload[block + 1u]), vec2(payload[at.x], payload[at.x + 1u]), at.y);
        }
        vertices[(index * 255u + v) * 3u] = vec4(p, uv.x);
        vertices[(index * 255u + v) * 3u + 1u] = vec4(n, uv.y);
        vertices[(index * 255u + v) * 3u + 2u] = vec4(bitcast<vec3<f32>>(grid), 0.0);
    }
    if t < meshlet_triangle_count(m) {
        let at = meshlet_triangle_location(m, t);
        let c = meshlet_triangle(m, t, vec2(payload[at.x], payload[at.x + 1u]), at.y);
        triangles[index * 128u + t] = vec4(c, 1u);
    }
}
