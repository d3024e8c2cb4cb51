// Software rasteriser: one workgroup per cluster, one thread per triangle, 64-bit
// atomicMax into the visibility buffer (a storage buffer, or with VIS_TEXTURE an R64Uint
// storage texture).
// `cpu::rasterize` (Rust) is the reference; every step below has its mirror there.
//
// With BIG_TRIANGLES, a triangle whose clipped box reaches `big_triangle_px` pixels in
// width or height is not covered by its thread: it is cut into tiles of TILE × TILE
// pixels of its box, listed in `big_triangle_tiles`, and `raster_big` covers each tile with a
// workgroup, its threads striding over the tile's pixels one at a time. The pixels, depths and values are the ones the thread
// would have written (the same setup and the same `shade`), so the reference does not
// change; only who covers them does. When the list is full the thread covers its
// triangle itself (atomicMax makes a pixel written twice harmless).
//
// A triangle with a corner outside the clip volume (in front of the near plane, or past
// the guard band GUARD screens out) is clipped in clip space, as a hardware rasteriser
// clips, and the pieces of its polygon (a fan) are covered one by one; each piece may be
// tiled like any triangle. So clusters crossing the near plane need no hardware raster.
// `raster` only lists the clusters holding such triangles; `raster_clipped` clips them,
// so the clipping code (and the registers it needs) stays out of the main kernel.

#import meshlight::dispatch::linear_workgroup
#import meshlight::meshlet::{Meshlet, Mesh, Cluster, meshlet_vertex_count, meshlet_triangle_count, meshlet_triangle_location, meshlet_triangle, meshlet_material}
#import meshlight::instance::{Instance, MATERIAL_FLAG_DOUBLE_SIDED, MATERIAL_FLAG_MASK}
#import meshlight::instance_table::instance_at
#import meshlight::scene_buffers::{meshes, meshlets, payload, materials, payload_grid_offsets}
#import meshlight::cluster_triangle::{ClusterTriangle, cluster_triangle}
#import meshlight::view::View
#import meshlight::visbuffer64::visbuffer64_pack
#import meshlight::visbuffer::visbuffer_depth_bits
#ifdef ALPHA_MASK
#import meshlight::surface::{CutOut, cut_out_setup, cut_at}
#endif

// The uniform block, declared once for Rust and WGSL by `GpuParams` in lib.rs.
#import sw_raster::params::Params

@group(0) @binding(0) var<storage, read> raster_clusters: array<Cluster>;
@group(0) @binding(1) var<storage, read> raster_counts: array<u32>;
@group(0) @binding(2) var<storage, read> sw_args: array<u32>;
// The scene's instances, meshes, meshlets and payload: meshlight::instance_table and
// meshlight::scene_buffers.
#ifdef DEPTH_ONLY
// `depth_only`: layers of width × height depths, reverse-Z f32 bits (which order as the
// depths do, all being at least 0), written with 32-bit atomicMax at layer `params.layer`.
@group(0) @binding(7) var<storage, read_write> visbuffer: array<atomic<u32>>;
#else
#ifdef VIS_TEXTURE
// `texture`: an R64Uint storage texture with 64-bit texture atomics.
@group(0) @binding(7) var visbuffer: texture_storage_2d<r64uint, atomic>;
#else
// `buffer`: width × height values, row-major, with 64-bit buffer atomics.
@group(0) @binding(7) var<storage, read_write> visbuffer: array<atomic<u64>>;
#endif
#endif
@group(0) @binding(8) var<uniform> view: View;
@group(0) @binding(9) var<uniform> params: Params;
#ifdef BIG_TRIANGLES
// One tile of a big triangle each: x = slot << 7 | triangle, y = tile x | tile y << 14;
// for a piece of a clipped triangle, x = the piece's index in `clip_list` and bit 31 of
// y set.
@group(0) @binding(10) var<storage, read_write> big_triangle_tiles: array<vec2<u32>>;
// [0] tiles listed, [1] tiles asked for (more than [0] when the list was full).
@group(0) @binding(11) var<storage, read_write> big_triangle_count: array<atomic<u32>>;
#endif
// Words [0, CLIP_CLUSTERS): the slots of clusters with a triangle to clip; then, with
// BIG_TRIANGLES, PIECE_WORDS words per big piece of a clipped triangle: its three
// snapped corners (x, y, depth bits) and `slot << 7 | triangle`.
@group(0) @binding(12) var<storage, read_write> clip_list: array<u32>;
// [0] clusters listed, [1] asked for, [2] pieces stored, [3] asked for.
@group(0) @binding(13) var<storage, read_write> clip_count: array<atomic<u32>>;

