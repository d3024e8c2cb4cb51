#define_import_path meshlight::froxel

// Which froxels of the cluster grid a clusterable object touches. Light clustering's
// count and populate stages (raster and compute implementations alike) and the CPU
// reference decide with these functions, so they agree on every list; `cpu::froxel` in
// Rust mirrors each float operation below in the same order.
//
// An object of a (object, slice) instance is tested against the froxels of that slice
// inside its tile rectangle (`froxel_rect`): the screen bounds of its view-space box cut
// to the slice's depths. Inside the rectangle the test is against each froxel's
// view-space bounding box (`froxel_aabb`): sphere–box for point lights, sphere–box and
// cone–sphere (the box's bounding sphere) for spot lights, and a separating-axis test of
// the object's oriented box against the froxel box for probes and decals.

#import meshlight::view::View
#import meshlight::light::{ClusterableObject, ClusterGrid, Aabb, z_slice_start, CLUSTERABLE_SPOT_LIGHT, CLUSTERABLE_PROBE, CLUSTERABLE_DECAL}

// Where the last slice's box ends. Depths past `far` belong to the last slice, so its
// box must reach past anything a scene holds, yet squared coordinates must stay finite.
const FROXEL_FAR_END: f32 = 1e15;
// Ranges above this, infinity included, are this (as in `z_slice`).
const FROXEL_RANGE_LIMIT: f32 = 1e30;

// An object in view space, prepared once per instance.
struct ViewObject {
    center: vec3<f32>,
    // The range, at most FROXEL_RANGE_LIMIT.
    range: f32,
    // Probes and decals: the box's three half-axes (each `range` long). Spot lights: the
    // unit axis in `axis_z`.
    axis_x: vec3<f32>,
    kind: u32,
    axis_y: vec3<f32>,
    cos_angle: f32,
    axis_z: vec3<f32>,
    sin_angle: f32,
}

// A rectangle of tiles, both corners inclusive; empty when `min_tile.x > max_tile.x`.
struct TileRect {
    min_tile: vec2<u32>,
    max_tile: vec2<u32>,
}

// world → view for a point: the view matrix's columns, summed in this order.
fn view_point(m: mat4x4<f32>, p: vec3<f32>) -> vec3<f32> {
    return m[0].xyz * p.x + m[1].xyz * p.y + m[2].xyz * p.z + m[3].xyz;
}

// world → view for a direction.
fn view_direction(m: mat4x4<f32>, d: vec3<f32>) -> vec3<f32> {
    return m[0].xyz * d.x + m[1].xyz * d.y + m[2].xyz * d.z;
}

fn unit(v: vec3<f32>) -> vec3<f32> {
    return v * (1.0 / sqrt(v.x * v.x + v.y * v.y + v.z * v.z));
}

// The object in view space. Decals have no rotation about their axis in the layout; the
// other two box axes are the branchless orthonormal basis of Duff et al. (2017) around
// the world-space direction, so every stage builds the same box.
fn view_object(view: View, object: ClusterableObject) -> ViewObject {
    let m = view.view;
    let range = min(object.position_range.w, FROXEL_RANGE_LIMIT);
    var o = ViewObject(view_point(m, object.position_range.xyz), range,
        vec3(0.0), object.kind, vec3(0.0), object.direction_cos_angle.w,
        vec3(0.0), object.sin_angle);
    if object.kind == CLUSTERABLE_SPOT_LIGHT {
        o.axis_z = unit(view_direction(m, object.direction_cos_angle.xyz));
    } else if object.kind == CLUSTERABLE_PROBE {
        o.axis_x = m[0].xyz * range;
        o.axis_y = m[1].xyz * range;
        o.axis_z = m[2].xyz * range;
    } else if object.kind == CLUSTERABLE_DECAL {
        let n = unit(object.direction_cos_angle.xyz);
        let s = select(-1.0, 1.0, n.z >= 0.0);
        let a = -1.0 / (s + n.z);
        let b = n.x * n.y * a;
        let t1 = vec3(1.0 + s * n.x * n.x * a, s * b, -s * n.x);
        let t2 = vec3(b, s + n.y * n.y * a, -n.y);
        o.axis_x = view_direction(m, t1) * range;
        o.axis_y = view_direction(m, t2) * range;
        o.axis_z = view_direction(m, n) * range;
    }
    return o;
}

fn is_box(o: ViewObject) -> bool {
    return o.kind == CLUSTERABLE_PROBE || o.kind == CLUSTERABLE_DECAL;
}

// Half-extents of the object's view-space axis-aligned bounds around its centre.
fn view_half_extent(o: ViewObject) -> vec3<f32> {
    if is_box(o) {
        return abs(o.axis_x) + abs(o.axis_y) + abs(o.axis_z);
    }
    return vec3(o.range);
}

