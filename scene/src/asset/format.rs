//! The on-disk and in-memory layout of a meshlet asset. Every record is `#[repr(C)]`
//! plain old data of 4-byte fields, so a loaded file is used in place through bytemuck
//! casts and uploaded to the GPU as is.
//!
//! File = [`AssetHeader`] then eight sections, each a whole number of 32-bit words:
//! meshlets ([`MeshletRecord`]), groups ([`GroupRecord`]), group children (`u32`
//! meshlet ids), the culling hierarchy's nodes ([`NodeRecord`]) and its cluster list
//! (`u32` meshlet ids, every meshlet once, in the order the hierarchy's leaves take
//! them; see [`crate::hierarchy`]), the pages ([`PageRecord`]), LOD 0's open edges as
//! baked ([`OpenEdgeRecord`]), and last the payload (`u32` words of packed vertex and
//! index data).
//!
//! **Pages.** The file is laid out so that a renderer can stream it: meshlets are stored
//! page by page, the roots first, then each group's children in group order, and their
//! payload in the same order. So everything but the pages' payload (the *resident
//! part*: records, hierarchy, the roots' payload) is one prefix of the file, and each
//! group's children's payload (its page, see `meshlight-stream`) is one range after it,
//! with its own checksum ([`PageRecord::checksum`]). The header's checksum covers the
//! resident part only, so a streamed file is checked without reading its pages, and
//! each page as it is read.
//!
//! A meshlet's payload is three blocks of fixed-width records (see [`PayloadLayout`]),
//! so that a GPU thread per vertex or per triangle finds its record by multiplying:
//! - vertices: grid offsets from `grid_min` at the meshlet's bits per axis, then the
//!   two octahedral normal components (of [`crate::compress::NORMAL_BITS`]) as offsets
//!   from the meshlet's smallest components at its normal bits (both in
//!   [`MeshletRecord::normals`]). A meshlet is a small patch whose
//!   normals span a fraction of the sphere, so this takes 19 to 23 bits on the test
//!   meshes (the smoother the surface, the fewer) where the full components took 24;
//! - triangles: fixed-width records of about 16 bits, see [`super::triangles`];
//! - UVs (when the asset has them): the meshlet's origin on the mesh's UV grid, then
//!   each vertex's offsets from it at the meshlet's bits per component (in
//!   [`MeshletRecord::bits`]; see [`crate::compress::UvQuantization`]);
//! - vertex colours (when the asset has them): one word per vertex, sRGB RGB and
//!   linear alpha at 8 bits each ([`crate::compress::encode_color`]).

use bytemuck::{Pod, Zeroable};

/// The first eight bytes of every asset, so that a mesh file or anything else given
/// by mistake is named as such instead of failing a later check.
pub const MAGIC: [u8; 8] = *b"MLASSET\0";
/// Bumped on any layout change; older files are refused, not misread. 4: the culling
/// hierarchy (`node_count`, two more sections). 5: material slots
/// ([`AssetHeader::material_count`], [`MeshletRecord::material`]). 6: UVs as per-meshlet
/// origins on a finer mesh-wide grid ([`UV_ORIGIN_WORDS`]). 7: UV offsets bit-packed at
/// the meshlet's bits per component, the UV block after the triangles; vertex colours
/// ([`FLAG_COLORS`]). 8: pages: meshlets and payload stored page by page, the payload
/// last, a page section with a checksum per page, the header's checksum over the
/// resident part ([`AssetHeader::resident_words`]). 9: LOD 0's open edges as baked
/// ([`SECTION_OPEN_EDGES`]), so that a load can tell a mesh that was open from one whose
/// meshlets were pulled apart since; the source's triangle counts
/// ([`AssetHeader::input_triangles`], [`AssetHeader::dropped_duplicate`]) and
/// [`AssetHeader::lod0_vertices`] in place of the cleaned mesh's vertex count, each
/// checkable against the meshlets.
pub const VERSION: u32 = 9;

/// Words at the start of a meshlet's UV block: its UV grid origin, one code per
/// component (see [`crate::compress::UvQuantization`]).
pub const UV_ORIGIN_WORDS: u32 = 2;

/// Header flag: each meshlet's payload holds UVs after its triangle records.
pub const FLAG_UVS: u32 = 1;
/// Header flag: each meshlet's payload ends with a colour word per vertex.
pub const FLAG_COLORS: u32 = 2;
/// Every header flag a reader knows.
pub const KNOWN_FLAGS: u32 = FLAG_UVS | FLAG_COLORS;

