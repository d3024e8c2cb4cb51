//! The CPU side of the GPU scene: what the buffers hold, and what changed since the last
//! upload. CPU references of the passes read these vectors directly.

use crate::error::SceneDataError;
use glam::{Mat4, Vec3};
use meshlight_scene::MeshletAsset;
use meshlight_scene::asset::format::{GroupRecord, MeshletRecord, NO_GROUP, NodeRecord};
use meshlight_scene::texture::{
    ColorSpace, Image, MipChain, mip_chain, resample_square, to_linear,
};
use meshlight_shaders::cpu::layout::{
    self, MAP_COUNT, MESH_FLAG_COLORS, MESH_FLAG_UVS, TextureRef, TextureWrap,
};
use std::ops::Range;

/// A mesh added with [`SceneData::add_mesh`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct MeshId(pub u32);

/// An instance added with [`SceneData::add_instance`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct InstanceId(pub u32);

/// A texture added with [`SceneData::add_texture`], for a [`Material`]'s maps.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct TextureId(pub u32);

/// A material: what shading needs to colour a surface, glTF's metallic-roughness
/// model, its factors multiplied by its textures where it has them.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Material {
    /// Linear RGB albedo (of a metal: its specular colour).
    pub base_color: [f32; 3],
    /// 0 for a dielectric, 1 for a metal.
    pub metallic: f32,
    /// Perceptual roughness, 0 (mirror) to 1; squared into GGX's alpha.
    pub roughness: f32,
    /// Linear RGB light the surface gives off, added to what it reflects.
    pub emissive: [f32; 3],
    /// Whether the base colour is modulated by a checkerboard over the mesh's UVs, so
    /// that an untextured test mesh shows its parameterisation and its LOD changes.
    pub checker: bool,
    /// The textures, by `layout::MAP_*` index: base colour (sRGB, multiplies
    /// `base_color`), metallic-roughness (G roughness, B metalness, multiplying the
    /// factors), normal (tangent space), occlusion (R, on the ambient light) and
    /// emissive (sRGB, multiplies `emissive`).
    pub maps: [Option<TextureId>; MAP_COUNT],
    /// How far the normal map tilts the normal (glTF's `normalTexture.scale`).
    pub normal_scale: f32,
    /// How much of the occlusion map applies, 0 to 1.
    pub occlusion_strength: f32,
    /// The texture coordinates the maps are sampled at, as an affine map of the mesh's:
    /// row `r` gives coordinate `r` as `row · (u, v, 1)` (glTF's `KHR_texture_transform`;
    /// [`IDENTITY_UV`] by default). It applies to the checkerboard too.
    pub uv_transform: [[f32; 3]; 2],
    /// Whether back faces are drawn too, lit with the normal reversed (glTF's
    /// `doubleSided`). Otherwise both rasterisers drop them, as they do by default.
    pub double_sided: bool,
    /// The base colour's alpha factor (glTF's `baseColorFactor[3]`), 0 to 1: with the
    /// base colour texture's alpha, what a MASK material is cut by.
    pub alpha: f32,
    /// glTF's `alphaMode` MASK: where the base colour's alpha (factor × texture) is
    /// below this cutoff, both rasterisers leave the pixel undrawn and what lies behind
    /// shows through. `None`: opaque.
    pub alpha_cutoff: Option<f32>,
}

/// [`Material::uv_transform`] that samples at the mesh's own texture coordinates.
pub const IDENTITY_UV: [[f32; 3]; 2] = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];

impl Default for Material {
    /// A rough white dielectric with the checkerboard, as the generated scenes use.
    fn default() -> Self {
        Self {
            base_color: [1.0; 3],
            metallic: 0.0,
            roughness: DEFAULT_ROUGHNESS,
            emissive: [0.0; 3],
            checker: true,
            maps: [None; MAP_COUNT],
            normal_scale: 1.0,
            occlusion_strength: 1.0,
            uv_transform: IDENTITY_UV,
            double_sided: false,
            alpha: 1.0,
            alpha_cutoff: None,
        }
    }
}

