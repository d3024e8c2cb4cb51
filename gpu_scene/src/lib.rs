//! The GPU scene: every loaded meshlet asset packed into shared buffers, the instances
//! that place them, a material table, and the view.
//!
//! Passes never see an asset file. They read six imported graph buffers, named by the
//! constants in [`names`], whose element layouts are the shared WGSL structs:
//!
//! | buffer          | WGSL                          | holds |
//! |-----------------|-------------------------------|-------|
//! | `meshlets`      | `array<meshlet::Meshlet>`     | every asset's meshlet records, offsets rebased |
//! | `meshlet_groups`| `array<meshlet::MeshletGroup>`| every asset's simplification groups |
//! | `payload`       | `array<u32>`                  | packed vertices, UVs and triangles |
//! | `meshes`        | `array<meshlet::Mesh>`        | per asset: grids, bounds, meshlet range |
//! | `instances`     | `array<instance::Instance>`   | transforms, material, mesh, meshlet range |
//! | `instances_high`| `array<instance::Instance>`   | the instances past one binding's limit (see [`instance_table`]) |
//! | `materials`     | `array<instance::Material>`   | factors and texture references |
//! | `textures`      | `array<u32>`                  | every texture's mip chain, RGBA8 (`layout::TextureRef`) |
//!
//! Three more hold the meshes' culling hierarchies (`meshlight_scene::hierarchy`), for
//! the `hierarchy` implementation of `fill_clusters`; a graph imports them with
//! [`gpu::import_hierarchy_for`] or [`GpuScene::import_hierarchy`]:
//!
//! | buffer               | element        | holds |
//! |----------------------|----------------|-------|
//! | `hierarchy_nodes`    | `HierarchyNode` (64 bytes, the asset's `NodeRecord`) | every asset's nodes, child and cluster ranges rebased |
//! | `hierarchy_clusters` | `u32`          | the leaves' meshlets, as indices into `meshlets` |
//! | `hierarchy_roots`    | `u32`          | per mesh, its root node |
//!
//! A streamed scene ([`SceneData::streamed`], see [`streaming`]) holds each mesh's
//! records, hierarchy and roots' payload, and a pool at the end of the payload where
//! pages are installed; one more buffer, `stream_errors` (`f32` per group), holds each
//! group's error while its page is not resident, for the cull to ask for it.
//!
//! [`SceneData`] is the CPU side (what CPU references read); [`GpuScene`] owns the
//! buffers and re-uploads only what changed. [`view`] builds the per-frame `View`.

#![warn(missing_docs)]

pub mod cascades;
pub mod data;
/// What adding assets and instances to a scene can refuse, and why.
pub mod error;
pub mod gpu;
pub mod instance_table;
pub mod lattice;
pub mod list_part;
pub mod phase;
pub mod scene_slots;
mod stream_upload;
pub mod streaming;
pub mod surface;
pub mod texture;
pub mod view;

pub use data::{IDENTITY_UV, InstanceId, Material, MeshId, SceneData, TextureId};
pub use error::SceneDataError;
pub use gpu::GpuScene;
pub use list_part::ListPart;
pub use phase::Phase;
pub use scene_slots::{SceneBuffer, scene_reads};
pub use view::{Camera, CameraError, Projection};

/// Names of the imported buffers (and of the pass slots that read them).
pub mod names {
    /// Every asset's meshlet records.
    pub const MESHLETS: &str = "meshlets";
    /// Every asset's simplification groups.
    pub const GROUPS: &str = "meshlet_groups";
    /// Every asset's packed vertex, UV and triangle words.
    pub const PAYLOAD: &str = "payload";
    /// One record per asset: grids, bounds, meshlet range.
    pub const MESHES: &str = "meshes";
    /// The instances (or the first binding's worth of them).
    pub const INSTANCES: &str = "instances";
    /// The instances past what one binding holds (`instance_table`).
    pub const INSTANCES_HIGH: &str = "instances_high";
    /// The material table.
    pub const MATERIALS: &str = "materials";
    /// Every texture's mip chain.
    pub const TEXTURES: &str = "textures";
    /// Every asset's culling-hierarchy nodes.
    pub const HIERARCHY_NODES: &str = "hierarchy_nodes";
    /// The hierarchy leaves' meshlets, as indices into `meshlets`.
    pub const HIERARCHY_CLUSTERS: &str = "hierarchy_clusters";
    /// Per mesh, its hierarchy's root node.
    pub const HIERARCHY_ROOTS: &str = "hierarchy_roots";
    /// Per group of a streamed scene, its error while its page is not resident (0 while
    /// it is): where the cull finds the pages it wants.
    pub const STREAM_ERRORS: &str = "stream_errors";
    /// The frame input holding the `View` bytes.
    pub const VIEW: &str = "view";
}