/// Section order in [`AssetHeader::sections`]: the meshlet records.
pub const SECTION_MESHLETS: usize = 0;
/// The group records.
pub const SECTION_GROUPS: usize = 1;
/// The meshlet ids of each group's children, which [`GroupRecord::first_child`] indexes.
pub const SECTION_CHILDREN: usize = 2;
/// The culling hierarchy's node records.
pub const SECTION_NODES: usize = 3;
/// The meshlet ids the hierarchy's leaves take, which [`NodeRecord::first_cluster`]
/// indexes.
pub const SECTION_NODE_CLUSTERS: usize = 4;
/// One [`PageRecord`] per group.
pub const SECTION_PAGES: usize = 5;
/// LOD 0's open edges as the bake packed them, one [`OpenEdgeRecord`] each (none for a
/// closed mesh); see [`crate::open_edges`].
pub const SECTION_OPEN_EDGES: usize = 6;
/// The packed vertex, UV and triangle words of every meshlet, the roots' first, then
/// page by page. Last, so that everything before the first page is one prefix.
pub const SECTION_PAYLOAD: usize = 7;
/// Sections in a file; the header holds one [`Section`] for each.
pub const SECTION_COUNT: usize = 8;

/// Where a section lies, in 32-bit words from the start of the file.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Eq, Pod, Zeroable)]
pub struct Section {
    /// First word of the section, from the start of the file (header included).
    pub offset: u32,
    /// Length of the section in words.
    pub words: u32,
}

/// The start of every asset: what a loader checks before it trusts the rest (magic,
/// version, size, checksum, where each section lies), the counts summaries report
/// without walking the records, and the grids positions and UVs are decoded on.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Pod, Zeroable)]
pub struct AssetHeader {
    /// [`MAGIC`].
    pub magic: [u8; 8],
    /// [`VERSION`] of the writer; a reader refuses any other.
    pub version: u32,
    /// [`FLAG_UVS`] and [`FLAG_COLORS`], or nothing.
    pub flags: u32,
    /// Whole file size in bytes, low and high halves (the header stays 4-byte aligned).
    pub file_size: [u32; 2],
    /// Checksum of the resident part after the header (every section before the
    /// payload, then the roots' payload), low and high halves; each page has its own.
    pub checksum: [u32; 2],
    /// Meshlet records, all levels.
    pub meshlet_count: u32,
    /// Group records: one per simplification step of the DAG.
    pub group_count: u32,
    /// Nodes of the culling hierarchy (at least one: the root).
    pub node_count: u32,
    /// Levels of the DAG, LOD 0 included.
    pub level_count: u32,
    /// Meshlets without a parent group, which a distant view draws.
    pub root_count: u32,
    /// Meshlets of LOD 0, the full-detail mesh.
    pub lod0_meshlets: u32,
    /// Triangles of LOD 0: the mesh's triangles after cleaning, what sizes and rates are
    /// quoted per.
    pub lod0_triangles: u32,
    /// Triangles of all levels.
    pub total_triangles: u32,
    /// Vertex records of all levels (a vertex is stored once per meshlet using it).
    pub total_vertices: u32,
    /// Distinct vertices LOD 0's triangles use (a position with its normal, UV and
    /// colour): at least the most any one LOD-0 meshlet holds, at most the LOD-0
    /// meshlets' vertex records together, which share the vertices on their borders.
    pub lod0_vertices: u32,
    /// Triangles of the source mesh as read: LOD 0's plus those the bake dropped.
    pub input_triangles: u32,
    /// Triangles the bake dropped as degenerate, so that a summary can say the asset
    /// has fewer triangles than the source for that reason.
    pub dropped_degenerate: u32,
    /// Triangles the bake dropped as repeating an earlier one's points and winding.
    pub dropped_duplicate: u32,
    /// Material slots of the mesh (at least 1): every meshlet's slot is below it, and
    /// whoever places the mesh gives a material for each.
    pub material_count: u32,
    /// Payload words of the roots, at the start of the payload: with every section
    /// before the payload, the resident part a streamed file is opened with, and what
    /// [`AssetHeader::checksum`] covers.
    pub resident_words: u32,
    /// Smallest corner of the mesh's bounding box.
    pub bounds_min: [f32; 3],
    /// Largest corner of the mesh's bounding box.
    pub bounds_max: [f32; 3],
    /// Position grid: `position = quant_origin + quant_step * q`.
    pub quant_origin: [f32; 3],
    /// Distance between neighbouring grid points (the same on every axis).
    pub quant_step: f32,
    /// Bits per axis of the grid: the largest grid coordinate is `2^quant_bits - 1`.
    pub quant_bits: u32,
    /// UV grid: `uv = uv_min + uv_step * (origin + offset)` per component, with a
    /// meshlet's origin and a vertex's offset (see [`crate::compress::UvQuantization`]).
    pub uv_min: [f32; 2],
    /// Distance between neighbouring UV grid points per component.
    pub uv_step: [f32; 2],
    /// Where each section lies, in the order of the `SECTION_*` constants.
    pub sections: [Section; SECTION_COUNT],
}

