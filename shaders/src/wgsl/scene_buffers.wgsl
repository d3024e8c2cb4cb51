#define_import_path meshlight::scene_buffers

// The GPU scene's read-only buffers, declared once for every pass that reads them. A
// shader imports the ones it uses; each binds the slot of its name (the contract's
// `meshlight_gpu_scene::scene_reads`), so the numbers below only have to stay clear of
// the importer's own: bindings 24 to 29 are these, as 30 and 31 are
// meshlight::instance_table's.

#import meshlight::meshlet::{Mesh, Meshlet, MeshletGroup, meshlet_vertex_location, meshlet_grid_offsets}
#import meshlight::instance::Material

@group(0) @binding(25) var<storage, read> meshes: array<Mesh>;
@group(0) @binding(26) var<storage, read> meshlets: array<Meshlet>;
// The simplification groups, for each meshlet's LOD errors.
@group(0) @binding(27) var<storage, read> meshlet_groups: array<MeshletGroup>;
// The meshlets' packed vertices and triangles (`meshlet_vertex_field` and friends).
@group(0) @binding(28) var<storage, read> payload: array<u32>;
@group(0) @binding(29) var<storage, read> materials: array<Material>;
// Every texture's mip chain, one RGBA8 texel a word (`cpu::layout::TextureRef` says
// where a texture lies; resolve::texture samples them).
@group(0) @binding(24) var<storage, read> textures: array<u32>;

// The grid offsets of vertex `vertex` of meshlet `m`, read from the payload through one
// window of four words (`meshlet_grid_offsets`; the GPU scene pads the payload so the
// window never leaves it).
fn payload_grid_offsets(m: Meshlet, vertex: u32) -> vec3<u32> {
    let at = meshlet_vertex_location(m, vertex);
    let words = vec4(payload[at.x], payload[at.x + 1u], payload[at.x + 2u], payload[at.x + 3u]);
    return meshlet_grid_offsets(m, words, at.y);
}
