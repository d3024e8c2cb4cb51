// Material shading from the visibility buffer, one thread per pixel: the triangle is
// fetched again from the payload, its corners transformed again, and perspective-correct
// barycentrics and their screen-space derivatives reconstructed at the pixel centre from
// the three clip-space corners. `cpu::shade` is the reference; every step has its mirror
// there.

#import meshlight::meshlet::{Meshlet, Mesh, Cluster, MESH_FLAG_COLORS, MESHLET_NO_GROUP, meshlet_level, meshlet_material, meshlet_color_word, meshlet_bounds, error_perceptible}
#import meshlight::instance::{Instance, Material, instance_max_scale, MATERIAL_FLAG_CHECKER, MATERIAL_FLAG_DOUBLE_SIDED, MAP_BASE_COLOR, MAP_METALLIC_ROUGHNESS, MAP_NORMAL, MAP_OCCLUSION, MAP_EMISSIVE, instance_transform_normal, material_uv}
#import resolve::brdf::{Surface, surface, light_response, ambient_response}
#import meshlight::texture::{texture_present, sample_texture, texture_lod, vertex_color}
#import meshlight::surface::{barycentrics, interpolated_uv, uv_transform_rows, transformed_uv, corner_normal, corner_position, corner_uv}
#import meshlight::cluster_triangle::cluster_triangle
#import meshlight::instance_table::instance_at
#import meshlight::scene_buffers::{meshlets, payload, materials}
#import meshlight::view::{View, project_error_to_pixels}
#import meshlight::visbuffer::{visbuffer_is_empty, visbuffer_depth, visbuffer_cluster, visbuffer_triangle}
#import resolve::visibility::{raster_clusters, visibility_at}
#ifdef SHADOWS
#import resolve::shadows::{shadow_factor, cascade_index, shadows}
#endif
#ifdef CLUSTERED_LIGHTS
#import meshlight::view::{position_from_depth, view_z_from_depth, pixel_to_uv}
#import meshlight::light::{ClusterableObject, ClusterGrid, cluster_of_pixel, cluster_index, CLUSTERABLE_POINT_LIGHT, CLUSTERABLE_SPOT_LIGHT, CLUSTERABLE_TYPE_COUNT}
#endif

// What the colour target shows (`DebugView` on the Rust side).
const VIEW_SHADED: u32 = 0u;
const VIEW_CLUSTERS: u32 = 1u;
const VIEW_TRIANGLES: u32 = 2u;
const VIEW_LOD: u32 = 3u;
const VIEW_RASTER: u32 = 4u;
const VIEW_DEPTH: u32 = 5u;
const VIEW_LIGHT_COUNT: u32 = 6u;
const VIEW_PYRAMID: u32 = 7u;
const VIEW_OCCLUSION: u32 = 8u;
const VIEW_MATERIAL: u32 = 9u;
const VIEW_UV: u32 = 10u;
const VIEW_NORMAL: u32 = 11u;
const VIEW_MIP: u32 = 12u;
const VIEW_BASE_COLOR: u32 = 13u;
const VIEW_RESIDENCY: u32 = 14u;
const VIEW_SHADOW: u32 = 15u;
// The `shadow` view's colour per cascade, nearest first, and past the last
// (`shadows::CASCADE_COLORS`).
const CASCADE_COLORS: array<vec3<f32>, 4> = array(
    vec3(0.95, 0.35, 0.3),
    vec3(0.35, 0.85, 0.4),
    vec3(0.35, 0.55, 1.0),
    vec3(0.95, 0.8, 0.3),
);
const NO_CASCADE_COLOR: vec3<f32> = vec3(0.6, 0.6, 0.6);
// The light-count view's scale: this many lights in a froxel is the hottest colour.
const LIGHT_COUNT_FULL: f32 = 32.0;