// A big triangle's tiles are TILE × TILE pixels: 32 pixels per thread of `raster_big`.
const TILE: i32 = 64;

// Vertices whose screen position reaches 2^20 pixels are unusable: below it the 8-bit
// fixed-point coordinates stay under 2^28, their differences under 2^29, and every
// edge-function product under 2^58, inside i64.
const MAX_SCREEN: f32 = 1048576.0;

// The guard band: clip-space |x| and |y| up to GUARD * w. Its screen coordinates stay
// under MAX_SCREEN (at most 32 viewports of 16,384 pixels out), so clipping against it
// keeps every piece usable while the pixels of the viewport are the same.
const GUARD: f32 = 63.0;
// Clusters `clip_list` holds, and big clipped pieces after them, PIECE_WORDS words each
// (the Rust side sizes the buffer from the same numbers).
const CLIP_CLUSTERS: u32 = 16384u;
const CLIP_PIECES: u32 = 16384u;
const PIECE_WORDS: u32 = 10u;
// Bit 31 of a tile entry's y: the entry is a stored piece.
const PIECE_TILE: u32 = 0x80000000u;

var<workgroup> screen_xy: array<vec2<i32>, 255>;
var<workgroup> screen_z: array<f32, 255>;
var<workgroup> usable: array<u32, 255>;
var<workgroup> widest: atomic<u32>;
// Set when a triangle of the cluster needs clipping.
var<workgroup> needs_clip: atomic<u32>;

// `m * vec4(p, 1.0)` summed column by column in a fixed order, which `cpu::affine`
// repeats; a matrix-vector product may be summed in any order by the driver.
fn affine(m: mat4x4<f32>, p: vec3<f32>) -> vec4<f32> {
    return unfused4(m[0] * p.x) + unfused4(m[1] * p.y) + unfused4(m[2] * p.z) + m[3];
}

// `x` itself, through an operation on a value the compiler cannot know (params.zero),
// so a product passed through it is rounded on its own and never fused into an fma
// with the add that follows (the reference rounds every product).
fn unfused(x: f32) -> f32 {
    return bitcast<f32>(bitcast<u32>(x) ^ params.zero);
}

fn unfused3(x: vec3<f32>) -> vec3<f32> {
    return bitcast<vec3<f32>>(bitcast<vec3<u32>>(x) ^ vec3(params.zero));
}

fn unfused4(x: vec4<f32>) -> vec4<f32> {
    return bitcast<vec4<f32>>(bitcast<vec4<u32>>(x) ^ vec4(params.zero));
}

// `a / b`. With EXACT_DIVISION: rounded to nearest (ties to even), as IEEE 754 and the
// reference divide, from integer operations: Vulkan lets a driver divide within 2.5 ulp,
// and some do. Without it, the driver's division (exact on lavapipe). Zeros,
// subnormals, infinities, NaNs and quotients outside the normal range take the driver's
// division instead; none of them reaches a visible pixel's depth or position.
fn divide(a: f32, b: f32) -> f32 {
#ifdef EXACT_DIVISION
    let ua = bitcast<u32>(a);
    let ub = bitcast<u32>(b);
    let ea = i32(extractBits(ua, 23u, 8u));
    let eb = i32(extractBits(ub, 23u, 8u));
    if ea == 0 || ea == 255 || eb == 0 || eb == 255 {
        return a / b;
    }
    // Significands as 24-bit integers; their quotient, scaled by 2^40, has 40 or 41
    // bits, and a remainder sets the lowest one so that rounding to 24 bits in the
    // conversion below sees it (it lies far below the rounding bit).
    let na = u64(extractBits(ua, 0u, 23u) | 0x800000u) << 40u;
    let mb = u64(extractBits(ub, 0u, 23u) | 0x800000u);
    let n = na / mb;
    let f = f32(n | select(0lu, 1lu, n * mb != na));
    // The quotient is f * 2^(ea - eb - 40): an exponent add when it stays normal.
    let shift = ea - eb - 40;
    let exponent = i32(extractBits(bitcast<u32>(f), 23u, 8u)) + shift;
    if exponent < 1 || exponent > 254 {
        return a / b;
    }
    let magnitude = bitcast<u32>(f) + bitcast<u32>(shift << 23u);
    return bitcast<f32>(magnitude | ((ua ^ ub) & 0x80000000u));
#else
    return a / b;
#endif
}