/// The roughness of [`Material::default`]: a broad, faint highlight.
pub const DEFAULT_ROUGHNESS: f32 = 0.6;

/// The table the `textures` buffer starts with ([`layout::SRGB_TABLE_WORDS`] words):
/// word `v` holds the f32 bits of the linear light of 8-bit sRGB value `v`, which the
/// resolve reads instead of decoding each texel with a `pow`.
pub fn srgb_table() -> [u32; layout::SRGB_TABLE_WORDS] {
    std::array::from_fn(|v| to_linear(v as u8).to_bits())
}

// The mesh flags are the asset's header flags, bit for bit.
const _: () = assert!(
    MESH_FLAG_UVS == meshlight_scene::asset::format::FLAG_UVS
        && MESH_FLAG_COLORS == meshlight_scene::asset::format::FLAG_COLORS
);

/// Zero words after the payload in its binding, so that a read of the words at a
/// field's location never leaves it: two for a field (`read_bits`), four for a vertex's
/// grid offsets (`meshlet_grid_offsets`' window), whatever record ends the payload.
pub const PAYLOAD_PADDING: u32 = 4;

/// Element counts the buffers may not exceed. Each buffer is bound whole, so the binding
/// limit of the device bounds it; [`Limits::for_device`] derives them. The instance
/// table alone may take two bindings ([`crate::instance_table`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Limits {
    /// Instances one binding holds: past this the table continues in `instances_high`.
    pub instances_per_binding: u32,
    /// Instances both bindings hold.
    pub max_instances: u32,
    /// Meshlet records the shared `meshlets` binding holds.
    pub max_meshlets: u32,
    /// Words the shared `payload` binding holds (less the [`PAYLOAD_PADDING`] words of
    /// padding after it).
    pub max_payload_words: u32,
    /// Culling-hierarchy nodes the shared `hierarchy_nodes` binding holds.
    pub max_hierarchy_nodes: u32,
    /// Texel words (one RGBA8 texel each, mips included) the `textures` binding holds:
    /// the scene's texture budget.
    pub max_texture_words: u32,
}

impl Limits {
    /// The counts whose buffers fit `max_storage_buffer_binding_size` bytes.
    pub fn for_binding_size(bytes: u64) -> Self {
        let count = |size: usize| (bytes / size as u64).min(u32::MAX as u64) as u32;
        let instances_per_binding = count(size_of::<layout::Instance>());
        Self {
            instances_per_binding,
            max_instances: instances_per_binding.saturating_mul(2),
            max_meshlets: count(size_of::<MeshletRecord>()),
            // Padding follows the payload (see `GpuScene`).
            max_payload_words: count(4).saturating_sub(PAYLOAD_PADDING),
            max_hierarchy_nodes: count(size_of::<NodeRecord>()),
            max_texture_words: count(4),
        }
    }
    /// The counts an adapter with these limits can bind, for sizing a scene before it
    /// is uploaded.
    pub fn for_device(limits: &wgpu::Limits) -> Self {
        Self::for_binding_size(limits.max_storage_buffer_binding_size)
    }
}

impl Default for Limits {
    /// wgpu's default binding limit (128 MiB).
    fn default() -> Self {
        Self::for_device(&wgpu::Limits::default())
    }
}

