// Hardware rasteriser for the clusters culling sent right of the slot buffer. Two ways to
// feed the rasteriser, one fragment stage:
// - `indirect_draw`: one instance of 128 × 3 vertices per cluster, drawn indirectly;
// - `mesh_shader` (MESH_SHADER): one mesh workgroup per cluster emits the meshlet's
//   vertices and triangles once each.
// The fragment shader writes the software rasteriser's 64-bit visibility value with
// atomicMax into a storage buffer, or with VIS_TEXTURE into an R64Uint texture.
// `cpu::rasterize` (Rust) is the reference. The mesh variant is this file behind
// `enable wgpu_mesh_shader;` (`MESH_SHADER_SOURCE` in lib.rs): a directive must come
// first, and cannot sit behind an #ifdef.

#import meshlight::dispatch::linear_workgroup
#import meshlight::meshlet::{Meshlet, Mesh, Cluster, MESHLET_MAX_TRIANGLES, MESHLET_MAX_VERTICES, meshlet_vertex_count, meshlet_triangle_count, meshlet_vertex_location, meshlet_grid_offsets, meshlet_position, meshlet_triangle_location, meshlet_triangle, meshlet_material}
#import meshlight::instance::{Instance, Material, MATERIAL_FLAG_DOUBLE_SIDED}
#ifdef ALPHA_MASK
#import meshlight::surface::cut_out
#endif
#import meshlight::instance_table::instance_at
#import meshlight::view::View
#import meshlight::visbuffer64::visbuffer64_pack
#import meshlight::visbuffer::visbuffer_depth_bits

// The uniform block, declared once for Rust and WGSL by `GpuParams` in lib.rs.
#import hw_raster::params::Params

// Cluster slots; hardware clusters fill them from the right end, C - 1 downwards.
@group(0) @binding(0) var<storage, read> raster_clusters: array<Cluster>;
// Word 1: hardware cluster count; word 3: C, the slot capacity.
@group(0) @binding(1) var<storage, read> raster_counts: array<u32>;
// The instances: `instance_at` (meshlight::instance_table, bindings 30 and 31). The
// mesh variant declares the scene's other buffers here rather than importing them from
// meshlight::scene_buffers: naga_oil 0.23 keeps a mesh entry point's output-variable
// handle from the source when it composes, so `raster_ms` validates only while importing
// adds no globals ahead of `mesh_out`.
#ifdef MESH_SHADER
@group(0) @binding(3) var<storage, read> meshes: array<Mesh>;
@group(0) @binding(4) var<storage, read> meshlets: array<Meshlet>;
@group(0) @binding(5) var<storage, read> payload: array<u32>;
@group(0) @binding(10) var<storage, read> materials: array<Material>;
#else
#import meshlight::scene_buffers::{meshes, meshlets, payload, materials}
#endif
// width × height visibility values, row-major; the software rasteriser wrote first.
#ifdef DEPTH_ONLY
// Layers of width × height reverse-Z depth bits; this pass draws layer `params.layer`.
@group(0) @binding(6) var<storage, read_write> visbuffer: array<atomic<u32>>;
#else
#ifdef VIS_TEXTURE
@group(0) @binding(6) var visbuffer: texture_storage_2d<r64uint, atomic>;
#else
@group(0) @binding(6) var<storage, read_write> visbuffer: array<atomic<u64>>;
#endif
#endif
@group(0) @binding(7) var<uniform> view: View;
@group(0) @binding(8) var<uniform> params: Params;

// The grid offsets of vertex `vertex` of meshlet `m`, read from the payload in one window:
// `meshlight::scene_buffers`' `payload_grid_offsets`, over the payload this file declares
// for the mesh variant (see above).
fn grid_offsets(m: Meshlet, vertex: u32) -> vec3<u32> {
    let at = meshlet_vertex_location(m, vertex);
    let words = vec4(payload[at.x], payload[at.x + 1u], payload[at.x + 2u], payload[at.x + 3u]);
    return meshlet_grid_offsets(m, words, at.y);
}