// Twice the signed area of (a, b, p); positive when p lies right of a→b on the y-down
// screen, i.e. inside a clockwise (front-facing) triangle.
fn edge(a: vec2<i32>, b: vec2<i32>, p: vec2<i32>) -> i64 {
    return i64(b.x - a.x) * i64(p.y - a.y) - i64(b.y - a.y) * i64(p.x - a.x);
}

// Top or left edge of a clockwise triangle on the y-down screen.
fn top_left(a: vec2<i32>, b: vec2<i32>) -> bool {
    let d = b - a;
    return d.y < 0 || (d.y == 0 && d.x > 0);
}

// One vertex on the screen: 8-bit fixed-point position, NDC depth, and whether it is
// usable (in front of the eye, within 2^20 pixels).
struct ScreenVertex {
    xy: vec2<i32>,
    z: f32,
    ok: bool,
}

// Vertex `v` of meshlet `m` in clip space.
fn clip_vertex(m: Meshlet, mesh: Mesh, instance: Instance, v: u32) -> vec4<f32> {
    // `meshlet_position`, with the product kept apart from the add.
    let q = vec3(m.grid_min[0], m.grid_min[1], m.grid_min[2]) + payload_grid_offsets(m, v);
    let p = mesh.position_grid.xyz + unfused3(vec3<f32>(q) * mesh.position_grid.w);
    let world = affine(instance.world_from_local, p);
    return affine(view.view_projection, world.xyz);
}

// A clip-space position projected and snapped.
fn snap(clip: vec4<f32>) -> ScreenVertex {
    let size = vec2(f32(params.width), f32(params.height));
    let ndc = vec3(divide(clip.x, clip.w), divide(clip.y, clip.w), divide(clip.z, clip.w));
    let s = vec2((ndc.x * 0.5 + 0.5) * size.x, (0.5 - ndc.y * 0.5) * size.y);
    let ok = clip.w > 0.0 && abs(s.x) < MAX_SCREEN && abs(s.y) < MAX_SCREEN;
    return ScreenVertex(select(vec2(0), vec2<i32>(round(s * 256.0)), ok), ndc.z, ok);
}

// Vertex `v` of meshlet `m` transformed and snapped.
fn screen_vertex(m: Meshlet, mesh: Mesh, instance: Instance, v: u32) -> ScreenVertex {
    return snap(clip_vertex(m, mesh, instance, v));
}

// Signed distance of a clip-space position to clipping plane k (inside when >= 0):
// 0 the near plane (reverse Z: depth z / w at most 1), 1-4 the guard band's sides.
fn plane_distance(c: vec4<f32>, k: u32) -> f32 {
    let band = unfused(GUARD * c.w);
    switch k {
        case 0u: { return c.w - c.z; }
        case 1u: { return band + c.x; }
        case 2u: { return band - c.x; }
        case 3u: { return band + c.y; }
        default: { return band - c.y; }
    }
}

// Inside every clipping plane (each plane_distance >= 0): drawn as it is, without
// clipping. Written as comparisons, not through plane_distance: it runs for every
// vertex of every cluster, and the loop over the planes cost the kernel 10%.
fn inside(c: vec4<f32>) -> bool {
    let band = unfused(GUARD * c.w);
    return c.w > 0.0 && c.z <= c.w && abs(c.x) <= band && abs(c.y) <= band;
}

// A triangle clipped to the clip volume: a convex polygon in the triangle's winding.
struct Polygon {
    corners: array<vec4<f32>, 8>,
    count: u32,
}

// Where the edge from an inside corner `a` (distance `da` >= 0) to an outside corner `b`
// (`db` < 0) crosses the plane. Always from the inside corner: a triangle and its
// neighbour walk a shared edge in opposite directions, and must find the same point.
fn crossing(a: vec4<f32>, b: vec4<f32>, da: f32, db: f32) -> vec4<f32> {
    let t = divide(da, da - db);
    return a + unfused4(t * (b - a));
}

