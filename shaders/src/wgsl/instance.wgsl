#define_import_path meshlight::instance

// One placed copy of a mesh. Layout matches `cpu::layout::Instance`.

struct Instance {
    // Mesh space to world space.
    world_from_local: mat4x4<f32>,
    // Last frame's world_from_local, for motion vectors and last frame's occlusion test.
    previous_world_from_local: mat4x4<f32>,
    // World space to mesh space; its transposed upper 3x3 transforms normals.
    local_from_world: mat4x4<f32>,
    // The mesh's quantisation grid: xyz origin, w step (mesh units per grid step).
    position_grid: vec4<f32>,
    // Index into the material table.
    material: u32,
    // The mesh's first meshlet in the shared meshlet array.
    first_meshlet: u32,
    // How many meshlets the mesh has (all LOD levels).
    meshlet_count: u32,
    // Index into the mesh table (`meshlight::meshlet::Mesh`).
    mesh: u32,
}

// One entry of the material table. Layout matches `cpu::layout::Material`.
struct Material {
    // Linear RGB albedo; alpha factor in w.
    base_color: vec4<f32>,
    // Linear RGB emitted light; the normal map's scale in w.
    emissive: vec4<f32>,
    // 0 dielectric, 1 metal.
    metallic: f32,
    // Perceptual roughness, 0 to 1 (GGX alpha = roughness²).
    roughness: f32,
    // How much of the occlusion map applies, 0 to 1.
    occlusion_strength: f32,
    // MASK materials: texels whose alpha is below this are cut out (0 for opaque).
    alpha_cutoff: f32,
    // MATERIAL_FLAG_CHECKER | MATERIAL_FLAG_DOUBLE_SIDED | MATERIAL_FLAG_MASK, or 0.
    flags: u32,
    // The word of the `textures` buffer where the texture transform the maps are
    // sampled through lies (six f32: rows (a, b, c), (d, e, f)), 0 for none.
    uv_transform: u32,
    // The textures, by MAP_* index: (first texel word, shape), shape 0 for none
    // (`cpu::layout::TextureRef`).
    maps: array<vec2<u32>, 5>,
}

// `uv` through a texture transform of rows `r0` and `r1` (glTF's KHR_texture_transform):
// coordinate k is dot(row k, vec3(uv, 1)).
fn material_uv(r0: vec3<f32>, r1: vec3<f32>, uv: vec2<f32>) -> vec2<f32> {
    let h = vec3(uv, 1.0);
    return vec2(dot(r0, h), dot(r1, h));
}

// A change `d` of uv through the transform's linear part (how UV derivatives transform).
fn material_uv_step(r0: vec3<f32>, r1: vec3<f32>, d: vec2<f32>) -> vec2<f32> {
    return vec2(dot(r0.xy, d), dot(r1.xy, d));
}

// `Material::flags`: the base colour is modulated by a checkerboard over the UVs.
const MATERIAL_FLAG_CHECKER: u32 = 1u;
// `Material::flags`: back faces are drawn too, and shaded with the normal reversed.
const MATERIAL_FLAG_DOUBLE_SIDED: u32 = 2u;
// `Material::flags`: alphaMode MASK; texels whose alpha is below `alpha_cutoff` are not
// drawn (meshlight::surface's `cut_out`, which both rasterisers ask).
const MATERIAL_FLAG_MASK: u32 = 4u;

// `Material::maps` indices.
const MAP_BASE_COLOR: u32 = 0u;
const MAP_METALLIC_ROUGHNESS: u32 = 1u;
const MAP_NORMAL: u32 = 2u;
const MAP_OCCLUSION: u32 = 3u;
const MAP_EMISSIVE: u32 = 4u;

fn instance_transform_point(instance: Instance, p: vec3<f32>) -> vec3<f32> {
    return (instance.world_from_local * vec4(p, 1.0)).xyz;
}

fn instance_previous_transform_point(instance: Instance, p: vec3<f32>) -> vec3<f32> {
    return (instance.previous_world_from_local * vec4(p, 1.0)).xyz;
}

// World-space normal; uses the inverse so non-uniform scale keeps normals perpendicular.
fn instance_transform_normal(instance: Instance, n: vec3<f32>) -> vec3<f32> {
    let m = instance.local_from_world;
    let inverse_transpose = transpose(mat3x3(m[0].xyz, m[1].xyz, m[2].xyz));
    return normalize(inverse_transpose * n);
}

// The largest axis scale: a mesh-space radius or error times this bounds it in world space.
fn instance_max_scale(instance: Instance) -> f32 {
    let m = instance.world_from_local;
    let s = vec3(dot(m[0].xyz, m[0].xyz), dot(m[1].xyz, m[1].xyz), dot(m[2].xyz, m[2].xyz));
    return sqrt(max(s.x, max(s.y, s.z)));
}

// A mesh-space sphere (xyz centre, w radius) in world space, radius scaled conservatively.
fn instance_transform_sphere(instance: Instance, sphere: vec4<f32>) -> vec4<f32> {
    return vec4(instance_transform_point(instance, sphere.xyz), sphere.w * instance_max_scale(instance));
}