// View-space depths where a slice's box begins and ends: slice 0 from the camera's near
// plane (every nearer depth is slice 0's), the last to FROXEL_FAR_END.
fn froxel_depths(view: View, grid: ClusterGrid, slice: u32) -> vec2<f32> {
    var z0 = view.near;
    if slice > 0u {
        z0 = z_slice_start(grid, slice);
    }
    var z1 = FROXEL_FAR_END;
    if slice + 1u < grid.dims.z {
        z1 = z_slice_start(grid, slice + 1u);
    }
    return vec2(z0, z1);
}

// The view-space line through a pixel: its points at NDC depth 1 (the near plane under
// reverse-Z) and 0.5. One line serves perspective (a ray through the eye) and
// orthographic projections (parallel to the view axis) alike.
struct PixelLine {
    a: vec3<f32>,
    b: vec3<f32>,
}

fn unproject(view: View, ndc: vec2<f32>, depth: f32) -> vec3<f32> {
    let ip = view.inverse_projection;
    let p = ip[0] * ndc.x + ip[1] * ndc.y + ip[2] * depth + ip[3];
    return p.xyz / p.w;
}

fn pixel_line(view: View, pixel: vec2<f32>) -> PixelLine {
    let uv = pixel * view.inverse_viewport_size;
    let ndc = uv * vec2(2.0, -2.0) + vec2(-1.0, 1.0);
    return PixelLine(unproject(view, ndc, 1.0), unproject(view, ndc, 0.5));
}

// The line's point at view-space distance `depth` in front of the camera.
fn line_at_depth(line: PixelLine, depth: f32) -> vec3<f32> {
    let t = (depth + line.a.z) / (line.a.z - line.b.z);
    return line.a + (line.b - line.a) * t;
}

// The view-space bounding box of froxel (x, y, slice): its tile's four corner lines cut
// at the slice's depths.
fn froxel_aabb(view: View, grid: ClusterGrid, froxel: vec3<u32>) -> Aabb {
    let tile_min = vec2<f32>(froxel.xy) * grid.tile_size;
    let tile_max = min(tile_min + grid.tile_size, view.viewport_size);
    let depths = froxel_depths(view, grid, froxel.z);
    var lo = vec3(3.4e38);
    var hi = vec3(-3.4e38);
    for (var corner = 0u; corner < 4u; corner += 1u) {
        let pixel = vec2(
            select(tile_min.x, tile_max.x, (corner & 1u) != 0u),
            select(tile_min.y, tile_max.y, (corner & 2u) != 0u),
        );
        let line = pixel_line(view, pixel);
        let p0 = line_at_depth(line, depths.x);
        let p1 = line_at_depth(line, depths.y);
        lo = min(lo, min(p0, p1));
        hi = max(hi, max(p0, p1));
    }
    return Aabb(lo, hi);
}

// The tiles an instance walks: the screen bounds of the object's view-space box cut to
// the slice's depths (and to the near plane), clamped to the grid. Empty when the cut
// leaves nothing.
fn froxel_rect(view: View, grid: ClusterGrid, o: ViewObject, slice: u32) -> TileRect {
    let empty = TileRect(vec2(1u, 0u), vec2(0u, 0u));
    let depths = froxel_depths(view, grid, slice);
    let half = view_half_extent(o);
    let depth = -o.center.z;
    let z_lo = max(max(depths.x, view.near), depth - half.z);
    let z_hi = min(depths.y, depth + half.z);
    if !(z_lo <= z_hi) {
        return empty;
    }
    let lo = o.center.xy - half.xy;
    let hi = o.center.xy + half.xy;
    let p = view.projection;
    var pixel_lo = vec2(3.4e38);
    var pixel_hi = vec2(-3.4e38);
    for (var corner = 0u; corner < 8u; corner += 1u) {
        let x = select(lo.x, hi.x, (corner & 1u) != 0u);
        let y = select(lo.y, hi.y, (corner & 2u) != 0u);
        let z = -select(z_lo, z_hi, (corner & 4u) != 0u);
        let clip = p[0] * x + p[1] * y + p[2] * z + p[3];
        let ndc = clip.xy / clip.w;
        let pixel = (ndc * vec2(0.5, -0.5) + vec2(0.5)) * view.viewport_size;
        pixel_lo = min(pixel_lo, pixel);
        pixel_hi = max(pixel_hi, pixel);
    }
    let last = vec2<f32>(grid.dims.xy - vec2(1u));
    let tile_lo = min(max(floor(pixel_lo / grid.tile_size), vec2(0.0)), last);
    let tile_hi = min(max(floor(pixel_hi / grid.tile_size), vec2(0.0)), last);
    return TileRect(vec2<u32>(tile_lo), vec2<u32>(tile_hi));
}