const SKY_ZENITH: vec3<f32> = vec3(0.25, 0.45, 0.8);
const SKY_HORIZON: vec3<f32> = vec3(0.75, 0.85, 0.95);
const SOFTWARE_COLOR: vec3<u32> = vec3(230u, 90u, 50u);
const HARDWARE_COLOR: vec3<u32> = vec3(50u, 120u, 230u);
// The occlusion view: the pass that drew the cluster, the colour an instance wholly
// culled by occlusion tends to, and how far (`cpu::occlusion_color`).
const FIRST_PASS_COLOR: vec3<f32> = vec3(0.35, 0.85, 0.4);
const SECOND_PASS_COLOR: vec3<f32> = vec3(0.3, 0.55, 1.0);
const CULLED_COLOR: vec3<f32> = vec3(1.0, 0.2, 0.15);
const CULLED_TINT: f32 = 0.7;
// Checker squares: dark ones multiply the base colour by this.
const CHECKER_DARK: f32 = 0.55;

// The uniform block, declared once for Rust and WGSL by `ShadeParams` in lib.rs.
#import resolve::shade_params::Params

// Bindings 0 and 1: the visibility buffer and `raster_clusters` (resolve::visibility).
// Word 0: software clusters; ids below it were drawn in software.
@group(0) @binding(2) var<storage, read> raster_counts: array<u32>;
// The scene's instances, meshes, meshlets, payload and materials:
// meshlight::instance_table and meshlight::scene_buffers.
@group(0) @binding(8) var color: texture_storage_2d<rgba8unorm, write>;
@group(0) @binding(9) var<uniform> view: View;
@group(0) @binding(10) var<uniform> params: Params;

#ifdef PYRAMID
// A reverse-Z min-depth pyramid: mip L is ceil(size / 2^(L+1)), its texel (x, y) covers
// pixels [x, x + 1) · 2^(L+1) on each axis.
@group(0) @binding(16) var pyramid: texture_2d<f32>;

// The texel of mip `level` covering `pixel`, clamped to the mip's size.
fn pyramid_depth(pixel: vec2<u32>, level: u32) -> f32 {
    let mip = min(level, textureNumLevels(pyramid) - 1u);
    let last = textureDimensions(pyramid, mip) - vec2(1u);
    return textureLoad(pyramid, min(pixel >> vec2(mip + 1u), last), mip).x;
}
#endif

#ifdef SECOND_COUNTS
// The second culling pass's `raster_counts`: `[7]` its first software slot (the first
// pass's software count) and `[3]` one past its last hardware slot (`C` minus the first
// pass's hardware count), so ids in `[7], [3])` are the second pass's.
@group(0) @binding(17) var<storage, read> second_counts: array<u32>;
#endif
#ifdef OCCLUDED_PER_INSTANCE
// Per instance `i`: `[2i]` clusters of the first pass's LOD cut, `[2i + 1]` of those
// left hidden after both passes.
@group(0) @binding(18) var<storage, read> occluded_per_instance: array<u32>;
#endif

#ifdef RESIDENCY
// Per group: its error while its page is not in the streaming pool, else 0.
@group(0) @binding(19) var<storage, read> stream_errors: array<f32>;
#endif

// The `residency` view: how many levels coarser than the view wants the cluster is
// drawn, because the page of the group that made its meshlet is not in the pool. The
// missing error is projected on the meshlet's own bounds (the cull projects it on the
// group's LOD sphere, which holds them: this never overstates), and each level coarser
// about doubles it. 0 when the scene does not stream.
fn levels_missing(cluster: Cluster) -> u32 {
#ifdef RESIDENCY
    let m = meshlets[cluster.meshlet];
    let group = m.source_group;
    if group == MESHLET_NO_GROUP {
        return 0u;
    }
    let missing = stream_errors[group];
    if missing <= 0.0 {
        return 0u;
    }
    let instance = instance_at(cluster.instance);
    let scale = instance_max_scale(instance);
    let bounds = meshlet_bounds(m);
    let centre = (instance.world_from_local * vec4(bounds.xyz, 1.0)).xyz;
    let px = project_error_to_pixels(view, centre, bounds.w * scale, missing * scale);
    if !error_perceptible(px, params.lod_threshold_px) {
        return 0u;
    }
    return 1u + u32(min(floor(log2(px / params.lod_threshold_px)), 2.0));
#else
    return 0u;
#endif
}