/// Everything the GPU scene uploads, with change tracking.
#[derive(Clone, Debug, Default)]
pub struct SceneData {
    /// One record per added asset: its grids, bounds and meshlet range, which instances
    /// refer to by [`MeshId`].
    pub meshes: Vec<layout::Mesh>,
    /// Every asset's meshlet records; `data_offset`, `source_group` and `parent_group`
    /// are rebased onto the shared payload and group arrays.
    pub meshlets: Vec<MeshletRecord>,
    /// Every asset's simplification groups (LOD spheres and errors), which meshlets refer to
    /// as their own and their parent's group.
    pub groups: Vec<GroupRecord>,
    /// Every asset's packed vertex, UV and triangle words, which meshlet records point into.
    pub payload: Vec<u32>,
    /// Every asset's culling-hierarchy nodes; `first_child` and `first_cluster` rebased
    /// onto these shared arrays.
    pub hierarchy_nodes: Vec<NodeRecord>,
    /// Every asset's hierarchy cluster list, as indices into `meshlets`.
    pub hierarchy_clusters: Vec<u32>,
    /// Per mesh: the index of its hierarchy's root in `hierarchy_nodes`.
    pub hierarchy_roots: Vec<u32>,
    /// The placed instances, in the order they were added: what the culling passes walk.
    pub instances: Vec<layout::Instance>,
    /// The material table instances index, in GPU layout.
    pub materials: Vec<layout::Material>,
    /// The sRGB decoding table ([`layout::SRGB_TABLE_WORDS`] words), then every
    /// texture's mip chain, one RGBA8 texel a word (see `layout::TextureRef`).
    pub textures: Vec<u32>,
    /// Where each added texture lies in `textures`, by [`TextureId`].
    pub texture_refs: Vec<TextureRef>,
    mesh_names: Vec<String>,
    /// Per mesh, its material slots: an instance's material is the first of as many.
    mesh_materials: Vec<u32>,
    limits: Limits,
    /// Instances refused because their transform was singular or not finite.
    skipped_instances: u32,
    /// Bumped whenever meshes are added (geometry buffers must be uploaded again).
    pub(crate) geometry_version: u64,
    pub(crate) materials_version: u64,
    pub(crate) textures_version: u64,
    /// Instances changed since the last upload.
    pub(crate) dirty_instances: Option<Range<usize>>,
    /// Set for a scene that streams its meshes' pages ([`Self::streamed`]).
    pub(crate) streaming: Option<crate::streaming::Streaming>,
}

impl SceneData {
    /// An empty scene that refuses to grow past `limits` (the device's, so that every
    /// buffer can be bound whole).
    pub fn new(limits: Limits) -> Self {
        Self {
            limits,
            ..Default::default()
        }
    }

    /// An empty scene that streams: each mesh added is held in streamed form, its
    /// records, hierarchy and roots' payload resident and every page absent until
    /// installed (see [`crate::streaming`]); reserve the pool with
    /// [`Self::reserve_pool`] once the meshes are in.
    pub fn streamed(limits: Limits) -> Self {
        Self {
            limits,
            streaming: Some(Default::default()),
            ..Default::default()
        }
    }

    /// The limits the scene was made with, for callers that size their own lists to it.
    pub fn limits(&self) -> Limits {
        self.limits
    }

