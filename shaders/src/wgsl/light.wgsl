#define_import_path meshlight::light

// Clusterable objects (point and spot lights, probes, decals) and the froxel grid they
// are assigned to. The view frustum is split into dims.x × dims.y screen tiles and
// dims.z depth slices spaced logarithmically between `near` and `far`, so every slice
// has about the same aspect ratio. Layouts match `cpu::layout`.

#import meshlight::view::View

const CLUSTERABLE_POINT_LIGHT: u32 = 0u;
const CLUSTERABLE_SPOT_LIGHT: u32 = 1u;
const CLUSTERABLE_PROBE: u32 = 2u;
const CLUSTERABLE_DECAL: u32 = 3u;
// Per-cluster counts are kept per type, so lists can be walked one type at a time.
const CLUSTERABLE_TYPE_COUNT: u32 = 4u;

struct ClusterableObject {
    // xyz world-space position; w range: the object affects nothing farther away.
    position_range: vec4<f32>,
    // xyz world-space unit direction (spot axis, decal projection); w cosine of the
    // spot's outer half-angle (unused for other types).
    direction_cos_angle: vec4<f32>,
    // rgb linear colour, w intensity (lights); probes and decals leave it to `payload`.
    color_intensity: vec4<f32>,
    // One of the CLUSTERABLE_* constants.
    kind: u32,
    // Sine of the spot's outer half-angle, precomputed for the cone test.
    sin_angle: f32,
    // Index into the probe or decal table of the pass that shades with it.
    payload: u32,
    // Padding to a 16-byte multiple.
    padding: u32,
}

struct ClusterGrid {
    // Clusters along x (tile columns), y (tile rows) and z (depth slices).
    dims: vec3<u32>,
    // dims.x * dims.y * dims.z.
    cluster_count: u32,
    // One tile's size in pixels (viewport size / dims.xy, rounded up).
    tile_size: vec2<f32>,
    // View-space distance where slice 0 begins; nearer depths are clamped into it.
    near: f32,
    // View-space distance where the last slice ends; farther depths are clamped into it.
    far: f32,
    // dims.z / log2(far / near): slices per doubling of distance.
    z_slice_scale: f32,
    // -log2(near) * z_slice_scale, so slice = floor(log2(z) * scale + bias).
    z_slice_bias: f32,
    // Padding to a 16-byte multiple.
    padding: vec2<u32>,
}

struct Aabb {
    // Minimum corner.
    min_corner: vec3<f32>,
    // Maximum corner.
    max_corner: vec3<f32>,
}

// The depth slice of a positive view-space distance, clamped to the grid.
fn z_slice_of_depth(grid: ClusterGrid, view_z: f32) -> u32 {
    let slice = floor(log2(max(view_z, grid.near)) * grid.z_slice_scale + grid.z_slice_bias);
    return min(u32(max(slice, 0.0)), grid.dims.z - 1u);
}

// View-space distance where slice `slice` begins (slice = dims.z gives `far`).
fn z_slice_start(grid: ClusterGrid, slice: u32) -> f32 {
    if slice == 0u {
        return grid.near;
    }
    if slice >= grid.dims.z {
        return grid.far;
    }
    return exp2((f32(slice) - grid.z_slice_bias) / grid.z_slice_scale);
}

// Linear index of cluster (x, y, z): x fastest, then y, then z.
fn cluster_index(grid: ClusterGrid, cluster: vec3<u32>) -> u32 {
    return (cluster.z * grid.dims.y + cluster.y) * grid.dims.x + cluster.x;
}

// The cluster of a pixel (coordinates in pixels) at a positive view-space distance.
fn cluster_of_pixel(grid: ClusterGrid, pixel: vec2<f32>, view_z: f32) -> vec3<u32> {
    let tile = min(vec2<u32>(max(pixel / grid.tile_size, vec2(0.0))), grid.dims.xy - vec2(1u));
    return vec3(tile, z_slice_of_depth(grid, view_z));
}

// The view-space point at distance `view_z` in front of the camera on the ray through
// pixel `pixel`. Perspective projections only.
fn view_point_at_depth(view: View, pixel: vec2<f32>, view_z: f32) -> vec3<f32> {
    let uv = pixel * view.inverse_viewport_size;
    let ndc = uv * vec2(2.0, -2.0) + vec2(-1.0, 1.0);
    // Any depth works for the direction; 1 is the near plane under reverse-Z.
    let p = view.inverse_projection * vec4(ndc, 1.0, 1.0);
    let ray = p.xyz / p.w;
    return ray * (view_z / -ray.z);
}

// The view-space bounding box of cluster (x, y, z): the tile's four corner rays cut at
// the slice's start and end distances.
fn cluster_aabb(view: View, grid: ClusterGrid, cluster: vec3<u32>) -> Aabb {
    let tile_min = vec2<f32>(cluster.xy) * grid.tile_size;
    let tile_max = min(tile_min + grid.tile_size, view.viewport_size);
    let z0 = z_slice_start(grid, cluster.z);
    let z1 = z_slice_start(grid, cluster.z + 1u);
    var lo = vec3(3.4e38);
    var hi = vec3(-3.4e38);
    for (var corner = 0u; corner < 8u; corner += 1u) {
        let pixel = vec2(
            select(tile_min.x, tile_max.x, (corner & 1u) != 0u),
            select(tile_min.y, tile_max.y, (corner & 2u) != 0u),
        );
        let p = view_point_at_depth(view, pixel, select(z0, z1, (corner & 4u) != 0u));
        lo = min(lo, p);
        hi = max(hi, p);
    }
    return Aabb(lo, hi);
}

// True when the sphere touches the box.
fn sphere_intersects_aabb(center: vec3<f32>, radius: f32, aabb: Aabb) -> bool {
    let d = center - clamp(center, aabb.min_corner, aabb.max_corner);
    return dot(d, d) <= radius * radius;
}

// True when the cone (apex, unit axis, length, half-angle as cos/sin) may touch the
// sphere. Measures the sphere centre's distance to the cone's side; conservative near
// the cap, exact along the side. Half-angles up to 90 degrees.
fn cone_intersects_sphere(
    apex: vec3<f32>,
    axis: vec3<f32>,
    cone_length: f32,
    cos_angle: f32,
    sin_angle: f32,
    center: vec3<f32>,
    radius: f32,
) -> bool {
    let v = center - apex;
    let along = dot(v, axis);
    let across = sqrt(max(dot(v, v) - along * along, 0.0));
    // Signed distance from the centre to the cone's side (positive outside).
    let to_side = cos_angle * across - sin_angle * along;
    let outside_side = to_side > radius;
    let beyond_cap = along > cone_length + radius;
    let behind_apex = along < -radius;
    return !(outside_side || beyond_cap || behind_apex);
}

// True when the object may affect the cluster whose view-space box is `aabb`.
fn clusterable_intersects_cluster(view: View, object: ClusterableObject, aabb: Aabb) -> bool {
    let center = (view.view * vec4(object.position_range.xyz, 1.0)).xyz;
    let range = object.position_range.w;
    if !sphere_intersects_aabb(center, range, aabb) {
        return false;
    }
    if object.kind == CLUSTERABLE_SPOT_LIGHT {
        let axis = normalize((view.view * vec4(object.direction_cos_angle.xyz, 0.0)).xyz);
        let box_center = 0.5 * (aabb.min_corner + aabb.max_corner);
        let box_radius = 0.5 * length(aabb.max_corner - aabb.min_corner);
        return cone_intersects_sphere(
            center, axis, range, object.direction_cos_angle.w, object.sin_angle,
            box_center, box_radius);
    }
    return true;
}
