#define_import_path meshlight::meshlet

// Meshlets as the asset format (version 7) stores them, and their decoding on the GPU.
// `Meshlet` and `MeshletGroup` are the asset's `MeshletRecord` and `GroupRecord` byte
// for byte, so the GPU scene uploads the asset's sections as they are (offsets rebased
// when several assets share the buffers); a test checks the layouts.
//
// A meshlet's payload, from word `data_offset` of the shared payload buffer:
// - vertex records of `meshlet_vertex_stride` bits each: the grid offsets x, y, z at the
//   meshlet's bits per axis, then the two octahedral normal components as offsets from
//   the meshlet's smallest ones at its normal bits;
// - triangle records of `meshlet_triangle_stride` bits each (at most 25): the largest
//   corner as a biased offset from its prediction `(t + 1) * vertices / triangles`, then
//   the two other corners, in winding order, as distances below it;
// - when the mesh has UVs (`MESH_FLAG_UVS`), the UV block: the meshlet's origin on the
//   mesh's UV grid (`MESHLET_UV_ORIGIN_WORDS` words, a code and a shift per component),
//   then each vertex's offsets from it, u then v, at `meshlet_uv_bits` (at most 16
//   each);
// - when the mesh has vertex colours (`MESH_FLAG_COLORS`), a word per vertex: sRGB red,
//   green, blue and linear alpha at 8 bits each (`meshlight::texture`'s
//   `vertex_color`). The rasterisers read UVs and colours only for MASK materials, so
//   they come last.
// Every field is found by multiplying, so a thread per vertex or per triangle decodes
// its own record with no serial state. Read a field with `read_bits` from the two words
// at its location, a vertex's grid offsets from the four at its record; the GPU scene
// pads the payload with four words so those always exist.
// `meshlight_scene::asset::MeshletAsset::decode_meshlet` is the CPU reference.

#import meshlight::math::{read_bits, F32_MAX}
#import meshlight::view::{View, project_error_to_pixels}

// Triangles per meshlet at most; the visibility buffer gives the triangle index 7 bits.
const MESHLET_MAX_TRIANGLES: u32 = 128u;
// Vertices per meshlet at most, so a local index fits a byte.
const MESHLET_MAX_VERTICES: u32 = 255u;
// `source_group` of a LOD-0 meshlet and `parent_group` of a root.
const MESHLET_NO_GROUP: u32 = 0xffffffffu;
// Bits per octahedral normal component before the per-meshlet offsets.
const MESHLET_NORMAL_BITS: u32 = 10u;
// Added to a signed octahedral component to store its minimum unsigned.
const MESHLET_NORMAL_BIAS: i32 = 512;
// `Mesh::flags`: each meshlet's payload holds UVs after its triangle records.
const MESH_FLAG_UVS: u32 = 1u;
// `Mesh::flags`: each meshlet's payload ends with a colour word per vertex.
const MESH_FLAG_COLORS: u32 = 2u;
// Words of a meshlet's UV origin, before its vertices' UV offsets.
const MESHLET_UV_ORIGIN_WORDS: u32 = 2u;

// 52 bytes; the asset's `MeshletRecord`.
struct Meshlet {
    // Culling sphere around the decoded vertices, mesh space: centre xyz, radius.
    bounds: array<f32, 4>,
    // The group whose simplification produced this meshlet (its LOD sphere and error
    // are this meshlet's own), or MESHLET_NO_GROUP at LOD 0 (error 0, sphere `bounds`).
    source_group: u32,
    // The group this meshlet was simplified in (its parent's sphere and error), or
    // MESHLET_NO_GROUP for a root (an infinite parent error).
    parent_group: u32,
    // First payload word of this meshlet, in the shared payload buffer.
    data_offset: u32,
    // Vertex count (bits 0..8), triangle count (8..16), LOD level (16..24), material
    // slot (24..32), which the instance's `material` is the base of.
    counts: u32,
    // Smallest grid coordinate of the meshlet's vertices; vertices store offsets from it.
    grid_min: array<u32, 3>,
    // Bits per axis x (0..5), y (5..10), z (10..15); UV offset bits less one, u
    // (15..19), v (19..23); triangle record fields: corner offset (24..28), corner
    // distances (28..32).
    bits: u32,
    // Smallest octahedral components plus MESHLET_NORMAL_BIAS: x (0..12), y (12..24);
    // bits of each component's offset: x (24..28), y (28..32).
    normals: u32,
}

// 32 bytes; the asset's `GroupRecord`. Meshlets refer to groups for their LOD spheres
// and errors, which all meshlets of a group share so that they switch together.
struct MeshletGroup {
    // Mesh space: centre xyz, radius; encloses the spheres of the group's children.
    lod_sphere: vec4<f32>,
    // Simplification error in mesh units, at least that of every child.
    error: f32,
    level: u32,
    first_child: u32,
    child_count: u32,
}