impl AssetHeader {
    /// Size of the header in 32-bit words: the sections start after it.
    pub const WORDS: usize = size_of::<AssetHeader>() / 4;

    /// Whether each meshlet's payload holds UVs ([`FLAG_UVS`]).
    pub fn has_uvs(&self) -> bool {
        self.flags & FLAG_UVS != 0
    }

    /// Whether each meshlet's payload holds vertex colours ([`FLAG_COLORS`]).
    pub fn has_colors(&self) -> bool {
        self.flags & FLAG_COLORS != 0
    }
}

/// Most vertices per meshlet: local indices are `u8`, and 255 leaves 255 free as a
/// sentinel for the GPU.
pub const MAX_MESHLET_VERTICES: usize = 255;
/// Most triangles per meshlet: one workgroup of 128 threads rasterises one meshlet.
pub const MAX_MESHLET_TRIANGLES: usize = 128;

/// Most material slots one mesh may use: a meshlet record keeps its slot in 8 bits
/// (see [`MeshletRecord::counts`]).
pub const MAX_MATERIALS: u32 = 256;

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
    /// vertex count (bits 0..8), triangle count (8..16), level (16..24), material slot
    /// (24..32): a meshlet's triangles all have one material.
    pub counts: u32,
    /// Per-meshlet minimum of the grid coordinates; packed values are offsets from it.
    pub grid_min: [u32; 3],
    /// Bits per packed axis: x (0..5), y (5..10), z (10..15); bits of the UV offsets
    /// less one (when the asset has UVs, else 0): u (15..19), v (19..23); bit 23 is 0;
    /// then the widths of the triangle records' fields: corner offset (24..28), corner
    /// deltas (28..32).
    pub bits: u32,
    /// Smallest octahedral normal components of the meshlet, biased by
    /// [`NORMAL_BIAS`] to be unsigned: x (0..12), y (12..24); then the bits of each
    /// component's offset: x (24..28), y (28..32).
    pub normals: u32,
}

/// Added to a signed octahedral component to store it unsigned in 12 bits.
pub const NORMAL_BIAS: i32 = 1 << (crate::compress::NORMAL_BITS - 1);

impl MeshletRecord {
    /// Vertices of the meshlet, from [`Self::counts`].
    pub fn vertex_count(&self) -> u32 {
        self.counts & 0xff
    }
    /// Triangles of the meshlet, from [`Self::counts`].
    pub fn triangle_count(&self) -> u32 {
        (self.counts >> 8) & 0xff
    }
    /// DAG level of the meshlet (0: full detail), from [`Self::counts`].
    pub fn level(&self) -> u32 {
        (self.counts >> 16) & 0xff
    }
    /// The material slot of the meshlet's triangles, from [`Self::counts`].
    pub fn material(&self) -> u32 {
        self.counts >> 24
    }
    /// Bits of each packed position offset (x, y, z), from [`Self::bits`].
    pub fn axis_bits(&self) -> [u32; 3] {
        [
            self.bits & 0x1f,
            (self.bits >> 5) & 0x1f,
            (self.bits >> 10) & 0x1f,
        ]
    }
    /// Bits of each vertex's UV offset (u, v), from [`Self::bits`]; meaningful only in
    /// an asset with UVs.
    pub fn uv_bits(&self) -> [u32; 2] {
        [((self.bits >> 15) & 0xf) + 1, ((self.bits >> 19) & 0xf) + 1]
    }
    /// [`Self::bits`] from its fields (`uv_bits` is `None` without UVs).
    pub fn pack_bits(
        axis: [u32; 3],
        uv_bits: Option<[u32; 2]>,
        triangles: super::triangles::TriangleBits,
    ) -> u32 {
        let uv = uv_bits.map_or(0, |b| ((b[0] - 1) << 15) | ((b[1] - 1) << 19));
        axis[0]
            | (axis[1] << 5)
            | (axis[2] << 10)
            | uv
            | (triangles.offset << 24)
            | (triangles.delta << 28)
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
    /// Sphere (centre, radius) enclosing the group's children's LOD spheres: the error
    /// is projected from it, so that a parent is never finer than a child from any
    /// viewpoint.
    pub lod_sphere: [f32; 4],
    /// Simplification error of the group's result, at least its children's, so that
    /// errors grow monotonically up the DAG and a cut is consistent.
    pub error: f32,
    /// The build iteration that formed the group: the meshlets it produced are one
    /// level above it (its children may be lower, when they were stuck before).
    pub level: u32,
    /// Range in the children section.
    pub first_child: u32,
    /// Meshlets simplified in the group.
    pub child_count: u32,
}

/// One edge of LOD 0's open boundary as baked: the grid points of its ends, and how
/// many more times LOD 0's triangles run along it from `from` to `to` than back. An
/// edge two triangles share the usual way cancels, so a closed mesh has none; the
/// mesh's own rim, holes and non-manifold edges are what is left. Records are in
/// ascending order of their ends' pair (the smaller grid point first), each pair once.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Eq, Pod, Zeroable)]
pub struct OpenEdgeRecord {
    /// Grid point the edge leaves.
    pub from: [u32; 3],
    /// Grid point the edge reaches (not `from`).
    pub to: [u32; 3],
    /// Net uses from `from` to `to` (at least 1).
    pub uses: u32,
}

impl OpenEdgeRecord {
    /// The ends in ascending order: the key records are sorted by.
    pub fn key(&self) -> ([u32; 3], [u32; 3]) {
        if self.from < self.to {
            (self.from, self.to)
        } else {
            (self.to, self.from)
        }
    }
}

/// One page: a group's children's payload, one range of the payload section. Pages
/// follow each other in group order after the roots' payload and fill the rest of it.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Eq, Pod, Zeroable)]
pub struct PageRecord {
    /// First word, relative to the payload section (the first child's `data_offset`).
    pub first_word: u32,
    /// Words of the page.
    pub words: u32,
    /// XXH3-64 of the page's bytes (`checksum::page_checksum`), low and high halves.
    pub checksum: [u32; 2],
}

impl PageRecord {
    /// The page's words as a range of the payload section.
    pub fn range(&self) -> std::ops::Range<usize> {
        self.first_word as usize..self.first_word as usize + self.words as usize
    }

