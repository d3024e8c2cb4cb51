//! The on-disk and in-memory layout of a meshlet asset. Every record is `#[repr(C)]`
//! plain old data of 4-byte fields, so a loaded file is used in place through bytemuck
//! casts and uploaded to the GPU as is.
//!
//! File = [`AssetHeader`] then six sections, each a whole number of 32-bit words:
//! meshlets ([`MeshletRecord`]), groups ([`GroupRecord`]), group children (`u32`
//! meshlet ids), the payload (`u32` words of packed vertex and index data), the culling
//! hierarchy's nodes ([`NodeRecord`]) and its cluster list (`u32` meshlet ids, every
//! meshlet once, in the order the hierarchy's leaves take them; see
//! [`crate::hierarchy`]).
//!
//! A meshlet's payload is three blocks of fixed-width records (see [`PayloadLayout`]),
//! so that a GPU thread per vertex or per triangle finds its record by multiplying:
//! - vertices: grid offsets from `grid_min` at the meshlet's bits per axis, then the
//!   two octahedral normal components (of [`crate::compress::NORMAL_BITS`]) as offsets
//!   from the meshlet's smallest components at its normal bits (both in
//!   [`MeshletRecord::normals`]). A meshlet is a small patch whose
//!   normals span a fraction of the sphere, so this takes 19 to 23 bits on the test
//!   meshes (the smoother the surface, the fewer) where the full components took 24;
//! - UVs (when the asset has them): 2 × 16-bit unorm per vertex, one word;
//! - triangles: fixed-width records of about 16 bits, see [`super::triangles`].

use bytemuck::{Pod, Zeroable};

pub const MAGIC: [u8; 8] = *b"MLASSET\0";
/// Bumped on any layout change; older files are refused, not misread. 4: the culling
/// hierarchy (`node_count`, two more sections).
pub const VERSION: u32 = 4;

/// Header flag: each meshlet's payload holds UVs after its vertex records.
pub const FLAG_UVS: u32 = 1;

/// Section order in [`AssetHeader::sections`].
pub const SECTION_MESHLETS: usize = 0;
pub const SECTION_GROUPS: usize = 1;
pub const SECTION_CHILDREN: usize = 2;
pub const SECTION_PAYLOAD: usize = 3;
pub const SECTION_NODES: usize = 4;
pub const SECTION_NODE_CLUSTERS: usize = 5;
pub const SECTION_COUNT: usize = 6;

/// Where a section lies, in 32-bit words from the start of the file.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Eq, Pod, Zeroable)]
pub struct Section {
    pub offset: u32,
    pub words: u32,
}

#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Pod, Zeroable)]
pub struct AssetHeader {
    pub magic: [u8; 8],
    pub version: u32,
    pub flags: u32,
    /// Whole file size in bytes, low and high halves (the header stays 4-byte aligned).
    pub file_size: [u32; 2],
    /// Checksum of every byte after the header, low and high halves.
    pub checksum: [u32; 2],
    pub meshlet_count: u32,
    pub group_count: u32,
    /// Nodes of the culling hierarchy (at least one: the root).
    pub node_count: u32,
    pub level_count: u32,
    pub root_count: u32,
    pub lod0_meshlets: u32,
    pub lod0_triangles: u32,
    pub total_triangles: u32,
    pub total_vertices: u32,
    pub input_vertices: u32,
    pub dropped_degenerate: u32,
    pub bounds_min: [f32; 3],
    pub bounds_max: [f32; 3],
    /// Position grid: `position = quant_origin + quant_step * q`.
    pub quant_origin: [f32; 3],
    pub quant_step: f32,
    pub quant_bits: u32,
    pub uv_min: [f32; 2],
    pub uv_step: [f32; 2],
    pub sections: [Section; SECTION_COUNT],
}

impl AssetHeader {
    pub const WORDS: usize = size_of::<AssetHeader>() / 4;

    pub fn has_uvs(&self) -> bool {
        self.flags & FLAG_UVS != 0
    }
}

/// Most vertices per meshlet: local indices are `u8`, and 255 leaves 255 free as a
/// sentinel for the GPU.
pub const MAX_MESHLET_VERTICES: usize = 255;
/// Most triangles per meshlet: one workgroup of 128 threads rasterises one meshlet.
pub const MAX_MESHLET_TRIANGLES: usize = 128;

/// Marks "no group" in [`MeshletRecord::source_group`] and
/// [`MeshletRecord::parent_group`].
pub const NO_GROUP: u32 = u32::MAX;

/// One meshlet: what culling, LOD selection and rasterisation need, 52 bytes.
///
/// A meshlet is drawn when its own LOD error projected from its own LOD sphere is
/// imperceptible and its parent's is not. Both are the spheres and errors of groups
/// ([`GroupRecord`]), shared by the eight or so meshlets of a group, so the record
/// refers to them rather than holding copies: 32 bytes less per meshlet, half a byte
/// per LOD-0 triangle.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Pod, Zeroable)]
pub struct MeshletRecord {
    /// Sphere around the decoded vertices (centre, radius), for culling; also the own
    /// LOD sphere of a LOD-0 meshlet.
    pub bounds: [f32; 4],
    /// The group whose simplification produced this meshlet: its LOD sphere and error
    /// are this meshlet's own. [`NO_GROUP`] at LOD 0 (error 0, sphere = `bounds`).
    pub source_group: u32,
    /// The group this meshlet was simplified in: its LOD sphere and error are this
    /// meshlet's parent's. [`NO_GROUP`] for roots, which are drawn whenever nothing
    /// finer is (an infinite parent error).
    pub parent_group: u32,
    /// First payload word, relative to the payload section.
    pub data_offset: u32,
    /// vertex count (bits 0..8), triangle count (8..16), level (16..24).
    pub counts: u32,
    /// Per-meshlet minimum of the grid coordinates; packed values are offsets from it.
    pub grid_min: [u32; 3],
    /// Bits per packed axis: x (0..8), y (8..16), z (16..24); then the widths of the
    /// triangle records' fields: corner offset (24..28), corner deltas (28..32).
    pub bits: u32,
    /// Smallest octahedral normal components of the meshlet, biased by
    /// [`NORMAL_BIAS`] to be unsigned: x (0..12), y (12..24); then the bits of each
    /// component's offset: x (24..28), y (28..32).
    pub normals: u32,
}