    /// Appends an asset's meshlets, groups and payload to the shared arrays. An asset
    /// not yet verified (built in memory, or read with `MeshletAsset::load`) is first
    /// put through every check `meshlight inspect` runs, so nothing it rejects reaches
    /// the GPU; one loaded with `MeshletAsset::load_verified` is not checked twice.
    pub fn add_mesh(&mut self, name: &str, asset: &MeshletAsset) -> Result<MeshId, SceneDataError> {
        if asset.page_file().is_some() && self.streaming.is_none() {
            return Err(SceneDataError::InvalidAsset {
                name: name.to_string(),
                reason: "it was opened for streaming (its resident part only): add it to a \
                         streamed scene (`SceneData::streamed`), or load it whole \
                         (`MeshletAsset::load_verified`)"
                    .into(),
            });
        }
        if !asset.is_verified() {
            asset.check_all(std::path::Path::new(name)).map_err(|e| {
                SceneDataError::InvalidAsset {
                    name: name.to_string(),
                    reason: e.to_string(),
                }
            })?;
        }
        let header = asset.header();
        for (what, held, added, limit) in [
            (
                "meshlets",
                self.meshlets.len(),
                asset.meshlets().len(),
                self.limits.max_meshlets,
            ),
            (
                "payload words",
                self.payload.len(),
                asset.payload().len(),
                self.limits.max_payload_words,
            ),
            (
                "hierarchy nodes",
                self.hierarchy_nodes.len(),
                asset.nodes().len(),
                self.limits.max_hierarchy_nodes,
            ),
        ] {
            check_limit(
                what,
                held as u64 + added as u64,
                limit as u64,
                "load fewer or smaller meshes, or use a device with a larger storage binding",
            )?;
        }
        if asset.meshlets().is_empty() {
            return Err(SceneDataError::InvalidAsset {
                name: name.to_string(),
                reason: "it has no meshlets".into(),
            });
        }
        let first_meshlet = self.meshlets.len() as u32;
        let payload_base = self.payload.len() as u32;
        let group_base = self.groups.len() as u32;
        let rebase_group = |g: u32| {
            if g == NO_GROUP {
                NO_GROUP
            } else {
                g + group_base
            }
        };
        self.meshlets
            .extend(asset.meshlets().iter().map(|m| MeshletRecord {
                data_offset: m.data_offset + payload_base,
                source_group: rebase_group(m.source_group),
                parent_group: rebase_group(m.parent_group),
                ..*m
            }));
        // `first_child` and `child_count` still index the asset's own children section,
        // which no pass reads; they are kept for inspection.
        self.groups.extend_from_slice(asset.groups());
        self.payload.extend_from_slice(asset.payload());
        if header.has_colors() && self.textures.is_empty() {
            // Vertex colours are sRGB-encoded: the resolve decodes them with the table
            // the textures buffer starts with (256 words, within any limit).
            self.textures.extend(srgb_table());
        }
        let node_base = self.hierarchy_nodes.len() as u32;
        let list_base = self.hierarchy_clusters.len() as u32;
        self.hierarchy_roots.push(node_base);
        self.hierarchy_nodes
            .extend(asset.nodes().iter().map(|n| NodeRecord {
                first_child: if n.is_leaf() {
                    0
                } else {
                    n.first_child + node_base
                },
                first_cluster: n.first_cluster + list_base,
                ..*n
            }));
        self.hierarchy_clusters
            .extend(asset.node_clusters().iter().map(|&m| m + first_meshlet));
        let min = Vec3::from(header.bounds_min);
        let max = Vec3::from(header.bounds_max);
        let center = (min + max) * 0.5;
        // The decoded vertices lie within half a grid step of the bounds.
        let radius = (max - min).length() * 0.5 + header.quant_step;
        self.meshes.push(layout::Mesh {
            position_grid: [
                header.quant_origin[0],
                header.quant_origin[1],
                header.quant_origin[2],
                header.quant_step,
            ],
            uv_grid: [
                header.uv_min[0],
                header.uv_min[1],
                header.uv_step[0],
                header.uv_step[1],
            ],
            bounding_sphere: [center.x, center.y, center.z, radius],
            first_meshlet,
            meshlet_count: asset.meshlets().len() as u32,
            // The asset's flags as they are: the payload layout follows from them
            // (`PayloadLayout::of`), on the GPU as on the CPU.
            flags: header.flags & (MESH_FLAG_UVS | MESH_FLAG_COLORS),
            level_count: header.level_count,
        });
        if self.streaming.is_some() {
            self.add_streamed_parts(asset, self.meshes.len() as u32 - 1);
        }
        self.mesh_names.push(name.to_string());
        self.mesh_materials.push(header.material_count);
        self.geometry_version += 1;
        Ok(MeshId(self.meshes.len() as u32 - 1))
    }

    /// The name an asset was added under, for counters and messages that name meshes.
    pub fn mesh_name(&self, mesh: MeshId) -> Option<&str> {
        self.mesh_names.get(mesh.0 as usize).map(String::as_str)
    }

    /// The material a cluster of `meshlet` placed by `instance` is drawn with (the
    /// instance's first material plus the meshlet's slot), as the passes find it; `None`
    /// where an index is out of range.
    pub fn cluster_material(&self, instance: u32, meshlet: u32) -> Option<&layout::Material> {
        let first = self.instances.get(instance as usize)?.material;
        let slot = self.meshlets.get(meshlet as usize)?.material();
        self.materials
            .get((first as usize).checked_add(slot as usize)?)
    }