const RESIDENCY_COLORS = array<vec3<f32>, 4>(
    vec3(0.3, 0.8, 0.35),
    vec3(0.95, 0.85, 0.2),
    vec3(1.0, 0.5, 0.1),
    vec3(0.95, 0.15, 0.1),
);

// True when the second culling pass drew the cluster in slot `id`.
fn drawn_by_second_pass(id: u32) -> bool {
#ifdef SECOND_COUNTS
    return id >= second_counts[7] && id < second_counts[3];
#else
    return false;
#endif
}

// The share of an instance's LOD cut that occlusion culled (0 without the counters).
fn culled_share(instance: u32) -> f32 {
#ifdef OCCLUDED_PER_INSTANCE
    let at = instance * 2u;
    if at + 1u >= arrayLength(&occluded_per_instance) {
        return 0.0;
    }
    let cut = occluded_per_instance[at];
    if cut == 0u {
        return 0.0;
    }
    return f32(min(occluded_per_instance[at + 1u], cut)) / f32(cut);
#else
    return 0.0;
#endif
}

#ifdef CLUSTERED_LIGHTS
// Light clustering's output: the objects, the grid, and per froxel and kind an offset
// and a count into one list of object indices.
@group(0) @binding(11) var<storage, read> objects: array<ClusterableObject>;
@group(0) @binding(12) var<storage, read> cluster_grid: ClusterGrid;
@group(0) @binding(13) var<storage, read> cluster_offsets: array<u32>;
@group(0) @binding(14) var<storage, read> cluster_counts: array<u32>;
@group(0) @binding(15) var<storage, read> cluster_objects: array<u32>;

// The (froxel, kind) list of a pixel: start and length, clamped to the buffers.
fn froxel_list(pixel: vec2<f32>, view_z: f32, kind: u32) -> vec2<u32> {
    let froxel = cluster_of_pixel(cluster_grid, pixel, view_z);
    let at = cluster_index(cluster_grid, froxel) * CLUSTERABLE_TYPE_COUNT + kind;
    if at >= min(arrayLength(&cluster_offsets), arrayLength(&cluster_counts)) {
        return vec2(0u);
    }
    let start = min(cluster_offsets[at], arrayLength(&cluster_objects));
    return vec2(start, min(cluster_counts[at], arrayLength(&cluster_objects) - start));
}

// Steps per unit of the clustered lights' fixed-point sum, and the most one light adds.
const LIGHT_SUM_SCALE: f32 = 65536.0;
const LIGHT_SUM_MAX: f32 = 64.0;

// Radiance from the point and spot lights of the pixel's froxel towards `v`: inverse-square
// falloff windowed to reach zero at the range, spots faded over the outer fifth of the
// cone, each reflected by the surface `s` (resolve::brdf). Summed in fixed point
// (2^-16 steps, each light clamped to LIGHT_SUM_MAX), which is associative: populate
// fills a froxel's list in whatever order its atomics fall, and a float sum in another
// order could round a pixel differently from one frame to the next.
fn clustered_lighting(pixel: vec2<f32>, depth: f32, s: Surface, n: vec3<f32>, v: vec3<f32>) -> vec3<f32> {
    let world = position_from_depth(view, pixel_to_uv(view, pixel), depth);
    let view_z = view_z_from_depth(view, depth);
    var sum = vec3(0u);
    for (var kind = CLUSTERABLE_POINT_LIGHT; kind <= CLUSTERABLE_SPOT_LIGHT; kind += 1u) {
        let list = froxel_list(pixel, view_z, kind);
        for (var i = 0u; i < list.y; i += 1u) {
            let light = objects[cluster_objects[list.x + i]];
            let to_light = light.position_range.xyz - world;
            let d2 = max(dot(to_light, to_light), 1e-4);
            let l = to_light * inverseSqrt(d2);
            let range = light.position_range.w;
            let ratio = d2 / max(range * range, 1e-8);
            let window = saturate(1.0 - ratio * ratio);
            var falloff = window * window / d2;
            if kind == CLUSTERABLE_SPOT_LIGHT {
                let cos_outer = light.direction_cos_angle.w;
                let cd = dot(-l, normalize(light.direction_cos_angle.xyz));
                falloff *= smoothstep(cos_outer, mix(cos_outer, 1.0, 0.2), cd);
            }
            let c = light.color_intensity.rgb * light.color_intensity.w * falloff * light_response(s, n, v, l);
            sum += vec3<u32>(clamp(c, vec3(0.0), vec3(LIGHT_SUM_MAX)) * LIGHT_SUM_SCALE + 0.5);
        }
    }
    return vec3<f32>(sum) / LIGHT_SUM_SCALE;
}