/// Added to a signed octahedral component to store it unsigned in 12 bits.
pub const NORMAL_BIAS: i32 = 1 << (crate::compress::NORMAL_BITS - 1);

impl MeshletRecord {
    pub fn vertex_count(&self) -> u32 {
        self.counts & 0xff
    }
    pub fn triangle_count(&self) -> u32 {
        (self.counts >> 8) & 0xff
    }
    pub fn level(&self) -> u32 {
        (self.counts >> 16) & 0xff
    }
    pub fn axis_bits(&self) -> [u32; 3] {
        [
            self.bits & 0xff,
            (self.bits >> 8) & 0xff,
            (self.bits >> 16) & 0xff,
        ]
    }
    /// Field widths of the triangle records (see [`super::triangles`]).
    pub fn triangle_bits(&self) -> super::triangles::TriangleBits {
        super::triangles::TriangleBits {
            offset: (self.bits >> 24) & 0xf,
            delta: self.bits >> 28,
        }
    }
    /// Smallest signed octahedral components of the meshlet's normals.
    pub fn normal_min(&self) -> [i32; 2] {
        [
            (self.normals & 0xfff) as i32 - NORMAL_BIAS,
            ((self.normals >> 12) & 0xfff) as i32 - NORMAL_BIAS,
        ]
    }
    /// Bits of each octahedral component's offset from [`Self::normal_min`].
    pub fn normal_bits(&self) -> [u32; 2] {
        [(self.normals >> 24) & 0xf, self.normals >> 28]
    }
    /// Bits of one vertex record: position offsets and normal offsets.
    pub fn vertex_stride(&self) -> u32 {
        let [x, y, z] = self.axis_bits();
        let [nx, ny] = self.normal_bits();
        x + y + z + nx + ny
    }
    /// Bits of one triangle record.
    pub fn triangle_stride(&self) -> u32 {
        self.triangle_bits().stride()
    }
}

/// One simplification group: for checking the DAG, and the leaves of the culling
/// hierarchy (a leaf holds the meshlets simplified in one group).
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Pod, Zeroable)]
pub struct GroupRecord {
    pub lod_sphere: [f32; 4],
    pub error: f32,
    pub level: u32,
    /// Range in the children section.
    pub first_child: u32,
    pub child_count: u32,
}

/// Payload layout of one meshlet, in words from its `data_offset`: vertex records,
/// UVs (when the asset has them), triangle records.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct PayloadLayout {
    pub vertices: u32,
    pub uvs: u32,
    pub triangles: u32,
    pub end: u32,
}

impl PayloadLayout {
    pub fn of(record: &MeshletRecord, has_uvs: bool) -> Self {
        let vc = record.vertex_count();
        let vertices = 0;
        let uvs = (vc * record.vertex_stride()).div_ceil(32);
        let triangles = uvs + if has_uvs { vc } else { 0 };
        let end = triangles + (record.triangle_count() * record.triangle_stride()).div_ceil(32);
        Self {
            vertices,
            uvs,
            triangles,
            end,
        }
    }
}

/// `max_parent_error` of a node with a root meshlet below: roots have no parent, so
/// their parent error is infinite (the shaders' `F32_MAX`), and such a node is never
/// too fine to visit.
pub const ROOT_PARENT_ERROR: f32 = f32::MAX;

/// One node of the culling hierarchy, 64 bytes (the WGSL struct's size, so the section
/// is uploaded as it is). A node bounds every meshlet below it, so that one test can
/// reject them all; see [`crate::hierarchy`] for why each field makes that test
/// conservative.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Pod, Zeroable)]
pub struct NodeRecord {
    /// Encloses the culling spheres ([`MeshletRecord::bounds`]) of every meshlet below:
    /// outside the frustum, none of them is in it.
    pub bounds: [f32; 4],
    /// Encloses the own and parent LOD spheres of every meshlet below, so that its
    /// distance from the camera bounds theirs from both sides.
    pub lod_sphere: [f32; 4],
    /// Smallest own error of a meshlet below (0 when a LOD-0 meshlet is below).
    pub min_error: f32,
    /// Largest parent error of a meshlet below; [`ROOT_PARENT_ERROR`] with a root below.
    pub max_parent_error: f32,
    /// Internal nodes: the children are nodes `first_child .. first_child + child_count`
    /// of the same mesh, all after this one. Leaves: `child_count` = 0, `first_child` = 0.
    pub first_child: u32,
    pub child_count: u32,
    /// The meshlets below, as a range of the cluster list: a leaf's own, an internal
    /// node's the concatenation of its children's (the list is in depth-first order).
    pub first_cluster: u32,
    pub cluster_count: u32,
    /// Zero.
    pub reserved: [u32; 2],
}

impl NodeRecord {
    pub fn is_leaf(&self) -> bool {
        self.child_count == 0
    }
    pub fn children(&self) -> std::ops::Range<usize> {
        self.first_child as usize..self.first_child as usize + self.child_count as usize
    }
    pub fn clusters(&self) -> std::ops::Range<usize> {
        self.first_cluster as usize..self.first_cluster as usize + self.cluster_count as usize
    }
}