    /// Material slots of `mesh` (1 for a mesh of one material): an instance of it
    /// takes that many consecutive materials, from the one it is placed with.
    pub fn mesh_material_count(&self, mesh: MeshId) -> Option<u32> {
        self.mesh_materials.get(mesh.0 as usize).copied()
    }

    /// Adds a material and returns the index instances refer to it by. A map naming a
    /// texture this scene was not given is refused.
    pub fn add_material(&mut self, material: Material) -> Result<u32, SceneDataError> {
        let [r, g, b] = material.base_color;
        let [er, eg, eb] = material.emissive;
        let mut maps = [[0u32; 2]; MAP_COUNT];
        for (slot, map) in maps.iter_mut().zip(material.maps) {
            if let Some(TextureId(id)) = map {
                let reference =
                    self.texture_refs
                        .get(id as usize)
                        .ok_or(SceneDataError::UnknownTexture {
                            texture: id,
                            added: self.texture_refs.len() as u32,
                        })?;
                *slot = reference.words();
            }
        }
        if let Some(&value) = material
            .uv_transform
            .as_flattened()
            .iter()
            .find(|v| !v.is_finite())
        {
            return Err(SceneDataError::NonFiniteUvTransform { value });
        }
        if let Some(value) = material.alpha_cutoff.filter(|v| !v.is_finite()) {
            return Err(SceneDataError::NonFiniteAlphaCutoff { value });
        }
        let finite = |v: f32, fallback: f32| if v.is_finite() { v } else { fallback };
        // A transform other than the identity goes into the `textures` buffer, where the
        // resolve reads it only for this material's pixels.
        let uv_transform = if material.uv_transform == IDENTITY_UV {
            0
        } else {
            if self.textures.is_empty() {
                self.textures.extend(srgb_table());
            }
            check_limit(
                "texture words (RGBA8 texels, mips included, and texture transforms)",
                (self.textures.len() + layout::UV_TRANSFORM_WORDS) as u64,
                self.limits.max_texture_words as u64,
                "scale the textures down, or use a device with a larger storage binding",
            )?;
            let word = self.textures.len() as u32;
            self.textures.extend(
                material
                    .uv_transform
                    .as_flattened()
                    .iter()
                    .map(|v| v.to_bits()),
            );
            self.textures_version += 1;
            word
        };
        self.materials.push(layout::Material {
            base_color: [r, g, b, finite(material.alpha, 1.0).clamp(0.0, 1.0)],
            emissive: [er, eg, eb, finite(material.normal_scale, 1.0)],
            metallic: material.metallic.clamp(0.0, 1.0),
            roughness: material.roughness.clamp(0.0, 1.0),
            occlusion_strength: material.occlusion_strength.clamp(0.0, 1.0),
            alpha_cutoff: material.alpha_cutoff.unwrap_or(0.0),
            flags: if material.checker {
                layout::MATERIAL_FLAG_CHECKER
            } else {
                0
            } | if material.double_sided {
                layout::MATERIAL_FLAG_DOUBLE_SIDED
            } else {
                0
            } | if material.alpha_cutoff.is_some() {
                layout::MATERIAL_FLAG_MASK
            } else {
                0
            },
            uv_transform,
            maps,
        });
        self.materials_version += 1;
        Ok(self.materials.len() as u32 - 1)
    }

    /// Adds a decoded image as a texture: resampled to a square power-of-two side (the
    /// next one up from its longer side, at most 2^[`layout::MAX_TEXTURE_SIZE_LOG2`],
    /// larger images scaled down) and mip-mapped, both in linear light when `srgb`.
    pub fn add_image(
        &mut self,
        image: &Image,
        srgb: bool,
        wrap: [TextureWrap; 2],
    ) -> Result<TextureId, SceneDataError> {
        let side = image
            .width
            .max(image.height)
            .max(1)
            .next_power_of_two()
            .min(1 << layout::MAX_TEXTURE_SIZE_LOG2);
        let space = if srgb {
            ColorSpace::Srgb
        } else {
            ColorSpace::Linear
        };
        let chain = mip_chain(&resample_square(image, side, space), space);
        self.add_texture(&chain, srgb, wrap)
    }