// Point and spot lights in the pixel's froxel (the last slice for the sky).
fn light_count(pixel: vec2<f32>, depth: f32, empty: bool) -> u32 {
    var view_z = 3.4e38;
    if !empty {
        view_z = view_z_from_depth(view, depth);
    }
    return froxel_list(pixel, view_z, CLUSTERABLE_POINT_LIGHT).y
        + froxel_list(pixel, view_z, CLUSTERABLE_SPOT_LIGHT).y;
}
#endif

// Black through blue, green and yellow to red as `t` goes from 0 to 1.
fn heat(t: f32) -> vec3<f32> {
    let x = saturate(t);
    return saturate(vec3(
        1.5 - abs(4.0 * x - 3.0),
        1.5 - abs(4.0 * x - 2.0),
        1.5 - abs(4.0 * x - 1.0),
    )) * min(x * 8.0, 1.0);
}


// A well-mixed 32-bit hash (lowbias32), for colours that tell neighbouring ids apart.
fn hash(x: u32) -> u32 {
    var h = x;
    h ^= h >> 16u;
    h *= 0x7feb352du;
    h ^= h >> 15u;
    h *= 0x846ca68bu;
    h ^= h >> 16u;
    return h;
}

// The scene cluster (instance, meshlet) as one word: its colour stays the same whichever
// raster slot the atomics gave it this frame (`cpu::cluster_key`).
fn cluster_key(c: Cluster) -> u32 {
    return hash(c.instance) ^ c.meshlet;
}

// The colour of an id: three bytes of its hash, lifted to 64..255 so none is too dark.
fn id_color(id: u32) -> vec3<u32> {
    let h = hash(id);
    let bytes = vec3(h & 0xffu, (h >> 8u) & 0xffu, (h >> 16u) & 0xffu);
    return vec3(64u) + bytes * 3u / 4u;
}

fn byte_color(c: vec3<u32>) -> vec3<f32> {
    return vec3<f32>(c) / 255.0;
}

// A checkerboard box-filtered over the pixel's footprint in checker space (the
// analytic integral of the square wave), so it fades to grey instead of aliasing.
fn filtered_checker(p: vec2<f32>, ddx: vec2<f32>, ddy: vec2<f32>) -> f32 {
    let w = max(abs(ddx), abs(ddy)) + vec2(1e-4);
    let i = 2.0 * (abs(fract((p - 0.5 * w) * 0.5) - 0.5) - abs(fract((p + 0.5 * w) * 0.5) - 0.5)) / w;
    return 0.5 - 0.5 * i.x * i.y;
}

// A corner of the pixel's triangle: where it lies (world space and clip space), its
// mesh-space normal and its texture coordinates (0 without UVs).
struct CornerAttributes {
    clip: vec4<f32>,
    world: vec3<f32>,
    normal: vec3<f32>,
    uv: vec2<f32>,
}

// The corners are decoded by three calls to this, not by a loop filling arrays: a
// driver may keep arrays indexed in a loop in memory, and on an H200 the loop cost
// 8% of the 3840×2160 resolve.
fn corner_attributes(instance: Instance, m: Meshlet, mesh: Mesh, v: u32) -> CornerAttributes {
    var c: CornerAttributes;
    c.world = (instance.world_from_local * vec4(corner_position(m, mesh, v), 1.0)).xyz;
    c.clip = view.view_projection * vec4(c.world, 1.0);
    c.normal = corner_normal(m, v);
    c.uv = corner_uv(m, mesh, v);
    return c;
}