// One loaded mesh asset in the GPU scene. Layout matches `cpu::layout::Mesh`.
struct Mesh {
    // Position grid: position = xyz + w * (grid_min + offset).
    position_grid: vec4<f32>,
    // UV rectangle: uv = xy + zw * (the two 16-bit values).
    uv_grid: vec4<f32>,
    // Mesh-space sphere around the whole mesh (centre xyz, radius), to cull instances.
    bounding_sphere: vec4<f32>,
    // The mesh's meshlets are [first_meshlet, first_meshlet + meshlet_count).
    first_meshlet: u32,
    meshlet_count: u32,
    // MESH_FLAG_UVS or 0.
    flags: u32,
    // LOD levels of the mesh's DAG.
    level_count: u32,
}

// One entry of a cluster list: which instance draws which meshlet.
struct Cluster {
    // Index into the instance array.
    instance: u32,
    // Index into the shared meshlet array.
    meshlet: u32,
}

fn meshlet_vertex_count(m: Meshlet) -> u32 {
    return extractBits(m.counts, 0u, 8u);
}

fn meshlet_triangle_count(m: Meshlet) -> u32 {
    return extractBits(m.counts, 8u, 8u);
}

fn meshlet_level(m: Meshlet) -> u32 {
    return extractBits(m.counts, 16u, 8u);
}

// The meshlet's material slot: its triangles take material `instance.material + slot`.
fn meshlet_material(m: Meshlet) -> u32 {
    return m.counts >> 24u;
}

fn meshlet_bounds(m: Meshlet) -> vec4<f32> {
    return vec4(m.bounds[0], m.bounds[1], m.bounds[2], m.bounds[3]);
}

// Bits per axis of the grid offsets (x, y, z).
fn meshlet_axis_bits(m: Meshlet) -> vec3<u32> {
    return vec3(extractBits(m.bits, 0u, 5u), extractBits(m.bits, 5u, 5u), extractBits(m.bits, 10u, 5u));
}

// Bits of each vertex's UV offsets (u, v); meaningful only when the mesh has UVs.
fn meshlet_uv_bits(m: Meshlet) -> vec2<u32> {
    return vec2(extractBits(m.bits, 15u, 4u), extractBits(m.bits, 19u, 4u)) + 1u;
}

// Bits of the two octahedral offsets.
fn meshlet_normal_bits(m: Meshlet) -> vec2<u32> {
    return vec2(extractBits(m.normals, 24u, 4u), extractBits(m.normals, 28u, 4u));
}

fn meshlet_vertex_stride(m: Meshlet) -> u32 {
    let a = meshlet_axis_bits(m);
    let n = meshlet_normal_bits(m);
    return a.x + a.y + a.z + n.x + n.y;
}

// Bits of the triangle records' fields: x = corner offset, y = each corner distance.
fn meshlet_triangle_field_bits(m: Meshlet) -> vec2<u32> {
    return vec2(extractBits(m.bits, 24u, 4u), extractBits(m.bits, 28u, 4u));
}

fn meshlet_triangle_stride(m: Meshlet) -> u32 {
    let t = meshlet_triangle_field_bits(m);
    return t.x + 2u * t.y;
}

// First payload word of the triangle records.
fn meshlet_triangle_word(m: Meshlet) -> u32 {
    return m.data_offset + (meshlet_vertex_count(m) * meshlet_vertex_stride(m) + 31u) / 32u;
}

// First payload word of the UV block, the meshlet's UV origin (meaningful only when the
// mesh has UVs).
fn meshlet_uv_word(m: Meshlet) -> u32 {
    return meshlet_triangle_word(m) + (meshlet_triangle_count(m) * meshlet_triangle_stride(m) + 31u) / 32u;
}

// First payload word of the colour words, one per vertex (meaningful only when the mesh
// has vertex colours): after the UV block where the mesh has UVs.
fn meshlet_color_word(m: Meshlet, mesh_flags: u32) -> u32 {
    var word = meshlet_uv_word(m);
    if (mesh_flags & MESH_FLAG_UVS) != 0u {
        let b = meshlet_uv_bits(m);
        word += MESHLET_UV_ORIGIN_WORDS + (meshlet_vertex_count(m) * (b.x + b.y) + 31u) / 32u;
    }
    return word;
}

// Where vertex `vertex`'s UV offsets lie: x = payload word, y = bit in it. Both offsets
// (at most 32 bits together) lie in the words x and x + 1.
fn meshlet_uv_location(m: Meshlet, vertex: u32) -> vec2<u32> {
    let b = meshlet_uv_bits(m);
    let bit = vertex * (b.x + b.y);
    return vec2(meshlet_uv_word(m) + MESHLET_UV_ORIGIN_WORDS + bit / 32u, bit % 32u);
}