// Sutherland-Hodgman against the near plane and the guard band's four sides, in that
// order.
fn clip_triangle(a: vec4<f32>, b: vec4<f32>, c: vec4<f32>) -> Polygon {
    var poly: Polygon;
    poly.corners[0] = a;
    poly.corners[1] = b;
    poly.corners[2] = c;
    poly.count = 3u;
    for (var k = 0u; k < 5u; k += 1u) {
        var out: Polygon;
        out.count = 0u;
        for (var i = 0u; i < poly.count; i += 1u) {
            let p = poly.corners[i];
            let q = poly.corners[(i + 1u) % poly.count];
            let dp = plane_distance(p, k);
            let dq = plane_distance(q, k);
            if dp >= 0.0 {
                out.corners[out.count] = p;
                out.count += 1u;
                if dq < 0.0 {
                    out.corners[out.count] = crossing(p, q, dp, dq);
                    out.count += 1u;
                }
            } else if dq >= 0.0 {
                out.corners[out.count] = crossing(q, p, dq, dp);
                out.count += 1u;
            }
        }
        poly = out;
        if poly.count < 3u {
            poly.count = 0u;
            break;
        }
    }
    return poly;
}

// The snapped corners of piece `k` of a clipped polygon's fan, (0, k + 1, k + 2);
// `ok` is false for all three when one does not snap.
fn piece_corners(poly: Polygon, k: u32) -> array<ScreenVertex, 3> {
    var v = array(snap(poly.corners[0]), snap(poly.corners[k + 1u]), snap(poly.corners[k + 2u]));
    if !(v[0].ok && v[1].ok && v[2].ok) {
        v[0].ok = false;
    }
    return v;
}

// The material flags this variant acts on: MATERIAL_FLAG_DOUBLE_SIDED with TWO_SIDED (back
// faces are turned to face the eye rather than dropped), MATERIAL_FLAG_MASK with
// ALPHA_MASK (pixels `cut_at` cuts out are left undrawn). A renderer sets them only for a scene
// with such a material; with neither, no material is read.
#ifdef TWO_SIDED
const SIDED_FLAG: u32 = MATERIAL_FLAG_DOUBLE_SIDED;
#else
const SIDED_FLAG: u32 = 0u;
#endif
#ifdef ALPHA_MASK
const MASK_FLAG: u32 = MATERIAL_FLAG_MASK;
#else
const MASK_FLAG: u32 = 0u;
#endif

// The flags of the material meshlet `m` placed by `instance` is drawn with, of those
// this variant acts on.
fn material_flags(instance: Instance, m: Meshlet) -> u32 {
    if (SIDED_FLAG | MASK_FLAG) == 0u {
        return 0u;
    }
    return materials[instance.material + meshlet_material(m)].flags & (SIDED_FLAG | MASK_FLAG);
}

// `material_flags` of the cluster in raster slot `slot`.
fn slot_material_flags(slot: u32) -> u32 {
    let cluster = raster_clusters[slot];
    return material_flags(instance_at(cluster.instance), meshlets[cluster.meshlet]);
}

// A triangle ready to cover, with its clipped pixel box [lo, hi] (empty when it is a
// back face of a material that is not double-sided, degenerate, or off the screen).
struct Setup {
    tri: Tri,
    lo: vec2<i32>,
    hi: vec2<i32>,
}

fn triangle_setup(a: ScreenVertex, b: ScreenVertex, c: ScreenVertex, slot: u32, t: u32, flags: u32) -> Setup {
    var tri: Tri;
    let two_sided = (flags & MATERIAL_FLAG_DOUBLE_SIDED) != 0u;
#ifdef ALPHA_MASK
    if (flags & MATERIAL_FLAG_MASK) != 0u {
        // Once per triangle (or piece, or tile): what every covered pixel's test needs.
        tri.cut = cut_out_setup(raster_clusters[slot], t, view.view_projection);
    }
#endif
    var lo = vec2(0);
    var hi = vec2(-1);
    // Front faces are counter-clockwise in NDC (y up), so counter-clockwise on the
    // y-down screen too; corners (0, 2, 1) make them clockwise there. A two-sided back
    // face is turned back to (0, 1, 2), which is clockwise for it.
    tri.v0 = a.xy;
    tri.v1 = c.xy;
    tri.v2 = b.xy;
    tri.z = vec3(a.z, c.z, b.z);
    tri.area = edge(tri.v0, tri.v1, tri.v2);
    if two_sided && tri.area < 0li {
        tri.v1 = b.xy;
        tri.v2 = c.xy;
        tri.z = vec3(a.z, b.z, c.z);
        tri.area = -tri.area;
    }
    let fa = f32(tri.area);
    tri.gradient = vec2(divide(tri.z.y - tri.z.x, fa), divide(tri.z.z - tri.z.x, fa));
    tri.bias = vec3(
        select(-1, 0, top_left(tri.v1, tri.v2)),
        select(-1, 0, top_left(tri.v2, tri.v0)),
        select(-1, 0, top_left(tri.v0, tri.v1)),
    );
    tri.value_cluster = slot;
    tri.triangle = t;
    // Back faces (not two-sided) and degenerate triangles have area <= 0.
    if tri.area > 0li {
        let mn = min(tri.v0, min(tri.v1, tri.v2));
        let mx = max(tri.v0, max(tri.v1, tri.v2));
        // Pixels whose centre x * 256 + 128 lies in [mn, mx], clipped to the viewport.
        lo = max((mn - vec2(128) + vec2(255)) >> vec2(8u), vec2(0));
        hi = min((mx - vec2(128)) >> vec2(8u), vec2(i32(params.width), i32(params.height)) - vec2(1));
    }
    return Setup(tri, lo, hi);
}

