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