fn rect_is_empty(rect: TileRect) -> bool {
    return rect.min_tile.x > rect.max_tile.x || rect.min_tile.y > rect.max_tile.y;
}

// True when the sphere touches the box.
fn sphere_touches_aabb(center: vec3<f32>, radius: f32, aabb: Aabb) -> bool {
    let d = center - clamp(center, aabb.min_corner, aabb.max_corner);
    return d.x * d.x + d.y * d.y + d.z * d.z <= radius * radius;
}

// True when `axis` separates the object's box (centre offset `t` from the froxel box's
// centre, half-axes in `o`) from the froxel box (half-extents `e`).
fn separates(axis: vec3<f32>, t: vec3<f32>, e: vec3<f32>, o: ViewObject) -> bool {
    let distance = abs(t.x * axis.x + t.y * axis.y + t.z * axis.z);
    let froxel_reach = e.x * abs(axis.x) + e.y * abs(axis.y) + e.z * abs(axis.z);
    let object_reach = abs(dot(o.axis_x, axis)) + abs(dot(o.axis_y, axis)) + abs(dot(o.axis_z, axis));
    return distance > froxel_reach + object_reach;
}

// Oriented box against axis-aligned box: the fifteen separating axes.
fn box_touches_aabb(o: ViewObject, aabb: Aabb) -> bool {
    let c = 0.5 * (aabb.min_corner + aabb.max_corner);
    let e = 0.5 * (aabb.max_corner - aabb.min_corner);
    let t = o.center - c;
    var a = array(o.axis_x, o.axis_y, o.axis_z);
    for (var k = 0u; k < 3u; k += 1u) {
        var unit_axis = vec3(0.0);
        unit_axis[k] = 1.0;
        if separates(unit_axis, t, e, o) || separates(a[k], t, e, o) {
            return false;
        }
    }
    for (var i = 0u; i < 3u; i += 1u) {
        let v = a[i];
        // unit_x × v, unit_y × v, unit_z × v.
        if separates(vec3(0.0, -v.z, v.y), t, e, o)
            || separates(vec3(v.z, 0.0, -v.x), t, e, o)
            || separates(vec3(-v.y, v.x, 0.0), t, e, o) {
            return false;
        }
    }
    return true;
}

// True when the spot's cone may touch the sphere: the centre's distance to the cone's
// side, its cap and its apex (exact along the side, conservative near the cap).
// Half-angles up to 90 degrees.
fn cone_touches_sphere(o: ViewObject, center: vec3<f32>, radius: f32) -> bool {
    let v = center - o.center;
    let along = v.x * o.axis_z.x + v.y * o.axis_z.y + v.z * o.axis_z.z;
    let across = sqrt(max(v.x * v.x + v.y * v.y + v.z * v.z - along * along, 0.0));
    let to_side = o.cos_angle * across - o.sin_angle * along;
    return !(to_side > radius || along > o.range + radius || along < -radius);
}

// The froxel test: may the object affect the froxel whose view-space box is `aabb`?
fn object_touches_froxel(o: ViewObject, aabb: Aabb) -> bool {
    if is_box(o) {
        return box_touches_aabb(o, aabb);
    }
    if !sphere_touches_aabb(o.center, o.range, aabb) {
        return false;
    }
    if o.kind == CLUSTERABLE_SPOT_LIGHT {
        let center = 0.5 * (aabb.min_corner + aabb.max_corner);
        let h = 0.5 * (aabb.max_corner - aabb.min_corner);
        return cone_touches_sphere(o, center, sqrt(h.x * h.x + h.y * h.y + h.z * h.z));
    }
    return true;
}

// Clip-space corner `vertex` of the quad covering a tile rectangle on a viewport of
// `grid.dims.xy` pixels, one pixel per tile, drawn as a triangle strip. Vertices past the
// fourth repeat it (zero-area triangles), so draws of 4 or 6 vertices per quad both work;
// an empty rectangle collapses to a point.
fn froxel_quad_corner(grid: ClusterGrid, rect: TileRect, vertex: u32) -> vec4<f32> {
    if rect_is_empty(rect) {
        return vec4(2.0, 2.0, 0.5, 1.0);
    }
    let corner = min(vertex, 3u);
    let tile = vec2(
        select(rect.min_tile.x, rect.max_tile.x + 1u, (corner & 1u) != 0u),
        select(rect.min_tile.y, rect.max_tile.y + 1u, (corner & 2u) != 0u),
    );
    let uv = vec2<f32>(tile) / vec2<f32>(grid.dims.xy);
    return vec4(uv.x * 2.0 - 1.0, 1.0 - uv.y * 2.0, 0.5, 1.0);
}