struct Tri {
    v0: vec2<i32>,
    v1: vec2<i32>,
    v2: vec2<i32>,
    z: vec3<f32>,
    // Depth per unit of edge functions 1 and 2: (z1 - z0) / area, (z2 - z0) / area.
    gradient: vec2<f32>,
    area: i64,
    bias: vec3<i32>,
    value_cluster: u32,
    triangle: u32,
#ifdef ALPHA_MASK
    // Set up for a MASK material (`cut.masked`): each covered pixel asks `cut_at`
    // before it is written.
    cut: CutOut,
#endif
}

// Pixel (x, y) of the triangle, when it covers it: edge functions in i64, which any
// usable triangle fits.
fn shade(tri: Tri, x: i32, y: i32) {
    let p = vec2(x * 256 + 128, y * 256 + 128);
    let e0 = edge(tri.v1, tri.v2, p);
    let e1 = edge(tri.v2, tri.v0, p);
    let e2 = edge(tri.v0, tri.v1, p);
    if e0 + i64(tri.bias.x) < 0li || e1 + i64(tri.bias.y) < 0li || e2 + i64(tri.bias.z) < 0li {
        return;
    }
    write_pixel(tri, x, y, f32(e1), f32(e2));
}

// Whether the triangle takes `cover_small`: its corners lie within `params.small_extent`
// (at most 2^14) fixed-point units of each other on both axes.
fn is_small(tri: Tri) -> bool {
    let extent = max(tri.v0, max(tri.v1, tri.v2)) - min(tri.v0, min(tri.v1, tri.v2));
    return all(vec2<u32>(extent) < vec2(params.small_extent));
}

// Every pixel of the box [lo, hi] a small triangle covers, with the edge functions in
// i32, stepped from pixel to pixel by adds. Exact, so the same pixels and depths as
// `shade`: a pixel centre of the box lies within the corners' extent (under 2^14) of
// each corner, one step past it under 2^14 + 2^8, so each product of an edge function
// stays under 2^28.1 and the function under 2^29.1. On an H200 the i64 products of
// `shade` cost the default frame's software raster 14% at 3840×2160.
fn cover_small(tri: Tri, lo: vec2<i32>, hi: vec2<i32>) {
    let p = vec2(lo.x * 256 + 128, lo.y * 256 + 128);
    var row = vec3(edge32(tri.v1, tri.v2, p), edge32(tri.v2, tri.v0, p), edge32(tri.v0, tri.v1, p));
    // `edge(a, b, p)` grows by a.y - b.y per unit of p.x and by b.x - a.x per unit of p.y.
    let step_x = vec3(tri.v1.y - tri.v2.y, tri.v2.y - tri.v0.y, tri.v0.y - tri.v1.y) * 256;
    let step_y = vec3(tri.v2.x - tri.v1.x, tri.v0.x - tri.v2.x, tri.v1.x - tri.v0.x) * 256;
    for (var y = lo.y; y <= hi.y; y += 1) {
        var e = row;
        for (var x = lo.x; x <= hi.x; x += 1) {
            if all(e + tri.bias >= vec3(0)) {
                write_pixel(tri, x, y, f32(e.y), f32(e.z));
            }
            e += step_x;
        }
        row += step_y;
    }
}

// `edge` in i32, for corners and points within `cover_small`'s bound of each other.
fn edge32(a: vec2<i32>, b: vec2<i32>, p: vec2<i32>) -> i32 {
    return (b.x - a.x) * (p.y - a.y) - (b.y - a.y) * (p.x - a.x);
}