    /// The checksum as one number.
    pub fn checksum(&self) -> u64 {
        u64::from(self.checksum[0]) | (u64::from(self.checksum[1]) << 32)
    }
}

/// Payload layout of one meshlet, in words from its `data_offset`: vertex records,
/// triangle records, then the UV block (when the asset has them: the meshlet's origin,
/// then the vertices' offsets), then the colour words (when it has them). UVs and
/// colours come last so that the rasterisers, which rarely read them, find the
/// triangles at the same place with or without.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct PayloadLayout {
    /// First word of the vertex records (always 0).
    pub vertices: u32,
    /// First word of the triangle records.
    pub triangles: u32,
    /// First word of the UV block, its origin (equal to `end` without UVs).
    pub uvs: u32,
    /// First word of the vertices' UV offsets, after the origin (equal to `colors`
    /// without UVs).
    pub uv_words: u32,
    /// First word of the colour words, one per vertex (equal to `end` without colours).
    pub colors: u32,
    /// One past the meshlet's last word.
    pub end: u32,
}

impl PayloadLayout {
    /// The layout of `record`'s payload in an asset (or GPU mesh) with header `flags`
    /// ([`FLAG_UVS`], [`FLAG_COLORS`]), from its counts and bit widths alone: the
    /// decoders and the validation find every block without reading the payload.
    pub fn of(record: &MeshletRecord, flags: u32) -> Self {
        let vc = record.vertex_count();
        let vertices = 0;
        let triangles = (vc * record.vertex_stride()).div_ceil(32);
        let uvs = triangles + (record.triangle_count() * record.triangle_stride()).div_ceil(32);
        let (uv_words, colors) = if flags & FLAG_UVS != 0 {
            let [u, v] = record.uv_bits();
            let uv_words = uvs + UV_ORIGIN_WORDS;
            (uv_words, uv_words + (vc * (u + v)).div_ceil(32))
        } else {
            (uvs, uvs)
        };
        let end = colors + if flags & FLAG_COLORS != 0 { vc } else { 0 };
        Self {
            vertices,
            triangles,
            uvs,
            uv_words,
            colors,
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
    /// Child nodes; 0 for a leaf.
    pub child_count: u32,
    /// The meshlets below, as a range of the cluster list: a leaf's own, an internal
    /// node's the concatenation of its children's (the list is in depth-first order).
    pub first_cluster: u32,
    /// Meshlets below.
    pub cluster_count: u32,
    /// Zero.
    pub reserved: [u32; 2],
}

impl NodeRecord {
    /// Whether the node holds meshlets rather than child nodes.
    pub fn is_leaf(&self) -> bool {
        self.child_count == 0
    }
    /// The child nodes' indices (empty for a leaf).
    pub fn children(&self) -> std::ops::Range<usize> {
        self.first_child as usize..self.first_child as usize + self.child_count as usize
    }
    /// The range of the cluster list holding the meshlets below.
    pub fn clusters(&self) -> std::ops::Range<usize> {
        self.first_cluster as usize..self.first_cluster as usize + self.cluster_count as usize
    }
}