// Where field `field` of vertex `vertex` lies: x = payload word, y = bit in it, z = bit
// count. Fields: 0, 1, 2 = grid offsets x, y, z; 3, 4 = octahedral offsets x, y. Read
// words x and x + 1 and pass them, with y and z, to `read_bits`.
//
// The fields' widths and the bits before each are chosen with selects, not read from a
// local array in a loop: a driver may keep such an array in memory, and this runs for
// every corner the rasterisers and the resolve decode (as an indexed array it cost an
// H200 a quarter of the 3840×2160 resolve).
fn meshlet_vertex_field(m: Meshlet, vertex: u32, field: u32) -> vec3<u32> {
    let a = meshlet_axis_bits(m);
    let n = meshlet_normal_bits(m);
    let before = select(0u, a.x, field > 0u) + select(0u, a.y, field > 1u)
        + select(0u, a.z, field > 2u) + select(0u, n.x, field > 3u);
    let width = select(select(select(select(n.y, n.x, field == 3u), a.z, field == 2u), a.y, field == 1u), a.x, field == 0u);
    let bit = vertex * meshlet_vertex_stride(m) + before;
    return vec3(m.data_offset + bit / 32u, bit % 32u, width);
}

// Where vertex `vertex`'s record starts: x = payload word, y = bit in it. Its grid
// offsets (fields 0, 1, 2: at most 93 bits) lie in words x to x + 3: read the four and
// pass them, with y, to `meshlet_grid_offsets`. One window of loads for the three
// fields, where `meshlet_vertex_field` reads two words per field.
fn meshlet_vertex_location(m: Meshlet, vertex: u32) -> vec2<u32> {
    let bit = vertex * meshlet_vertex_stride(m);
    return vec2(m.data_offset + bit / 32u, bit % 32u);
}

// The grid offsets (x, y, z) of a vertex whose record starts at bit `bit` (0..31) of
// `words`, four payload words from `meshlet_vertex_location`. Each field is read from
// the pair of words holding it, picked by selects (no indexed array: see
// `meshlet_vertex_field`).
fn meshlet_grid_offsets(m: Meshlet, words: vec4<u32>, bit: u32) -> vec3<u32> {
    let a = meshlet_axis_bits(m);
    // Field y starts below bit 63 of the window, field z below bit 94.
    let y = bit + a.x;
    let z = y + a.y;
    return vec3(
        read_bits(words.xy, bit, a.x),
        read_bits(select(words.xy, words.yz, y >= 32u), y % 32u, a.y),
        read_bits(select(select(words.xy, words.yz, z >= 32u), words.zw, z >= 64u), z % 32u, a.z),
    );
}

// Where vertex `vertex`'s two octahedral offsets lie: x = payload word, y = bit in it,
// z = their bits together (at most 30, so words x and x + 1 hold both). Read the two
// words and pass them to `meshlet_normal_offsets`.
fn meshlet_normal_location(m: Meshlet, vertex: u32) -> vec3<u32> {
    let a = meshlet_axis_bits(m);
    let n = meshlet_normal_bits(m);
    let bit = vertex * meshlet_vertex_stride(m) + a.x + a.y + a.z;
    return vec3(m.data_offset + bit / 32u, bit % 32u, n.x + n.y);
}

// The two octahedral offsets from the words and location `meshlet_normal_location` gave.
fn meshlet_normal_offsets(m: Meshlet, words: vec2<u32>, at: vec3<u32>) -> vec2<u32> {
    let both = read_bits(words, at.y, at.z);
    let n = meshlet_normal_bits(m);
    return vec2(extractBits(both, 0u, n.x), extractBits(both, n.x, n.y));
}

// Mesh-space position from the three grid offsets. The integer add comes first, so a
// vertex shared by neighbouring meshlets decodes to identical bits in each: no cracks.
fn meshlet_position(m: Meshlet, position_grid: vec4<f32>, offset: vec3<u32>) -> vec3<f32> {
    let q = vec3(m.grid_min[0], m.grid_min[1], m.grid_min[2]) + offset;
    return position_grid.xyz + vec3<f32>(q) * position_grid.w;
}

