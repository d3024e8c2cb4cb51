//! The cluster-grid arithmetic and intersection tests of `meshlight::light`, for the CPU
//! reference of light clustering. Same operations in the same order as the WGSL; the
//! GPU's `log2`/`exp2` are not correctly rounded, so compare slices away from boundaries
//! or allow one slice of slack there.

use super::layout::ClusterGrid;

/// `z_slice_of_depth`: the depth slice of a positive view-space distance, clamped.
pub fn z_slice_of_depth(grid: &ClusterGrid, view_z: f32) -> u32 {
    let slice = (view_z.max(grid.near).log2() * grid.z_slice_scale + grid.z_slice_bias).floor();
    (slice.max(0.0) as u32).min(grid.dims[2] - 1)
}

/// `z_slice_start`: where slice `slice` begins; `dims.z` gives `far`.
pub fn z_slice_start(grid: &ClusterGrid, slice: u32) -> f32 {
    if slice == 0 {
        grid.near
    } else if slice >= grid.dims[2] {
        grid.far
    } else {
        ((slice as f32 - grid.z_slice_bias) / grid.z_slice_scale).exp2()
    }
}

/// `cluster_index`: x fastest, then y, then z.
pub fn cluster_index(grid: &ClusterGrid, cluster: [u32; 3]) -> u32 {
    (cluster[2] * grid.dims[1] + cluster[1]) * grid.dims[0] + cluster[0]
}

/// `sphere_intersects_aabb`.
pub fn sphere_intersects_aabb(center: [f32; 3], radius: f32, min: [f32; 3], max: [f32; 3]) -> bool {
    let d: [f32; 3] = std::array::from_fn(|i| center[i] - center[i].clamp(min[i], max[i]));
    d[0] * d[0] + d[1] * d[1] + d[2] * d[2] <= radius * radius
}

/// `cone_intersects_sphere`: apex, unit axis, length, half-angle as cos/sin.
pub fn cone_intersects_sphere(
    apex: [f32; 3],
    axis: [f32; 3],
    cone_length: f32,
    cos_angle: f32,
    sin_angle: f32,
    center: [f32; 3],
    radius: f32,
) -> bool {
    let v: [f32; 3] = std::array::from_fn(|i| center[i] - apex[i]);
    let along = v[0] * axis[0] + v[1] * axis[1] + v[2] * axis[2];
    let across = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2] - along * along)
        .max(0.0)
        .sqrt();
    let to_side = cos_angle * across - sin_angle * along;
    !(to_side > radius || along > cone_length + radius || along < -radius)
}