// Writes covered pixel (x, y) with edge functions 1 and 2 there (exact integers, as
// f32): its depth, and with ALPHA_MASK only where the material keeps it.
fn write_pixel(tri: Tri, x: i32, y: i32, e1: f32, e2: f32) {
    let depth = tri.z.x + unfused(e1 * tri.gradient.x) + unfused(e2 * tri.gradient.y);
#ifdef ALPHA_MASK
    if cut_at(tri.cut, vec2(f32(x), f32(y)) + 0.5, vec2(f32(params.width), f32(params.height))) {
        return;
    }
#endif
#ifdef DEPTH_ONLY
    // The visibility value's high word.
    let layer_start = params.layer * params.width * params.height;
    atomicMax(&visbuffer[layer_start + u32(y) * params.width + u32(x)], visbuffer_depth_bits(depth));
#else
    let value = visbuffer64_pack(depth, tri.value_cluster, tri.triangle);
#ifdef VIS_TEXTURE
    textureAtomicMax(visbuffer, vec2(u32(x), u32(y)), value);
#else
    atomicMax(&visbuffer[u32(y) * params.width + u32(x)], value);
#endif
#endif
}

@compute @workgroup_size(128)
fn raster(@builtin(workgroup_id) wg: vec3<u32>, @builtin(local_invocation_index) t: u32) {
    let j = linear_workgroup(wg, sw_args[0]);
    if j >= raster_counts[0] {
        return;
    }
    // The slot, which is also the cluster id the visibility buffer holds.
#ifdef SLOT_BASE
    let i = raster_counts[7] + j;
#else
    let i = j;
#endif
    let cluster = raster_clusters[i];
    let instance = instance_at(cluster.instance);
    let m = meshlets[cluster.meshlet];
    let mesh = meshes[instance.mesh];
    let flags = material_flags(instance, m);
    if t == 0u {
        atomicStore(&widest, 0u);
        atomicStore(&needs_clip, 0u);
    }
    for (var v = t; v < meshlet_vertex_count(m); v += 128u) {
        let clip = clip_vertex(m, mesh, instance, v);
        let s = snap(clip);
        usable[v] = select(0u, 1u, s.ok && inside(clip));
        screen_xy[v] = s.xy;
        screen_z[v] = s.z;
    }
    workgroupBarrier();

    var setup = Setup(Tri(), vec2(0), vec2(-1));
    if t < meshlet_triangle_count(m) {
        let at = meshlet_triangle_location(m, t);
        let c = meshlet_triangle(m, t, vec2(payload[at.x], payload[at.x + 1u]), at.y);
        if (usable[c.x] & usable[c.y] & usable[c.z]) != 0u {
            setup = triangle_setup(
                ScreenVertex(screen_xy[c.x], screen_z[c.x], true),
                ScreenVertex(screen_xy[c.y], screen_z[c.y], true),
                ScreenVertex(screen_xy[c.z], screen_z[c.z], true),
                i,
                t,
                flags,
            );
        } else {
            // Clipped by `raster_clipped`.
            atomicStore(&needs_clip, 1u);
        }
    }
    let tri = setup.tri;
    let lo = setup.lo;
    let hi = setup.hi;
    var visible = all(lo <= hi);
#ifdef BIG_TRIANGLES
    if visible && list_big(i, t, lo, hi) {
        visible = false;
    }
#endif
    if visible {
        atomicMax(&widest, u32(hi.x - lo.x + 1));
    }
    workgroupBarrier();
    if t == 0u && atomicLoad(&needs_clip) != 0u {
        let k = atomicAdd(&clip_count[1], 1u);
        if k < CLIP_CLUSTERS {
            clip_list[k] = i;
            atomicAdd(&clip_count[0], 1u);
        }
    }
    // One choice for the whole workgroup, so its threads run the same loop shape.
    let scanline = atomicLoad(&widest) >= params.scanline_width;
    if visible {
        cover(tri, lo, hi, scanline);
    }
}

// Triangle `t` of the cluster in raster slot `slot`: what transforms and decodes it.
fn slot_triangle(slot: u32, t: u32) -> ClusterTriangle {
    return cluster_triangle(raster_clusters[slot], t);
}