// What shading knows of a pixel's surface before it is lit.
struct PixelSurface {
    material: Material,
    // Base colour (factor × texture × vertex colour × checker) and its alpha, linear.
    base: vec4<f32>,
    metallic: f32,
    roughness: f32,
    // Shading normal (normal map applied) and direction to the eye, world space.
    n: vec3<f32>,
    v: vec3<f32>,
    // The surface point, world space.
    world: vec3<f32>,
    // The ambient light's share left by the occlusion map.
    occlusion: f32,
    emissive: vec3<f32>,
    // Texture coordinates and their change per pixel step.
    uv: vec2<f32>,
    uv_dx: vec2<f32>,
    uv_dy: vec2<f32>,
}

// `map` of `material` at the pixel, or `fallback` where the material has no such texture.
fn sample_map(material: Material, map: u32, s: PixelSurface, fallback: vec4<f32>) -> vec4<f32> {
    let words = material.maps[map];
    if !texture_present(words) {
        return fallback;
    }
    return sample_texture(words, s.uv, s.uv_dx, s.uv_dy);
}

// The normal map's normal: the texel's tangent-space vector (x, y scaled by the
// material's scale) in the triangle's tangent frame, derived from its world-space edges
// and UV edges (no tangents are stored). glTF's V runs down the image while a normal
// map's green points up it, so the bitangent is cross(n, t) for an unmirrored mapping
// and its opposite where the UVs are mirrored.
fn mapped_normal(n: vec3<f32>, world: array<vec3<f32>, 3>, uv: array<vec2<f32>, 3>, texel: vec3<f32>, scale: f32) -> vec3<f32> {
    let e1 = world[1] - world[0];
    let e2 = world[2] - world[0];
    let d1 = uv[1] - uv[0];
    let d2 = uv[2] - uv[0];
    let r = d1.x * d2.y - d2.x * d1.y;
    let t_raw = (e1 * d2.y - e2 * d1.y) * sign(r);
    let t_perp = t_raw - n * dot(n, t_raw);
    if r == 0.0 || dot(t_perp, t_perp) < 1e-20 {
        return n;
    }
    let t = normalize(t_perp);
    let b = cross(n, t) * -sign(r);
    let m = (texel * 2.0 - 1.0) * vec3(scale, scale, 1.0);
    return normalize(t * m.x + b * m.y + n * m.z);
}