// Clip position of vertex `k` of the cluster's meshlet, with the software rasteriser's
// operations, so both rasterisers start from the same bits.
fn clip_position(instance: Instance, mesh: Mesh, m: Meshlet, k: u32) -> vec4<f32> {
    let p = meshlet_position(m, mesh.position_grid, grid_offsets(m, k));
    let world = instance.world_from_local * vec4(p, 1.0);
    return view.view_projection * vec4(world.xyz, 1.0);
}

// Whether meshlet `m` placed by `instance` is drawn with a double-sided material: its
// back faces are turned to face the eye (two corners swapped), so the pipeline's
// back-face culling keeps them.
// Without TWO_SIDED (a scene with no such material) no material is read.
fn double_sided(instance: Instance, m: Meshlet) -> bool {
#ifdef TWO_SIDED
    return (materials[instance.material + meshlet_material(m)].flags & MATERIAL_FLAG_DOUBLE_SIDED) != 0u;
#else
    return false;
#endif
}

// Whether clip-space corners (a, b, c) are a back face: counter-clockwise in NDC is front,
// and the sign of the homogeneous determinant tells the facing of the visible part even
// when a corner lies behind the eye (Olano and Greer's 2DH rasterisation).
fn back_facing(a: vec4<f32>, b: vec4<f32>, c: vec4<f32>) -> bool {
    return determinant(mat3x3(a.xyw, b.xyw, c.xyw)) < 0.0;
}

// The visibility write of one fragment; position.z is the NDC depth, since the
// viewport's depth range is 0..1. With ALPHA_MASK a fragment of a MASK material that
// `cut_out` leaves undrawn (position.xy is the pixel centre) writes nothing.
fn write_visibility(position: vec4<f32>, id: vec2<u32>) {
    let x = u32(position.x);
    let y = u32(position.y);
    if x >= params.width || y >= params.height {
        return;
    }
#ifdef ALPHA_MASK
    if cut_out(raster_clusters[id.x], id.y, position.xy, vec2(f32(params.width), f32(params.height)), view.view_projection) {
        return;
    }
#endif
#ifdef DEPTH_ONLY
    // The visibility value's high word.
    let layer_start = params.layer * params.width * params.height;
    atomicMax(&visbuffer[layer_start + y * params.width + x], visbuffer_depth_bits(position.z));
#else
    let value = visbuffer64_pack(position.z, id.x, id.y);
#ifdef VIS_TEXTURE
    textureAtomicMax(visbuffer, vec2(x, y), value);
#else
    atomicMax(&visbuffer[y * params.width + x], value);
#endif
#endif
}

struct VertexOut {
    @builtin(position) position: vec4<f32>,
    // x: the cluster's slot (its visibility id), y: the triangle in the meshlet.
    @location(0) @interpolate(flat) id: vec2<u32>,
}

@vertex
fn raster_vs(@builtin(vertex_index) v: u32, @builtin(instance_index) j: u32) -> VertexOut {
    var out: VertexOut;
    let capacity = raster_counts[3];
    let t = v / 3u;
    // Triangles past the meshlet's count (and instances past the capacity, which
    // culling never produces) get NaN corners: the rasteriser drops the triangle.
    out.position = vec4(bitcast<f32>(params.nan_bits));
    if j >= capacity || t >= MESHLET_MAX_TRIANGLES {
        return out;
    }
    let slot = capacity - 1u - j;
    out.id = vec2(slot, t);
    let cluster = raster_clusters[slot];
    let m = meshlets[cluster.meshlet];
    if t >= meshlet_triangle_count(m) {
        return out;
    }
    let instance = instance_at(cluster.instance);
    let mesh = meshes[instance.mesh];
    let at = meshlet_triangle_location(m, t);
    let corners = meshlet_triangle(m, t, vec2(payload[at.x], payload[at.x + 1u]), at.y);
    if double_sided(instance, m) {
        // Every corner's invocation decides alike, from the same three positions, and
        // takes its own from them (corners 1 and 2 swapped for a back face).
        let p = array(
            clip_position(instance, mesh, m, corners.x),
            clip_position(instance, mesh, m, corners.y),
            clip_position(instance, mesh, m, corners.z),
        );
        var k = v % 3u;
        if back_facing(p[0], p[1], p[2]) && k != 0u {
            k = 3u - k;
        }
        out.position = p[k];
        return out;
    }
    out.position = clip_position(instance, mesh, m, corners[v % 3u]);
    return out;
}