// The clusters `raster` listed, a workgroup each (strided) and a thread per triangle:
// the triangles with a corner outside the clip volume (`raster` drew the others) are
// clipped and the pieces of their fan covered, each tiled when big.
@compute @workgroup_size(128)
fn raster_clipped(
    @builtin(workgroup_id) wg: vec3<u32>,
    @builtin(num_workgroups) groups: vec3<u32>,
    @builtin(local_invocation_index) t: u32,
) {
    let listed = min(atomicLoad(&clip_count[0]), CLIP_CLUSTERS);
    for (var e = wg.x; e < listed; e += groups.x) {
        let slot = clip_list[e];
        if t >= meshlet_triangle_count(meshlets[raster_clusters[slot].meshlet]) {
            continue;
        }
        let s = slot_triangle(slot, t);
        let a = clip_vertex(s.m, s.mesh, s.instance, s.corners.x);
        let b = clip_vertex(s.m, s.mesh, s.instance, s.corners.y);
        let d = clip_vertex(s.m, s.mesh, s.instance, s.corners.z);
        if inside(a) && inside(b) && inside(d) && snap(a).ok && snap(b).ok && snap(d).ok {
            continue;
        }
        let poly = clip_triangle(a, b, d);
        let flags = material_flags(s.instance, s.m);
        for (var k = 0u; k + 2u < poly.count; k += 1u) {
            let v = piece_corners(poly, k);
            if !v[0].ok {
                continue;
            }
            let piece = triangle_setup(v[0], v[1], v[2], slot, t, flags);
            if any(piece.lo > piece.hi) {
                continue;
            }
#ifdef BIG_TRIANGLES
            if list_piece(v, slot, t, piece.lo, piece.hi) {
                continue;
            }
#endif
            cover(piece.tri, piece.lo, piece.hi, true);
        }
    }
}

// Every pixel of the box [lo, hi] the triangle covers: a small triangle by
// `cover_small`, others per scanline over each row's edge span, or over the whole box;
// all three cover the same pixels.
fn cover(tri: Tri, lo: vec2<i32>, hi: vec2<i32>, scanline: bool) {
    if is_small(tri) {
        cover_small(tri, lo, hi);
        return;
    }
    if !scanline {
        for (var y = lo.y; y <= hi.y; y += 1) {
            for (var x = lo.x; x <= hi.x; x += 1) {
                shade(tri, x, y);
            }
        }
        return;
    }
    // Scanline: per row, the span where each edge can be non-negative, widened by one
    // pixel on each side (the exact test in `shade` decides), so pixels outside the
    // triangle's row span are never visited.
    // Edge k runs from `starts[k]` to `ends[k]`, as edge function k in `shade`.
    var starts = array(tri.v1, tri.v2, tri.v0);
    var ends = array(tri.v2, tri.v0, tri.v1);
    for (var y = lo.y; y <= hi.y; y += 1) {
        var x0 = lo.x;
        var x1 = hi.x;
        let py = y * 256 + 128;
        for (var k = 0; k < 3; k += 1) {
            let a = starts[k];
            let b = ends[k];
            // edge(a, b, (px, py)) = c + s * px with s = -(b.y - a.y).
            let s = -i64(b.y - a.y);
            let c = i64(b.x - a.x) * i64(py - a.y) + i64(b.y - a.y) * i64(a.x);
            // The bound is found in f32 and clamped to the box (one pixel out) before it
            // becomes an integer: for a nearly horizontal edge it can lie billions of
            // pixels away. Within the box (under 2^22 units) the f32 quotient is a few
            // units (256ths of a pixel) off at most, far inside the pixel of margin, and
            // farther out it stays outside the box: the span still holds every covered
            // pixel. An i64 division instead cost the default frame's raster 5% on an
            // H200.
            let low = lo.x - 1;
            let high = hi.x + 1;
            let units = vec2(f32(low) * 256.0 - 512.0, f32(high) * 256.0 + 512.0);
            if s > 0li {
                // px >= -c / s, px = x * 256 + 128.
                let px = i32(clamp(-f32(c) / f32(s), units.x, units.y));
                x0 = max(x0, clamp(((px - 128) >> 8u) - 1, low, high));
            } else if s < 0li {
                let px = i32(clamp(f32(c) / f32(-s), units.x, units.y));
                x1 = min(x1, clamp(((px - 128) >> 8u) + 1, low, high));
            }
        }
        for (var x = x0; x <= x1; x += 1) {
            shade(tri, x, y);
        }
    }
}

#ifdef BIG_TRIANGLES
// Lists the tiles of a big triangle's box for `raster_big`; false when it is not big,
// or the list has no room for all its tiles (its thread then covers it).
fn list_big(slot: u32, t: u32, lo: vec2<i32>, hi: vec2<i32>) -> bool {
    return is_big(lo, hi) && list_tiles((slot << 7u) | t, 0u, lo, hi);
}

fn is_big(lo: vec2<i32>, hi: vec2<i32>) -> bool {
    let extent = hi - lo + vec2(1);
    return u32(max(extent.x, extent.y)) >= params.big_triangle_px;
}

