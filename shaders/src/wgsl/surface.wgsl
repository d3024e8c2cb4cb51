#define_import_path meshlight::surface

// Where a pixel lies on its triangle and what its material reads there: perspective-
// correct barycentrics and their change per pixel step (from the three clip-space
// corners, as the anchors reconstruct them from a visibility buffer), the coordinates
// the material's maps are sampled at, and the alpha a MASK material is cut by. The
// resolve shades through these functions and both rasterisers ask `cut_out` which
// pixels of a MASK material to leave undrawn, so the three agree on every pixel.
// `meshlight_gpu_scene::surface` mirrors each step on the CPU.

#import meshlight::math::read_bits
#import meshlight::meshlet::{Meshlet, Mesh, Cluster, MESH_FLAG_UVS, meshlet_material, meshlet_vertex_field, meshlet_position, meshlet_uv_word, meshlet_uv}
#import meshlight::instance::{Material, MATERIAL_FLAG_MASK, MAP_BASE_COLOR, material_uv, material_uv_step}
#import meshlight::cluster_triangle::cluster_triangle
#import meshlight::scene_buffers::{payload, materials, textures}
#import meshlight::texture::{texture_present, sample_texture}

// Perspective-correct barycentrics at a pixel and their derivatives per pixel step in
// x and y.
struct Barycentrics {
    b: vec3<f32>,
    ddx: vec3<f32>,
    ddy: vec3<f32>,
}

// The barycentrics at `pixel` (centres at +0.5) of a `size` pixel viewport, from the
// clip-space corners.
fn barycentrics(c0: vec4<f32>, c1: vec4<f32>, c2: vec4<f32>, pixel: vec2<f32>, size: vec2<f32>) -> Barycentrics {
    var out: Barycentrics;
    // NDC of the pixel centre, and NDC per pixel step (y goes down the screen).
    let p = vec2(pixel.x * 2.0 / size.x - 1.0, 1.0 - pixel.y * 2.0 / size.y);
    let step = vec2(2.0 / size.x, -2.0 / size.y);
    let iw = vec3(1.0 / c0.w, 1.0 / c1.w, 1.0 / c2.w);
    let n0 = c0.xy * iw.x;
    let d1 = c1.xy * iw.y - n0;
    let d2 = c2.xy * iw.z - n0;
    let dp = p - n0;
    let det = d1.x * d2.y - d1.y * d2.x;
    if abs(det) < 1e-30 {
        out.b = vec3(1.0, 0.0, 0.0);
        return out;
    }
    let inv_det = 1.0 / det;
    // Screen-linear barycentrics and their NDC gradients.
    let l1 = (dp.x * d2.y - dp.y * d2.x) * inv_det;
    let l2 = (d1.x * dp.y - d1.y * dp.x) * inv_det;
    let l = vec3(1.0 - l1 - l2, l1, l2);
    let gx = vec3(d1.y - d2.y, d2.y, -d1.y) * inv_det * step.x;
    let gy = vec3(d2.x - d1.x, -d2.x, d1.x) * inv_det * step.y;
    // Perspective correction: b = l·iw / Σ l·iw, differentiated by the quotient rule.
    let q = l * iw;
    let s = 1.0 / (q.x + q.y + q.z);
    out.b = q * s;
    let sx = dot(gx, iw);
    let sy = dot(gy, iw);
    out.ddx = (gx * iw - out.b * sx) * s;
    out.ddy = (gy * iw - out.b * sy) * s;
    return out;
}

// Texture coordinates at a pixel and their change per pixel step.
struct SampleUv {
    uv: vec2<f32>,
    dx: vec2<f32>,
    dy: vec2<f32>,
}

// The corners' coordinates `uv` interpolated at the pixel `b` describes.
fn interpolated_uv(uv: array<vec2<f32>, 3>, b: Barycentrics) -> SampleUv {
    return SampleUv(
        uv[0] * b.b.x + uv[1] * b.b.y + uv[2] * b.b.z,
        uv[0] * b.ddx.x + uv[1] * b.ddx.y + uv[2] * b.ddx.z,
        uv[0] * b.ddy.x + uv[1] * b.ddy.y + uv[2] * b.ddy.z,
    );
}