// Tiles of a rectangle (0 when empty).
fn rect_tiles(rect: TileRect) -> u32 {
    if rect_is_empty(rect) {
        return 0u;
    }
    return (rect.max_tile.x - rect.min_tile.x + 1u) * (rect.max_tile.y - rect.min_tile.y + 1u);
}

// The rectangle's tile number `index`, row by row.
fn rect_tile(rect: TileRect, index: u32) -> vec2<u32> {
    let width = rect.max_tile.x - rect.min_tile.x + 1u;
    return rect.min_tile + vec2(index % width, index / width);
}

// The compute walks share a workgroup's lanes out over the tiles of all its instances,
// not a workgroup per instance: most rectangles hold a tile or two, and a workgroup per
// instance left most lanes idle. A workgroup takes `walk_share` instances a round: the
// instances written shared out over the grid (or WALK_SPREAD workgroups of it), so a
// short list spreads over many workgroups (a few tiles per lane), but at most
// WALK_GROUP, so a direct dispatch of a
// fixed size walks a long list in rounds (`walk_rounds`), each striding over the list by
// the whole grid's share. A prefix sum of the tile counts lays the round's tiles out in
// one run, and each lane walks every WALK_GROUP-th tile of it, finding the tile's
// instance by binary search.
const WALK_GROUP: u32 = 64u;

// Per lane: its instance's (object, slice) and tile rectangle.
var<workgroup> walk_items: array<vec2<u32>, 64>;
var<workgroup> walk_rects: array<TileRect, 64>;
// walk_starts[k]: where lane k's tiles start in the run; [WALK_GROUP]: the total.
var<workgroup> walk_starts: array<u32, 65>;

// Workgroups a list is spread over before each takes more than its share, about one per
// SM of an H100 or H200 (132): on the H200, 63 workgroups of one or two instances
// (1,000 lights) beat two of 64, but the list of 100,000 lights (over 9,000 instances) was
// slower spread a few per workgroup over thousands than 64 each in a few hundred.
const WALK_SPREAD: u32 = 128u;

// Instances each workgroup of the grid `groups` takes a round: `written` shared out over
// the workgroups, or over WALK_SPREAD of them when the grid is larger; 1 ..= WALK_GROUP.
fn walk_share(groups: vec3<u32>, written: u32) -> u32 {
    let n = min(groups.x * groups.y, WALK_SPREAD);
    return clamp(written / n + select(0u, 1u, written % n != 0u), 1u, WALK_GROUP);
}

// Rounds the grid `groups` takes to walk `written` instances (the same in every
// workgroup: the loop around `walk_layout` stays uniform).
fn walk_rounds(groups: vec3<u32>, written: u32) -> u32 {
    let per_round = groups.x * groups.y * walk_share(groups, written);
    return written / per_round + select(0u, 1u, written % per_round != 0u);
}

// The instance lane `t` takes in round `round`, or `written` when it takes none.
fn walk_instance(wg: vec3<u32>, groups: vec3<u32>, round: u32, t: u32, written: u32) -> u32 {
    let share = walk_share(groups, written);
    let group = wg.y * groups.x + wg.x;
    let first = (round * groups.x * groups.y + group) * share;
    if t < share && first < written && t < written - first {
        return first + t;
    }
    return written;
}

// Lays the workgroup's tiles out: lane `t` brings its instance's (object, slice) and
// rectangle (an empty one when it has none). Returns the tiles of the run. Every lane of
// the workgroup calls it, once a round.
fn walk_layout(t: u32, object: u32, slice: u32, rect: TileRect) -> u32 {
    // Every lane has finished the previous round's tiles before they are replaced.
    workgroupBarrier();
    walk_items[t] = vec2(object, slice);
    walk_rects[t] = rect;
    if t == 0u {
        walk_starts[0] = 0u;
    }
    walk_starts[t + 1u] = rect_tiles(rect);
    workgroupBarrier();
    // Inclusive Hillis–Steele sums over walk_starts[1..=WALK_GROUP].
    for (var d = 1u; d < WALK_GROUP; d <<= 1u) {
        var add = 0u;
        if t >= d {
            add = walk_starts[t + 1u - d];
        }
        workgroupBarrier();
        walk_starts[t + 1u] += add;
        workgroupBarrier();
    }
    return walk_starts[WALK_GROUP];
}

// The run's tile `i`: its lane's (object, slice) and the tile.
struct WalkTile {
    object: u32,
    slice: u32,
    tile: vec2<u32>,
}

fn walk_tile(i: u32) -> WalkTile {
    // The last lane k with walk_starts[k] <= i.
    var lo = 0u;
    var hi = WALK_GROUP;
    while hi - lo > 1u {
        let mid = (lo + hi) / 2u;
        if walk_starts[mid] <= i {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    let item = walk_items[lo];
    return WalkTile(item.x, item.y, rect_tile(walk_rects[lo], i - walk_starts[lo]));
}
