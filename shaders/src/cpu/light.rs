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
