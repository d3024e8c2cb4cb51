// Hardware rasteriser for the clusters culling sent right of the slot buffer: one
// instance of 128 × 3 vertices per cluster, drawn indirectly; the fragment shader writes
// the same 64-bit visibility value as the software rasteriser with atomicMax.
// `cpu::rasterize` (Rust) is the reference.

#import meshlight::math::read_bits
#import meshlight::meshlet::{Meshlet, Mesh, Cluster, MESHLET_MAX_TRIANGLES, meshlet_triangle_count, meshlet_vertex_field, meshlet_position, meshlet_triangle_location, meshlet_triangle}
#import meshlight::instance::Instance
#import meshlight::view::View
#import meshlight::visbuffer64::visbuffer64_pack

struct Params {
    // Visibility buffer size in pixels (the viewport's).
    width: u32,
    height: u32,
    // 0x7fc00000, a quiet NaN: discarded vertices take it as every coordinate. It comes
    // from the uniform because shader validation refuses a NaN constant.
    nan_bits: u32,
    _pad: u32,
}

// Cluster slots; hardware clusters fill them from the right end, C - 1 downwards.
@group(0) @binding(0) var<storage, read> raster_clusters: array<Cluster>;
// Word 3: C, the slot capacity.
@group(0) @binding(1) var<storage, read> raster_counts: array<u32>;
@group(0) @binding(2) var<storage, read> instances: array<Instance>;
@group(0) @binding(3) var<storage, read> meshes: array<Mesh>;
@group(0) @binding(4) var<storage, read> meshlets: array<Meshlet>;
@group(0) @binding(5) var<storage, read> payload: array<u32>;
// width × height visibility values, row-major; the software rasteriser wrote first.
@group(0) @binding(6) var<storage, read_write> visbuffer: array<atomic<u64>>;
@group(0) @binding(7) var<uniform> view: View;
@group(0) @binding(8) var<uniform> params: Params;

struct VertexOut {
    @builtin(position) position: vec4<f32>,
    // x: the cluster's slot (its visibility id), y: the triangle in the meshlet.
    @location(0) @interpolate(flat) id: vec2<u32>,
}

fn field(m: Meshlet, vertex: u32, f: u32) -> u32 {
    let at = meshlet_vertex_field(m, vertex, f);
    return read_bits(vec2(payload[at.x], payload[at.x + 1u]), at.y, at.z);
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
    let instance = instances[cluster.instance];
    let mesh = meshes[instance.mesh];
    let at = meshlet_triangle_location(m, mesh.flags, t);
    let corners = meshlet_triangle(m, t, vec2(payload[at.x], payload[at.x + 1u]), at.y);
    let k = corners[v % 3u];
    let p = meshlet_position(m, mesh.position_grid, vec3(field(m, k, 0u), field(m, k, 1u), field(m, k, 2u)));
    // The same operations as the software rasteriser, so both see the same clip position.
    let world = instance.world_from_local * vec4(p, 1.0);
    out.position = view.view_projection * vec4(world.xyz, 1.0);
    return out;
}

// Writes nothing to its (masked) colour target; position.z is the NDC depth, since the
// viewport's depth range is 0..1.
@fragment
fn raster_fs(in: VertexOut) -> @location(0) vec4<f32> {
    let x = u32(in.position.x);
    let y = u32(in.position.y);
    if x < params.width && y < params.height {
        atomicMax(&visbuffer[y * params.width + x], visbuffer64_pack(in.position.z, in.id.x, in.id.y));
    }
    return vec4(0.0);
}