// Writes nothing to its (masked) colour target.
@fragment
fn raster_fs(in: VertexOut) -> @location(0) vec4<f32> {
    write_visibility(in.position, in.id);
    return vec4(0.0);
}

#ifdef MESH_SHADER
struct MeshVertex {
    @builtin(position) position: vec4<f32>,
}

struct MeshPrimitive {
    @builtin(triangle_indices) indices: vec3<u32>,
    // x: the cluster's slot, y: the triangle in the meshlet.
    @per_primitive @location(0) @interpolate(flat) id: vec2<u32>,
}

struct MeshOutput {
    @builtin(vertices) vertices: array<MeshVertex, MESHLET_MAX_VERTICES>,
    @builtin(primitives) primitives: array<MeshPrimitive, MESHLET_MAX_TRIANGLES>,
    @builtin(vertex_count) vertex_count: u32,
    @builtin(primitive_count) primitive_count: u32,
}

var<workgroup> mesh_out: MeshOutput;

// Threads of a mesh workgroup: one warp, each looping over vertices and triangles
// (NVIDIA's advice for mesh shaders; 128 threads measured slower on the H100).
const MESH_GROUP: u32 = 32u;

// One workgroup per hardware cluster: linear id `wg.y * params.row + wg.x`, hardware
// cluster j in slot C - 1 - j; ids at or past the count emit nothing.
@mesh(mesh_out)
@workgroup_size(MESH_GROUP)
fn raster_ms(@builtin(workgroup_id) wg: vec3<u32>, @builtin(local_invocation_index) lane: u32) {
    let j = linear_workgroup(wg, params.row);
    let capacity = raster_counts[3];
    let live = j < raster_counts[1] && j < capacity;
    var vertices = 0u;
    var triangles = 0u;
    if live {
        let slot = capacity - 1u - j;
        let cluster = raster_clusters[slot];
        let m = meshlets[cluster.meshlet];
        let instance = instance_at(cluster.instance);
        let mesh = meshes[instance.mesh];
        vertices = meshlet_vertex_count(m);
        triangles = meshlet_triangle_count(m);
        for (var v = lane; v < vertices; v += MESH_GROUP) {
            mesh_out.vertices[v].position = clip_position(instance, mesh, m, v);
        }
        let two_sided = double_sided(instance, m);
        for (var t = lane; t < triangles; t += MESH_GROUP) {
            let at = meshlet_triangle_location(m, t);
            var corners = meshlet_triangle(m, t, vec2(payload[at.x], payload[at.x + 1u]), at.y);
            if two_sided {
                // From the positions again: reading another lane's outputs would need
                // a barrier in uniform control flow.
                let a = clip_position(instance, mesh, m, corners.x);
                let b = clip_position(instance, mesh, m, corners.y);
                let c = clip_position(instance, mesh, m, corners.z);
                if back_facing(a, b, c) {
                    corners = corners.xzy;
                }
            }
            mesh_out.primitives[t].indices = corners;
            mesh_out.primitives[t].id = vec2(slot, t);
        }
    }
    if lane == 0u {
        mesh_out.vertex_count = vertices;
        mesh_out.primitive_count = triangles;
    }
}

struct MeshFragment {
    @builtin(position) position: vec4<f32>,
}

struct MeshFragmentPrimitive {
    @per_primitive @location(0) @interpolate(flat) id: vec2<u32>,
}

@fragment
fn raster_mesh_fs(in: MeshFragment, primitive: MeshFragmentPrimitive) -> @location(0) vec4<f32> {
    write_visibility(in.position, primitive.id);
    return vec4(0.0);
}

// The mesh dispatch `[row, rows, 1]` over the hardware clusters, written by `mesh_args`.
@group(0) @binding(9) var<storage, read_write> mesh_args: array<u32>;

// One thread: `min(count, total)` workgroups as rows of `params.row`, both under the
// adapter's mesh-dispatch limits (per dimension, and in all).
@compute @workgroup_size(1)
fn mesh_dispatch() {
    let count = min(min(raster_counts[1], raster_counts[3]), params.total);
    mesh_args[0] = min(count, params.row);
    mesh_args[1] = (count + params.row - 1u) / params.row;
    mesh_args[2] = 1u;
}
#endif
