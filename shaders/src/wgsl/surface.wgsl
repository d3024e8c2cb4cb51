#define_import_path meshlight::surface

// Where a pixel lies on its triangle and what its material reads there: perspective-
// correct barycentrics and their change per pixel step (from the three clip-space
// corners, as visibility-buffer renderers reconstruct them), the coordinates
// the material's maps are sampled at, and the alpha a MASK material is cut by. The
// resolve shades through these functions and both rasterisers ask `cut_out` which
// pixels of a MASK material to leave undrawn, so the three agree on every pixel.
// `meshlight_gpu_scene::surface` mirrors each step on the CPU.

#import meshlight::meshlet::{Meshlet, Mesh, Cluster, MESH_FLAG_UVS, MESH_FLAG_COLORS, meshlet_material, meshlet_normal_location, meshlet_normal_offsets, meshlet_normal, meshlet_position, meshlet_uv_word, meshlet_uv, meshlet_uv_location, meshlet_color_word}
#import meshlight::instance::{MATERIAL_FLAG_MASK, MAP_BASE_COLOR, material_uv, material_uv_step}
#import meshlight::cluster_triangle::{cluster_triangle, ClusterTriangle}
#import meshlight::scene_buffers::{payload, materials, textures, payload_grid_offsets}
#import meshlight::texture::{texture_present, sample_alpha, vertex_color}

// Perspective-correct barycentrics at a pixel and their derivatives per pixel step in
// x and y.
struct Barycentrics {
    b: vec3<f32>,
    ddx: vec3<f32>,
    ddy: vec3<f32>,
}

// What the barycentrics of a triangle take from its clip-space corners, whatever the
// pixel: a rasteriser sets it up once per triangle and evaluates it per pixel.
struct BarycentricSetup {
    // 1 / w of each corner.
    iw: vec3<f32>,
    // The first corner in NDC, and the other two relative to it.
    origin: vec2<f32>,
    side_a: vec2<f32>,
    side_b: vec2<f32>,
    // 1 / the NDC triangle's doubled area, 0 for a degenerate triangle.
    inv_det: f32,
}

fn barycentric_setup(c0: vec4<f32>, c1: vec4<f32>, c2: vec4<f32>) -> BarycentricSetup {
    var out: BarycentricSetup;
    out.iw = vec3(1.0 / c0.w, 1.0 / c1.w, 1.0 / c2.w);
    out.origin = c0.xy * out.iw.x;
    out.side_a = c1.xy * out.iw.y - out.origin;
    out.side_b = c2.xy * out.iw.z - out.origin;
    let det = out.side_a.x * out.side_b.y - out.side_a.y * out.side_b.x;
    out.inv_det = select(1.0 / det, 0.0, abs(det) < 1e-30);
    return out;
}

// The barycentrics at `pixel` (centres at +0.5) of a `size` pixel viewport.
fn barycentrics_at(t: BarycentricSetup, pixel: vec2<f32>, size: vec2<f32>) -> Barycentrics {
    var out: Barycentrics;
    if t.inv_det == 0.0 {
        out.b = vec3(1.0, 0.0, 0.0);
        return out;
    }
    // NDC of the pixel centre, and NDC per pixel step (y goes down the screen).
    let p = vec2(pixel.x * 2.0 / size.x - 1.0, 1.0 - pixel.y * 2.0 / size.y);
    let step = vec2(2.0 / size.x, -2.0 / size.y);
    let dp = p - t.origin;
    let d1 = t.side_a;
    let d2 = t.side_b;
    let inv_det = t.inv_det;
    // Screen-linear barycentrics and their NDC gradients.
    let l1 = (dp.x * d2.y - dp.y * d2.x) * inv_det;
    let l2 = (d1.x * dp.y - d1.y * dp.x) * inv_det;
    let l = vec3(1.0 - l1 - l2, l1, l2);
    let gx = vec3(d1.y - d2.y, d2.y, -d1.y) * inv_det * step.x;
    let gy = vec3(d2.x - d1.x, -d2.x, d1.x) * inv_det * step.y;
    // Perspective correction: b = l·iw / Σ l·iw, differentiated by the quotient rule.
    let iw = t.iw;
    let q = l * iw;
    let s = 1.0 / (q.x + q.y + q.z);
    out.b = q * s;
    let sx = dot(gx, iw);
    let sy = dot(gy, iw);
    out.ddx = (gx * iw - out.b * sx) * s;
    out.ddy = (gy * iw - out.b * sy) * s;
    return out;
}