// Mesh-space unit normal from the two octahedral offsets.
fn meshlet_normal(m: Meshlet, offset: vec2<u32>) -> vec3<f32> {
    let base = vec2(
        i32(extractBits(m.normals, 0u, 12u)) - MESHLET_NORMAL_BIAS,
        i32(extractBits(m.normals, 12u, 12u)) - MESHLET_NORMAL_BIAS,
    );
    let max_value = f32((1 << (MESHLET_NORMAL_BITS - 1u)) - 1);
    let e = clamp(vec2<f32>(base + vec2<i32>(offset)) / max_value, vec2(-1.0), vec2(1.0));
    var n = vec3(e, 1.0 - abs(e.x) - abs(e.y));
    let t = max(-n.z, 0.0);
    n.x += select(t, -t, n.x >= 0.0);
    n.y += select(t, -t, n.y >= 0.0);
    return normalize(n);
}

// Texture coordinates from the meshlet's UV `origin` (the two words at
// `meshlet_uv_word(m)`: a code in the low 24 bits, a shift in the high 8) and the two
// words at a vertex's `meshlet_uv_location` (`words`, its offsets from bit `bit` on, in
// units of 2^shift codes). Codes stay below 2^24, so their f32 is exact
// (`meshlight_scene::compress::UvQuantization`).
fn meshlet_uv(m: Meshlet, uv_grid: vec4<f32>, origin: vec2<u32>, words: vec2<u32>, bit: u32) -> vec2<f32> {
    let b = meshlet_uv_bits(m);
    // Both offsets (at most 32 bits) in one word, then split: the 32 bits from `bit` on.
    let field = (words.x >> bit) | select(words.y << (32u - bit), 0u, bit == 0u);
    let offset = vec2(extractBits(field, 0u, b.x), extractBits(field, b.x, b.y)) << (origin >> vec2(24u));
    let code = (origin & vec2(0xffffffu)) + offset;
    return uv_grid.xy + vec2<f32>(code) * uv_grid.zw;
}

// Where triangle `triangle`'s record begins: x = payload word, y = bit in it. A record
// fits in the two words x and x + 1.
fn meshlet_triangle_location(m: Meshlet, triangle: u32) -> vec2<u32> {
    let bit = triangle * meshlet_triangle_stride(m);
    return vec2(meshlet_triangle_word(m) + bit / 32u, bit % 32u);
}

// The three local vertex indices of triangle `triangle`, in winding order, from the two
// words at its location. Corners are clamped into the meshlet, as the CPU decoder
// clamps them, so no record, however damaged, reads another meshlet's vertices.
fn meshlet_triangle(m: Meshlet, triangle: u32, words: vec2<u32>, bit: u32) -> vec3<u32> {
    let widths = meshlet_triangle_field_bits(m);
    let record = read_bits(words, bit, widths.x + 2u * widths.y);
    let vertices = meshlet_vertex_count(m);
    let triangles = max(meshlet_triangle_count(m), 1u);
    let predicted = i32(((triangle + 1u) * vertices) / triangles);
    let bias = 1 << (max(widths.x, 1u) - 1u);
    let first = predicted + i32(extractBits(record, 0u, widths.x)) - bias;
    let d1 = i32(extractBits(record, widths.x, widths.y));
    let d2 = i32(extractBits(record, widths.x + widths.y, widths.y));
    let last = i32(max(vertices, 1u)) - 1;
    return vec3<u32>(clamp(vec3(first, first - d1, first - d2), vec3(0), vec3(last)));
}

// Whether an error of `pixels` is seen at `threshold_pixels`: the comparison of the LOD
// cut, which the hierarchy walk's bounds on it make too.
fn error_perceptible(pixels: f32, threshold_pixels: f32) -> bool {
    return pixels > threshold_pixels;
}

// The LOD cut: draw a meshlet when its own error is imperceptible and its parent's is
// not. Spheres (centre xyz, radius w) and errors are mesh space; `world_from_mesh` and
// its largest axis scale `scale` bring them to world space. Because errors and spheres
// grow monotonically up the DAG, exactly one level of each region passes.
fn lod_cut(
    view: View,
    world_from_mesh: mat4x4<f32>,
    scale: f32,
    own_sphere: vec4<f32>,
    own_error: f32,
    parent_sphere: vec4<f32>,
    parent_error: f32,
    threshold_pixels: f32,
) -> bool {
    let own_center = (world_from_mesh * vec4(own_sphere.xyz, 1.0)).xyz;
    let own = project_error_to_pixels(view, own_center, own_sphere.w * scale, own_error * scale);
    if error_perceptible(own, threshold_pixels) {
        return false;
    }
    // A root has no parent: it is drawn whenever its own error passes.
    if parent_error >= F32_MAX {
        return true;
    }
    let parent_center = (world_from_mesh * vec4(parent_sphere.xyz, 1.0)).xyz;
    let parent = project_error_to_pixels(
        view, parent_center, parent_sphere.w * scale, parent_error * scale);
    return error_perceptible(parent, threshold_pixels);
}