fn pixel_surface(value: vec2<u32>, pixel: vec2<f32>) -> PixelSurface {
    let id = visbuffer_cluster(value);
    let t = visbuffer_triangle(value);
    let tri = cluster_triangle(raster_clusters[id], t);
    let instance = tri.instance;
    let m = tri.m;
    let mesh = tri.mesh;
    let corners = tri.corners;
    let c0 = corner_attributes(instance, m, mesh, corners.x);
    let c1 = corner_attributes(instance, m, mesh, corners.y);
    let c2 = corner_attributes(instance, m, mesh, corners.z);
    let clip = array(c0.clip, c1.clip, c2.clip);
    let world = array(c0.world, c1.world, c2.world);
    let normal = array(c0.normal, c1.normal, c2.normal);
    var uv = array(c0.uv, c1.uv, c2.uv);
    let bary = barycentrics(clip[0], clip[1], clip[2], pixel, vec2(f32(params.width), f32(params.height)));
    let b = bary.b;
    var s: PixelSurface;
    let material = materials[instance.material + meshlet_material(m)];
    s.material = material;
    s.n = normalize(instance_transform_normal(instance, normal[0] * b.x + normal[1] * b.y + normal[2] * b.z));
    s.world = world[0] * b.x + world[1] * b.y + world[2] * b.z;
    s.v = normalize(view.camera_position - s.world);
    var at = interpolated_uv(uv, bary);
    if material.uv_transform != 0u {
        // The coordinates the maps are sampled at (as meshlight::surface's `cut_at`
        // finds them), and the corners' for the normal map's tangent frame.
        let r = uv_transform_rows(material.uv_transform);
        at = transformed_uv(r, at);
        uv = array(material_uv(r[0], r[1], uv[0]), material_uv(r[0], r[1], uv[1]), material_uv(r[0], r[1], uv[2]));
    }
    s.uv = at.uv;
    s.uv_dx = at.dx;
    s.uv_dy = at.dy;
    s.base = material.base_color * sample_map(material, MAP_BASE_COLOR, s, vec4(1.0));
#ifdef VERTEX_COLORS
    if (mesh.flags & MESH_FLAG_COLORS) != 0u {
        let colors = meshlet_color_word(m, mesh.flags);
        s.base *= vertex_color(payload[colors + corners[0]]) * b.x + vertex_color(payload[colors + corners[1]]) * b.y + vertex_color(payload[colors + corners[2]]) * b.z;
    }
#endif
    if (material.flags & MATERIAL_FLAG_CHECKER) != 0u {
        let scale = params.checker_scale;
        s.base = vec4(s.base.rgb * mix(CHECKER_DARK, 1.0, filtered_checker(s.uv * scale, s.uv_dx * scale, s.uv_dy * scale)), s.base.a);
    }
    let metallic_roughness = sample_map(material, MAP_METALLIC_ROUGHNESS, s, vec4(1.0));
    s.metallic = material.metallic * metallic_roughness.b;
    s.roughness = material.roughness * metallic_roughness.g;
    if texture_present(material.maps[MAP_NORMAL]) {
        let texel = sample_map(material, MAP_NORMAL, s, vec4(0.5, 0.5, 1.0, 1.0)).xyz;
        s.n = mapped_normal(s.n, world, uv, texel, material.emissive.w);
    }
    // A double-sided material's back face (drawn turned by the rasterisers; clockwise in
    // NDC, which the homogeneous determinant tells even with a corner behind the eye) is
    // lit with its shading normal reversed, as glTF asks. Only such materials pay for
    // the test: taken for every pixel it cost the resolve 1% at 3840×2160 on an H200.
    if (material.flags & MATERIAL_FLAG_DOUBLE_SIDED) != 0u && determinant(mat3x3(clip[0].xyw, clip[1].xyw, clip[2].xyw)) < 0.0 {
        s.n = -s.n;
    }
    s.occlusion = 1.0 + material.occlusion_strength * (sample_map(material, MAP_OCCLUSION, s, vec4(1.0)).r - 1.0);
    s.emissive = material.emissive.rgb * sample_map(material, MAP_EMISSIVE, s, vec4(1.0)).rgb;
    return s;
}

fn shade(value: vec2<u32>, pixel: vec2<f32>) -> vec3<f32> {
    let p = pixel_surface(value, pixel);
    let s = surface(p.base.rgb, p.metallic, p.roughness);
    var sun = params.light_color.rgb * light_response(s, p.n, p.v, params.light_direction.xyz);
#ifdef SHADOWS
    sun *= shadow_factor(view, p.world, p.n);
#endif
    var radiance = params.ambient_color.rgb * ambient_response(s) * p.occlusion + sun;
#ifdef CLUSTERED_LIGHTS
    radiance += clustered_lighting(pixel, visbuffer_depth(value), s, p.n, p.v);
#endif
    return radiance + p.emissive;
}

// The `mip` view: a colour per level the base colour texture is read at, black without one.
fn mip_color(p: PixelSurface) -> vec3<f32> {
    let words = p.material.maps[MAP_BASE_COLOR];
    if !texture_present(words) {
        return vec3(0.0);
    }
    return byte_color(id_color(u32(floor(texture_lod(words, p.uv_dx, p.uv_dy)))));
}

