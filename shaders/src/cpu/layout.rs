//! Rust mirrors of the shared WGSL structs, for uploading with bytemuck.
//!
//! Every field has the offset naga computes for the WGSL struct of the same name; a test
//! in `tests/layout.rs` compares them, so a change on one side fails until the other
//! follows. Matrices are column-major `[[f32; 4]; 4]` (glam's `Mat4::to_cols_array_2d`).

use bytemuck::{Pod, Zeroable};

/// `meshlight::view::View`; see the WGSL for what each field means.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct View {
    pub view: [[f32; 4]; 4],
    pub projection: [[f32; 4]; 4],
    pub view_projection: [[f32; 4]; 4],
    pub inverse_view: [[f32; 4]; 4],
    pub inverse_projection: [[f32; 4]; 4],
    pub inverse_view_projection: [[f32; 4]; 4],
    pub previous_view_projection: [[f32; 4]; 4],
    /// Left, right, bottom, top, near, far; inside when `dot(xyz, p) + w >= 0`.
    pub frustum: [[f32; 4]; 6],
    pub camera_position: [f32; 3],
    pub near: f32,
    pub viewport_size: [f32; 2],
    pub inverse_viewport_size: [f32; 2],
    /// `0.5 * projection[1][1] * viewport height`.
    pub lod_scale: f32,
    pub frame_index: u32,
    pub padding: [u32; 2],
}

/// `meshlight::meshlet::Mesh`: one loaded mesh asset in the GPU scene.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct Mesh {
    /// xyz origin, w step: `position = origin + step * q`.
    pub position_grid: [f32; 4],
    /// xy minimum, zw step of the 16-bit UV values.
    pub uv_grid: [f32; 4],
    /// Mesh-space sphere around the whole mesh: centre, radius.
    pub bounding_sphere: [f32; 4],
    pub first_meshlet: u32,
    pub meshlet_count: u32,
    /// `MESH_FLAG_UVS` (1) when the payload holds UVs.
    pub flags: u32,
    pub level_count: u32,
}

/// `MESH_FLAG_UVS` of [`Mesh::flags`].
pub const MESH_FLAG_UVS: u32 = 1;

/// `meshlight::meshlet::Cluster`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Pod, Zeroable)]
pub struct Cluster {
    pub instance: u32,
    pub meshlet: u32,
}

/// `meshlight::instance::Instance`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct Instance {
    pub world_from_local: [[f32; 4]; 4],
    pub previous_world_from_local: [[f32; 4]; 4],
    pub local_from_world: [[f32; 4]; 4],
    /// xyz origin, w step: the mesh's [`Mesh::position_grid`].
    pub position_grid: [f32; 4],
    pub material: u32,
    pub first_meshlet: u32,
    pub meshlet_count: u32,
    /// Index into the mesh table.
    pub mesh: u32,
}

/// `meshlight::instance::Material`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct Material {
    /// Linear RGB albedo; alpha unused.
    pub base_color: [f32; 4],
}

/// The `kind` values of [`ClusterableObject`], as the `CLUSTERABLE_*` WGSL constants.
#[repr(u32)]
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum ClusterableKind {
    PointLight = 0,
    SpotLight = 1,
    Probe = 2,
    Decal = 3,
}

impl ClusterableKind {
    /// How many kinds there are (`CLUSTERABLE_TYPE_COUNT`).
    pub const COUNT: u32 = 4;
}

/// `meshlight::light::ClusterableObject`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct ClusterableObject {
    pub position_range: [f32; 4],
    pub direction_cos_angle: [f32; 4],
    pub color_intensity: [f32; 4],
    /// A [`ClusterableKind`] as u32.
    pub kind: u32,
    pub sin_angle: f32,
    pub payload: u32,
    pub padding: u32,
}

/// `meshlight::light::ClusterGrid`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct ClusterGrid {
    pub dims: [u32; 3],
    pub cluster_count: u32,
    pub tile_size: [f32; 2],
    pub near: f32,
    pub far: f32,
    pub z_slice_scale: f32,
    pub z_slice_bias: f32,
    pub padding: [u32; 2],
}

impl ClusterGrid {
    /// A grid of `dims` clusters over a `viewport` of pixels, slices spaced
    /// logarithmically from `near` to `far` (both positive, `far > near`).
    pub fn new(dims: [u32; 3], viewport: [u32; 2], near: f32, far: f32) -> Self {
        assert!(
            dims.iter().all(|&d| d > 0),
            "cluster grid dims must be non-zero: {dims:?}"
        );
        assert!(
            near > 0.0 && far > near,
            "cluster grid needs 0 < near < far, got {near}..{far}"
        );
        let z_slice_scale = dims[2] as f32 / (far / near).log2();
        Self {
            dims,
            cluster_count: dims[0] * dims[1] * dims[2],
            tile_size: [
                viewport[0].div_ceil(dims[0]) as f32,
                viewport[1].div_ceil(dims[1]) as f32,
            ],
            near,
            far,
            z_slice_scale,
            z_slice_bias: -near.log2() * z_slice_scale,
            padding: [0; 2],
        }
    }
}
