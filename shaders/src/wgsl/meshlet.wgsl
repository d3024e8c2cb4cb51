#define_import_path meshlight::meshlet

// The GPU layout of meshlets and clusters, and the decoding of their compressed data.
// Layouts match `cpu::layout::Meshlet`; a test checks every offset.
//
// Positions: every mesh is quantised on one grid (origin, step), so a vertex shared by
// neighbouring meshlets has the same integer coordinate q in each and decodes to the same
// float bits — no cracks. Each meshlet stores its minimum q and the fewest bits per axis
// that hold q - min; vertex v occupies bits [v * stride, (v + 1) * stride) of the
// meshlet's part of the u32 position stream, x then y then z, least significant bit
// first, where stride = bits.x + bits.y + bits.z.
//
// Indices: three u8 local vertex indices per triangle, packed four per u32, the first in
// the low byte; triangle t uses bytes 3t, 3t + 1, 3t + 2 of the meshlet's index words.

#import meshlight::math::{read_bits, unpack_u8}
#import meshlight::view::{View, project_error_to_pixels}

// Triangles per meshlet at most; the visibility buffer gives the triangle index 7 bits.
const MESHLET_MAX_TRIANGLES: u32 = 128u;
// Vertices per meshlet at most, so a local index fits a byte.
const MESHLET_MAX_VERTICES: u32 = 255u;

struct Meshlet {
    // Culling sphere in mesh space: xyz centre, w radius.
    bounding_sphere: vec4<f32>,
    // Sphere of the group this meshlet was simplified in (xyz centre, w radius), mesh
    // space; together with lod_error it decides whether this meshlet is detailed enough.
    lod_sphere: vec4<f32>,
    // Sphere of the group this meshlet's simplification went into; equal for all
    // meshlets of that group so they switch together.
    parent_lod_sphere: vec4<f32>,
    // Simplification error of this meshlet in mesh units (0 at full detail).
    lod_error: f32,
    // Error of the coarser meshlets replacing this one; F32_MAX for roots.
    parent_lod_error: f32,
    // First u32 of this meshlet's bit-packed positions in the position stream.
    position_offset: u32,
    // First vertex of this meshlet in the per-vertex attribute arrays (normals, uvs).
    vertex_offset: u32,
    // First u32 of this meshlet's packed u8 local indices.
    index_offset: u32,
    // Vertices in this meshlet (1..=255).
    vertex_count: u32,
    // Triangles in this meshlet (1..=128).
    triangle_count: u32,
    // Bits per axis of the quantised position deltas: x | y << 8 | z << 16, each 0..=32.
    position_bits: u32,
    // Smallest quantised grid coordinate of the meshlet's vertices, per axis.
    position_min: vec3<u32>,
    // Padding to a 16-byte multiple.
    padding: u32,
}

// One entry of the cluster list: which instance draws which meshlet.
struct Cluster {
    // Index into the instance array.
    instance: u32,
    // Index into the meshlet array (already offset by the instance's first meshlet).
    meshlet: u32,
}

fn meshlet_position_bits(meshlet: Meshlet) -> vec3<u32> {
    return vec3(
        extractBits(meshlet.position_bits, 0u, 8u),
        extractBits(meshlet.position_bits, 8u, 8u),
        extractBits(meshlet.position_bits, 16u, 8u),
    );
}

// Where axis `axis` (0 = x, 1 = y, 2 = z) of local vertex `vertex` begins: x = index of
// the first u32 in the position stream, y = bit within it. Read words x and x + 1 and
// pass them to `meshlet_read_position_axis` (`cpu::positions::pack_positions` pads each
// meshlet's part so x + 1 is always in bounds).
fn meshlet_position_location(meshlet: Meshlet, vertex: u32, axis: u32) -> vec2<u32> {
    let bits = meshlet_position_bits(meshlet);
    let stride = bits.x + bits.y + bits.z;
    let before = select(0u, bits.x, axis > 0u) + select(0u, bits.y, axis > 1u);
    let bit = vertex * stride + before;
    return vec2(meshlet.position_offset + bit / 32u, bit % 32u);
}

// The quantised delta of one axis, from the two words at its location.
fn meshlet_read_position_axis(meshlet: Meshlet, axis: u32, words: vec2<u32>, bit: u32) -> u32 {
    let count = extractBits(meshlet.position_bits, axis * 8u, 8u);
    return read_bits(words, bit, count);
}

// Mesh-space position from the per-axis deltas and the mesh grid (xyz origin, w step).
// The integer add comes first so shared vertices decode to identical bits.
fn meshlet_dequantize_position(meshlet: Meshlet, delta: vec3<u32>, grid: vec4<f32>) -> vec3<f32> {
    let q = meshlet.position_min + delta;
    return grid.xyz + vec3<f32>(q) * grid.w;
}

// Where corner `corner` (0..2) of triangle `triangle` is: x = index of the u32 in the
// index stream, y = byte within it.
fn meshlet_index_location(meshlet: Meshlet, triangle: u32, corner: u32) -> vec2<u32> {
    let byte = triangle * 3u + corner;
    return vec2(meshlet.index_offset + byte / 4u, byte % 4u);
}

// The local vertex index stored at byte `byte` of `word`.
fn meshlet_local_index(word: u32, byte: u32) -> u32 {
    return unpack_u8(word, byte);
}

// The LOD cut: draw this meshlet when its own error is imperceptible and its parent's is
// not. Spheres and errors are in mesh space; `world_from_mesh` and its largest axis
// scale `scale` bring them to world space. Because parent errors and spheres are
// monotonic along the DAG, exactly one level of each region passes.
fn meshlet_in_lod_cut(
    view: View,
    world_from_mesh: mat4x4<f32>,
    scale: f32,
    meshlet: Meshlet,
    threshold_pixels: f32,
) -> bool {
    let own_center = (world_from_mesh * vec4(meshlet.lod_sphere.xyz, 1.0)).xyz;
    let own = project_error_to_pixels(
        view, own_center, meshlet.lod_sphere.w * scale, meshlet.lod_error * scale);
    let parent_center = (world_from_mesh * vec4(meshlet.parent_lod_sphere.xyz, 1.0)).xyz;
    let parent = project_error_to_pixels(
        view, parent_center, meshlet.parent_lod_sphere.w * scale, meshlet.parent_lod_error * scale);
    return own <= threshold_pixels && parent > threshold_pixels;
}