// The barycentrics at `pixel` (centres at +0.5) of a `size` pixel viewport, from the
// clip-space corners.
fn barycentrics(c0: vec4<f32>, c1: vec4<f32>, c2: vec4<f32>, pixel: vec2<f32>, size: vec2<f32>) -> Barycentrics {
    return barycentrics_at(barycentric_setup(c0, c1, c2), pixel, size);
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

// The rows of the texture transform at word `w` of `textures` (`Material::uv_transform`,
// six words); only for a word that is not 0.
fn uv_transform_rows(w: u32) -> array<vec3<f32>, 2> {
    return array(
        vec3(bitcast<f32>(textures[w]), bitcast<f32>(textures[w + 1u]), bitcast<f32>(textures[w + 2u])),
        vec3(bitcast<f32>(textures[w + 3u]), bitcast<f32>(textures[w + 4u]), bitcast<f32>(textures[w + 5u])),
    );
}

// `s` through the texture transform of rows `r`.
fn transformed_uv(r: array<vec3<f32>, 2>, s: SampleUv) -> SampleUv {
    return SampleUv(material_uv(r[0], r[1], s.uv), material_uv_step(r[0], r[1], s.dx), material_uv_step(r[0], r[1], s.dy));
}

// The base colour's alpha at `s`: the factor's, times the texture's where `map` is one.
fn base_alpha(map: vec2<u32>, factor: f32, s: SampleUv) -> f32 {
    if !texture_present(map) {
        return factor;
    }
    return factor * sample_alpha(map, s.uv, s.dx, s.dy);
}

// Mesh-space position of vertex `v` of meshlet `m` of `mesh`.
fn corner_position(m: Meshlet, mesh: Mesh, v: u32) -> vec3<f32> {
    return meshlet_position(m, mesh.position_grid, payload_grid_offsets(m, v));
}

// Mesh-space unit normal of vertex `v` of meshlet `m`.
fn corner_normal(m: Meshlet, v: u32) -> vec3<f32> {
    let at = meshlet_normal_location(m, v);
    return meshlet_normal(m, meshlet_normal_offsets(m, vec2(payload[at.x], payload[at.x + 1u]), at));
}

// Texture coordinates of vertex `v` of meshlet `m` of `mesh`, 0 where the mesh has none.
// The rasterisers' cut-out test and the resolve both read UVs through this.
fn corner_uv(m: Meshlet, mesh: Mesh, v: u32) -> vec2<f32> {
    if (mesh.flags & MESH_FLAG_UVS) == 0u {
        return vec2(0.0);
    }
    let block = meshlet_uv_word(m);
    let at = meshlet_uv_location(m, v);
    return meshlet_uv(m, mesh.uv_grid, vec2(payload[block], payload[block + 1u]), vec2(payload[at.x], payload[at.x + 1u]), at.y);
}

// What deciding a MASK triangle's pixels takes, whatever the pixel (`cut_out_setup`).
struct CutOut {
    // The triangle's material is MASK: without it no pixel is cut.
    masked: bool,
    bary: BarycentricSetup,
    uv: array<vec2<f32>, 3>,
    // The material's base colour map, alpha factor, cutoff and texture transform word.
    map: vec2<u32>,
    alpha: f32,
    cutoff: f32,
    uv_transform: u32,
    // The mesh has vertex colours, whose alphas multiply the material's.
    has_colors: bool,
    vertex_alpha: vec3<f32>,
}

// What the cut-out test takes from one corner: its clip-space position, texture
// coordinates (0 without UVs) and vertex alpha (1 without colours).
struct CutCorner {
    clip: vec4<f32>,
    uv: vec2<f32>,
    alpha: f32,
}

// Corner `v` of `tri`, as the resolve decodes it. Called once per corner rather than
// from a loop filling arrays, which a driver may keep in memory (as the resolve's
// `corner_attributes`).
fn cut_corner(tri: ClusterTriangle, v: u32, view_projection: mat4x4<f32>, has_colors: bool) -> CutCorner {
    var c = CutCorner(vec4(0.0), vec2(0.0), 1.0);
    let world = (tri.instance.world_from_local * vec4(corner_position(tri.m, tri.mesh, v), 1.0)).xyz;
    c.clip = view_projection * vec4(world, 1.0);
    c.uv = corner_uv(tri.m, tri.mesh, v);
    if has_colors {
        c.alpha = vertex_color(payload[meshlet_color_word(tri.m, tri.mesh.flags) + v]).a;
    }
    return c;
}

// Triangle `t` of `cluster` set up for `cut_at`. The corners are transformed as the
// resolve transforms them (`world_from_local`, then `view_projection`), so the
// rasterisers test the alpha the resolve would read. The material is read first: a
// triangle of another material costs one lookup.
fn cut_out_setup(cluster: Cluster, t: u32, view_projection: mat4x4<f32>) -> CutOut {
    var out: CutOut;
    let tri = cluster_triangle(cluster, t);
    let material = materials[tri.instance.material + meshlet_material(tri.m)];
    out.masked = (material.flags & MATERIAL_FLAG_MASK) != 0u;
    if !out.masked {
        return out;
    }
    out.map = material.maps[MAP_BASE_COLOR];
    out.alpha = material.base_color.a;
    out.cutoff = material.alpha_cutoff;
    out.uv_transform = material.uv_transform;
    out.has_colors = (tri.mesh.flags & MESH_FLAG_COLORS) != 0u;
    let c0 = cut_corner(tri, tri.corners.x, view_projection, out.has_colors);
    let c1 = cut_corner(tri, tri.corners.y, view_projection, out.has_colors);
    let c2 = cut_corner(tri, tri.corners.z, view_projection, out.has_colors);
    out.uv = array(c0.uv, c1.uv, c2.uv);
    out.vertex_alpha = vec3(c0.alpha, c1.alpha, c2.alpha);
    out.bary = barycentric_setup(c0.clip, c1.clip, c2.clip);
    return out;
}

// Whether the pixel centred at `pixel` of a `size` pixel viewport is cut out of the
// triangle `c` describes: its material is MASK and the base colour's alpha there is
// below the cutoff.
fn cut_at(c: CutOut, pixel: vec2<f32>, size: vec2<f32>) -> bool {
    if !c.masked {
        return false;
    }
    // The coordinates the resolve samples the maps at: interpolated, then through the
    // material's texture transform where it has one.
    let b = barycentrics_at(c.bary, pixel, size);
    var s = interpolated_uv(c.uv, b);
    if c.uv_transform != 0u {
        s = transformed_uv(uv_transform_rows(c.uv_transform), s);
    }
    var alpha = base_alpha(c.map, c.alpha, s);
    if c.has_colors {
        alpha *= c.vertex_alpha.x * b.b.x + c.vertex_alpha.y * b.b.y + c.vertex_alpha.z * b.b.z;
    }
    return alpha < c.cutoff;
}

// Whether the pixel centred at `pixel` of triangle `t` of `cluster` is cut out
// (`cut_at` of `cut_out_setup`): for a caller that tests one pixel of a triangle.
fn cut_out(cluster: Cluster, t: u32, pixel: vec2<f32>, size: vec2<f32>, view_projection: mat4x4<f32>) -> bool {
    return cut_at(cut_out_setup(cluster, t, view_projection), pixel, size);
}