// The tiles of the box [lo, hi], each listed as (x, its tile | flag); false when the
// list has no room for all of them.
fn list_tiles(x: u32, flag: u32, lo: vec2<i32>, hi: vec2<i32>) -> bool {
    let tiles = (hi - lo + vec2(TILE)) / TILE;
    let n = u32(tiles.x * tiles.y);
    let base = atomicAdd(&big_triangle_count[1], n);
    let cap = min(params.big_capacity, arrayLength(&big_triangle_tiles));
    if base >= cap || n > cap - base {
        return false;
    }
    atomicAdd(&big_triangle_count[0], n);
    for (var k = 0u; k < n; k += 1u) {
        let tile = vec2(k % u32(tiles.x), k / u32(tiles.x));
        big_triangle_tiles[base + k] = vec2(x, tile.x | (tile.y << 14u) | flag);
    }
    return true;
}

// A big piece of a clipped triangle: its corners stored in `clip_list` and its tiles
// listed; false when it is not big or there is no room (its thread then covers it).
fn list_piece(v: array<ScreenVertex, 3>, slot: u32, t: u32, lo: vec2<i32>, hi: vec2<i32>) -> bool {
    if !is_big(lo, hi) {
        return false;
    }
    let p = atomicAdd(&clip_count[3], 1u);
    let base = CLIP_CLUSTERS + p * PIECE_WORDS;
    if p >= CLIP_PIECES || base + PIECE_WORDS > arrayLength(&clip_list) {
        return false;
    }
    atomicAdd(&clip_count[2], 1u);
    for (var k = 0u; k < 3u; k += 1u) {
        clip_list[base + 3u * k] = bitcast<u32>(v[k].xy.x);
        clip_list[base + 3u * k + 1u] = bitcast<u32>(v[k].xy.y);
        clip_list[base + 3u * k + 2u] = bitcast<u32>(v[k].z);
    }
    clip_list[base + 9u] = (slot << 7u) | t;
    return list_tiles(p, PIECE_TILE, lo, hi);
}

// One tile of a big triangle per workgroup (strided), a pixel per thread: the triangle
// is set up again from its cluster (every thread alike), then each thread shades the
// tile's pixels k, k + 128, … that lie in the box.
@compute @workgroup_size(128)
fn raster_big(
    @builtin(workgroup_id) wg: vec3<u32>,
    @builtin(num_workgroups) groups: vec3<u32>,
    @builtin(local_invocation_index) t: u32,
) {
    let listed = min(atomicLoad(&big_triangle_count[0]), min(params.big_capacity, arrayLength(&big_triangle_tiles)));
    for (var e = wg.x; e < listed; e += groups.x) {
        let entry = big_triangle_tiles[e];
        var setup: Setup;
        if (entry.y & PIECE_TILE) != 0u {
            // A stored piece of a clipped triangle.
            let base = CLIP_CLUSTERS + entry.x * PIECE_WORDS;
            var v: array<ScreenVertex, 3>;
            for (var k = 0u; k < 3u; k += 1u) {
                let xy = vec2(bitcast<i32>(clip_list[base + 3u * k]), bitcast<i32>(clip_list[base + 3u * k + 1u]));
                v[k] = ScreenVertex(xy, bitcast<f32>(clip_list[base + 3u * k + 2u]), true);
            }
            let id = clip_list[base + 9u];
            setup = triangle_setup(v[0], v[1], v[2], id >> 7u, id & 127u, slot_material_flags(id >> 7u));
        } else {
            let slot = entry.x >> 7u;
            let triangle = entry.x & 127u;
            let s = slot_triangle(slot, triangle);
            setup = triangle_setup(
                screen_vertex(s.m, s.mesh, s.instance, s.corners.x),
                screen_vertex(s.m, s.mesh, s.instance, s.corners.y),
                screen_vertex(s.m, s.mesh, s.instance, s.corners.z),
                slot,
                triangle,
                material_flags(s.instance, s.m),
            );
        }
        // The part of the box this tile covers, a pixel per thread, row by row.
        let tile = vec2(i32(entry.y & 0x3fffu), i32((entry.y >> 14u) & 0x3fffu));
        let origin = setup.lo + tile * TILE;
        let extent = vec2<u32>(clamp(setup.hi - origin + vec2(1), vec2(0), vec2(TILE)));
        for (var k = t; k < extent.x * extent.y; k += 128u) {
            shade(setup.tri, origin.x + i32(k % extent.x), origin.y + i32(k / extent.x));
        }
    }
}
#endif