// The rows of `material`'s texture transform (`Material::uv_transform`, six words of
// `textures`); only for a material whose word is not 0.
fn uv_transform_rows(material: Material) -> array<vec3<f32>, 2> {
    let w = material.uv_transform;
    return array(
        vec3(bitcast<f32>(textures[w]), bitcast<f32>(textures[w + 1u]), bitcast<f32>(textures[w + 2u])),
        vec3(bitcast<f32>(textures[w + 3u]), bitcast<f32>(textures[w + 4u]), bitcast<f32>(textures[w + 5u])),
    );
}

// `s` through the texture transform of rows `r`.
fn transformed_uv(r: array<vec3<f32>, 2>, s: SampleUv) -> SampleUv {
    return SampleUv(material_uv(r[0], r[1], s.uv), material_uv_step(r[0], r[1], s.dx), material_uv_step(r[0], r[1], s.dy));
}

// Where `material`'s maps are sampled for corner coordinates `uv` at `b`: interpolated,
// then through the texture transform where the material has one (read only then, so
// materials without one pay nothing for it).
fn material_sample_uv(material: Material, uv: array<vec2<f32>, 3>, b: Barycentrics) -> SampleUv {
    let s = interpolated_uv(uv, b);
    if material.uv_transform == 0u {
        return s;
    }
    return transformed_uv(uv_transform_rows(material), s);
}

// The base colour's alpha at `s`: the factor's, times the texture's where there is one.
fn base_alpha(material: Material, s: SampleUv) -> f32 {
    let map = material.maps[MAP_BASE_COLOR];
    if !texture_present(map) {
        return material.base_color.a;
    }
    return material.base_color.a * sample_texture(map, s.uv, s.dx, s.dy).a;
}

fn corner_field(m: Meshlet, vertex: u32, f: u32) -> u32 {
    let at = meshlet_vertex_field(m, vertex, f);
    return read_bits(vec2(payload[at.x], payload[at.x + 1u]), at.y, at.z);
}

// Whether the pixel centred at `pixel` of triangle `t` of `cluster` is cut out: its
// material is MASK and the base colour's alpha there is below the cutoff. The corners
// are transformed as the resolve transforms them (`world_from_local`, then
// `view_projection`), so the rasterisers test the alpha the resolve would read.
fn cut_out(cluster: Cluster, t: u32, pixel: vec2<f32>, size: vec2<f32>, view_projection: mat4x4<f32>) -> bool {
    let tri = cluster_triangle(cluster, t);
    let material = materials[tri.instance.material + meshlet_material(tri.m)];
    if (material.flags & MATERIAL_FLAG_MASK) == 0u {
        return false;
    }
    let has_uvs = (tri.mesh.flags & MESH_FLAG_UVS) != 0u;
    var clip: array<vec4<f32>, 3>;
    var uv: array<vec2<f32>, 3>;
    for (var k = 0u; k < 3u; k += 1u) {
        let v = tri.corners[k];
        let m = tri.m;
        let p = meshlet_position(m, tri.mesh.position_grid, vec3(corner_field(m, v, 0u), corner_field(m, v, 1u), corner_field(m, v, 2u)));
        let world = (tri.instance.world_from_local * vec4(p, 1.0)).xyz;
        clip[k] = view_projection * vec4(world, 1.0);
        uv[k] = vec2(0.0);
        if has_uvs {
            uv[k] = meshlet_uv(tri.mesh.uv_grid, payload[meshlet_uv_word(m) + v]);
        }
    }
    let b = barycentrics(clip[0], clip[1], clip[2], pixel, size);
    return base_alpha(material, material_sample_uv(material, uv, b)) < material.alpha_cutoff;
}