@compute @workgroup_size(16, 8)
fn shade_pixels(@builtin(global_invocation_id) gid: vec3<u32>) {
    if gid.x >= params.width || gid.y >= params.height {
        return;
    }
    let value = visibility_at(gid.xy, params.width);
    let pixel = vec2<f32>(gid.xy) + vec2(0.5);
    var rgb = vec3(0.0);
    let empty = visbuffer_is_empty(value);
    switch params.view_mode {
        case VIEW_CLUSTERS: {
            if !empty {
                rgb = byte_color(id_color(cluster_key(raster_clusters[visbuffer_cluster(value)])));
            }
        }
        case VIEW_TRIANGLES: {
            if !empty {
                let key = cluster_key(raster_clusters[visbuffer_cluster(value)]);
                rgb = byte_color(id_color(key * 131u + visbuffer_triangle(value)));
            }
        }
        case VIEW_LOD: {
            if !empty {
                let m = meshlets[raster_clusters[visbuffer_cluster(value)].meshlet];
                rgb = byte_color(id_color(meshlet_level(m)));
            }
        }
        case VIEW_MATERIAL: {
            if !empty {
                let cluster = raster_clusters[visbuffer_cluster(value)];
                let slot = meshlet_material(meshlets[cluster.meshlet]);
                rgb = byte_color(id_color(instance_at(cluster.instance).material + slot));
            }
        }
        case VIEW_UV: {
            if !empty {
                let uv = pixel_surface(value, pixel).uv;
                rgb = vec3(fract(uv), 0.0);
            }
        }
        case VIEW_NORMAL: {
            if !empty {
                rgb = pixel_surface(value, pixel).n * 0.5 + 0.5;
            }
        }
        case VIEW_MIP: {
            if !empty {
                rgb = mip_color(pixel_surface(value, pixel));
            }
        }
        case VIEW_BASE_COLOR: {
            if !empty {
                rgb = pixel_surface(value, pixel).base.rgb;
            }
        }
        case VIEW_RASTER: {
            if !empty {
                let software = visbuffer_cluster(value) < raster_counts[0];
                rgb = byte_color(select(HARDWARE_COLOR, SOFTWARE_COLOR, software));
            }
        }
        case VIEW_DEPTH: {
            // Reverse-Z depth falls off as 1 / distance; the fourth root spreads it.
            rgb = vec3(sqrt(sqrt(visbuffer_depth(value))));
        }
        case VIEW_LIGHT_COUNT: {
#ifdef CLUSTERED_LIGHTS
            rgb = heat(f32(light_count(pixel, visbuffer_depth(value), empty)) / LIGHT_COUNT_FULL);
#endif
        }
        case VIEW_PYRAMID: {
#ifdef PYRAMID
            rgb = vec3(sqrt(sqrt(max(pyramid_depth(gid.xy, params.pyramid_mip), 0.0))));
#endif
        }
        case VIEW_SHADOW: {
#ifdef SHADOWS
            if !empty {
                let p = pixel_surface(value, pixel);
                let k = cascade_index(view, p.world);
                let tint = select(NO_CASCADE_COLOR, CASCADE_COLORS[min(k, 3u)], k < shadows.count);
                rgb = tint * (0.3 + 0.7 * shadow_factor(view, p.world, p.n));
            }
#endif
        }
        case VIEW_RESIDENCY: {
            if !empty {
                let tint = RESIDENCY_COLORS[levels_missing(raster_clusters[visbuffer_cluster(value)])];
                let lit = min(dot(shade(value, pixel), vec3(0.2126, 0.7152, 0.0722)), 1.0);
                rgb = tint * (0.45 + 0.55 * lit);
            }
        }
        case VIEW_OCCLUSION: {
            if !empty {
                let id = visbuffer_cluster(value);
                let base = select(FIRST_PASS_COLOR, SECOND_PASS_COLOR, drawn_by_second_pass(id));
                let tint = mix(base, CULLED_COLOR, CULLED_TINT * culled_share(raster_clusters[id].instance));
                // The shaded image's brightness, lifted, so shapes stay readable.
                let lit = min(dot(shade(value, pixel), vec3(0.2126, 0.7152, 0.0722)), 1.0);
                rgb = tint * (0.45 + 0.55 * lit);
            }
        }
        default: {
            if empty {
                let t = 1.0 - pixel.y / f32(params.height);
                rgb = mix(SKY_HORIZON, SKY_ZENITH, t);
            } else {
                rgb = shade(value, pixel);
            }
        }
    }
    textureStore(color, vec2<i32>(gid.xy), vec4(clamp(rgb, vec3(0.0), vec3(1.0)), 1.0));
}