    /// Adds a texture: `chain` (square, a power-of-two side up to
    /// 2^[`layout::MAX_TEXTURE_SIZE_LOG2`], every level down to 1 × 1, as
    /// `meshlight_scene::texture::mip_chain` makes it), its colour channels sRGB-encoded
    /// or data, wrapping in U and V as `wrap` says. Refused past the texture budget
    /// ([`Limits::max_texture_words`]) with the words needed and held.
    pub fn add_texture(
        &mut self,
        chain: &MipChain,
        srgb: bool,
        wrap: [TextureWrap; 2],
    ) -> Result<TextureId, SceneDataError> {
        let size = chain.size();
        let shape_ok = size.is_power_of_two()
            && size <= 1 << layout::MAX_TEXTURE_SIZE_LOG2
            && chain.levels.len() as u32 == size.trailing_zeros() + 1
            && chain.levels.iter().enumerate().all(|(l, level)| {
                let side = size >> l;
                level.width == side
                    && level.height == side
                    && level.rgba.len() == side as usize * side as usize * 4
            });
        if !shape_ok {
            return Err(SceneDataError::TextureShape { size });
        }
        if self.textures.is_empty() {
            self.textures.extend(srgb_table());
        }
        let reference = TextureRef {
            texels: self.textures.len() as u32,
            size_log2: size.trailing_zeros(),
            srgb,
            wrap,
        };
        check_limit(
            "texture words (RGBA8 texels, mips included)",
            self.textures.len() as u64 + reference.words_len(),
            self.limits.max_texture_words as u64,
            "scale the textures down, or use a device with a larger storage binding",
        )?;
        for level in &chain.levels {
            self.textures.extend(
                level
                    .rgba
                    .chunks_exact(4)
                    .map(|t| u32::from_le_bytes([t[0], t[1], t[2], t[3]])),
            );
        }
        self.texture_refs.push(reference);
        self.textures_version += 1;
        Ok(TextureId(self.texture_refs.len() as u32 - 1))
    }

    /// Places `mesh` with `world_from_local`, its material slot `k` drawn in material
    /// `material + k` (so a mesh of several materials takes as many consecutive ones,
    /// see [`Self::mesh_material_count`]). A transform that is singular or not finite
    /// cannot be drawn (its normals and LOD scale are undefined): the instance is
    /// skipped, counted in [`Self::skipped_instances`], and `Ok(None)` returned.
    pub fn add_instance(
        &mut self,
        mesh: MeshId,
        world_from_local: Mat4,
        material: u32,
    ) -> Result<Option<InstanceId>, SceneDataError> {
        let info = *self
            .meshes
            .get(mesh.0 as usize)
            .ok_or(SceneDataError::UnknownMesh(mesh.0))?;
        let slots = self.mesh_materials[mesh.0 as usize];
        if material as u64 + slots as u64 > self.materials.len() as u64 {
            return Err(SceneDataError::UnknownMaterial {
                material,
                slots,
                added: self.materials.len() as u32,
            });
        }
        check_limit(
            "instances",
            self.instances.len() as u64 + 1,
            self.limits.max_instances as u64,
            "place fewer instances (the instance table takes two storage bindings at most)",
        )?;
        if !drawable(world_from_local) {
            self.skipped_instances += 1;
            return Ok(None);
        }
        let m = world_from_local.to_cols_array_2d();
        self.instances.push(layout::Instance {
            world_from_local: m,
            previous_world_from_local: m,
            local_from_world: world_from_local.inverse().to_cols_array_2d(),
            position_grid: info.position_grid,
            material,
            first_meshlet: info.first_meshlet,
            meshlet_count: info.meshlet_count,
            mesh: mesh.0,
        });
        let i = self.instances.len() - 1;
        self.mark_instance(i);
        Ok(Some(InstanceId(i as u32)))
    }

    /// Moves an instance; its previous transform becomes the one it had. A singular or
    /// non-finite transform is refused (the instance keeps its place) and counted.
    pub fn set_transform(
        &mut self,
        id: InstanceId,
        world_from_local: Mat4,
    ) -> Result<bool, SceneDataError> {
        let i = id.0 as usize;
        let instance = self
            .instances
            .get_mut(i)
            .ok_or(SceneDataError::UnknownInstance(id.0))?;
        if !drawable(world_from_local) {
            self.skipped_instances += 1;
            return Ok(false);
        }
        instance.previous_world_from_local = instance.world_from_local;
        instance.world_from_local = world_from_local.to_cols_array_2d();
        instance.local_from_world = world_from_local.inverse().to_cols_array_2d();
        self.mark_instance(i);
        Ok(true)
    }

    /// Instances refused for a singular or non-finite transform.
    pub fn skipped_instances(&self) -> u32 {
        self.skipped_instances
    }

    /// Meshlets over all instances: the clusters `fill_clusters` writes for a view that
    /// sees everything.
    pub fn total_clusters(&self) -> u64 {
        self.instances.iter().map(|i| i.meshlet_count as u64).sum()
    }

    /// LOD-0 triangles over all instances (the "source triangles" of the scene).
    pub fn source_triangles(&self) -> u64 {
        let per_mesh: Vec<u64> = self
            .meshes
            .iter()
            .map(|m| {
                let range = m.first_meshlet as usize..(m.first_meshlet + m.meshlet_count) as usize;
                self.meshlets[range]
                    .iter()
                    .filter(|r| r.level() == 0)
                    .map(|r| r.triangle_count() as u64)
                    .sum()
            })
            .collect();
        self.instances
            .iter()
            .map(|i| per_mesh[i.mesh as usize])
            .sum()
    }

    /// A meshlet's own LOD sphere and error (its source group's; its bounds and 0 at
    /// LOD 0), as the shaders find them.
    pub fn own_lod(&self, meshlet: &MeshletRecord) -> ([f32; 4], f32) {
        match self.groups.get(meshlet.source_group as usize) {
            Some(g) => (g.lod_sphere, g.error),
            None => (meshlet.bounds, 0.0),
        }
    }

    /// A meshlet's parent LOD sphere and error (`f32::MAX` for roots).
    pub fn parent_lod(&self, meshlet: &MeshletRecord) -> ([f32; 4], f32) {
        match self.groups.get(meshlet.parent_group as usize) {
            Some(g) => (g.lod_sphere, g.error),
            None => ([0.0; 4], f32::MAX),
        }
    }

    /// Where the instance table splits: `instances` holds `..split`, `instances_high`
    /// the rest (none while the table fits one binding).
    pub fn instance_split(&self) -> usize {
        self.instances
            .len()
            .min(self.limits.instances_per_binding as usize)
    }

    /// True when the instances take two bindings (`instances_high` holds some).
    pub fn instances_split(&self) -> bool {
        self.instance_split() < self.instances.len()
    }

    fn mark_instance(&mut self, i: usize) {
        self.dirty_instances = Some(match self.dirty_instances.take() {
            Some(r) => r.start.min(i)..r.end.max(i + 1),
            None => i..i + 1,
        });
    }
}

/// A transform that can be drawn: finite, with a determinant far from zero.
pub fn drawable(m: Mat4) -> bool {
    m.is_finite() && m.determinant().abs() > 1e-20 && m.inverse().is_finite()
}

pub(crate) fn check_limit(
    what: &'static str,
    requested: u64,
    limit: u64,
    advice: &'static str,
) -> Result<(), SceneDataError> {
    if requested > limit {
        return Err(SceneDataError::Limit {
            what,
            requested,
            limit,
            advice,
        });
    }
    Ok(())
}
