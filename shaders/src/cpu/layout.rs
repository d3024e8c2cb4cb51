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
    /// World space to view space.
    pub view: [[f32; 4]; 4],
    /// View space to clip space, reverse-Z.
    pub projection: [[f32; 4]; 4],
    /// World space to clip space: `projection * view`.
    pub view_projection: [[f32; 4]; 4],
    /// View space to world space.
    pub inverse_view: [[f32; 4]; 4],
    /// Clip space to view space.
    pub inverse_projection: [[f32; 4]; 4],
    /// Clip space to world space, to rebuild positions from depth.
    pub inverse_view_projection: [[f32; 4]; 4],
    /// Last frame's world-to-clip, for testing against last frame's depth pyramid.
    pub previous_view_projection: [[f32; 4]; 4],
    /// Left, right, bottom, top, near, far; inside when `dot(xyz, p) + w >= 0`.
    pub frustum: [[f32; 4]; 6],
    /// Camera position, world space: where LOD errors are measured from.
    pub camera_position: [f32; 3],
    /// Distance to the near plane, view-space units: the nearest a projected error is
    /// measured at.
    pub near: f32,
    /// Render target size in pixels.
    pub viewport_size: [f32; 2],
    /// `1 / viewport_size`, so a shader turns pixels into uv without dividing.
    pub inverse_viewport_size: [f32; 2],
    /// `0.5 * projection[1][1] * viewport height`: pixels per world unit at distance 1
    /// (perspective), or at any distance (orthographic).
    pub lod_scale: f32,
    /// Frame counter, for temporal effects and debugging.
    pub frame_index: u32,
    /// 1 when the projection is orthographic (a shadow cascade, an orthographic camera):
    /// a projected error does not shrink with distance.
    pub orthographic: u32,
    /// Pads the struct to a 16-byte multiple, so the mirror has no implicit padding.
    pub padding: u32,
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
    /// The mesh's first meshlet in the shared meshlet array.
    pub first_meshlet: u32,
    /// Its meshlets, all LOD levels: `first_meshlet .. first_meshlet + meshlet_count`.
    pub meshlet_count: u32,
    /// `MESH_FLAG_UVS` (1) when the payload holds UVs, `MESH_FLAG_COLORS` (2) when it
    /// holds vertex colours: the asset header's flags.
    pub flags: u32,
    /// LOD levels of the mesh's DAG, for the `lod` debug view and statistics.
    pub level_count: u32,
}

/// `MESH_FLAG_UVS` of [`Mesh::flags`].
pub const MESH_FLAG_UVS: u32 = 1;
/// `MESH_FLAG_COLORS` of [`Mesh::flags`].
pub const MESH_FLAG_COLORS: u32 = 2;

/// `meshlight::meshlet::Cluster`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Pod, Zeroable)]
pub struct Cluster {
    /// Index of the instance that draws the meshlet.
    pub instance: u32,
    /// Index into the shared meshlet array.
    pub meshlet: u32,
}

/// `meshlight::instance::Instance`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct Instance {
    /// Mesh space to world space.
    pub world_from_local: [[f32; 4]; 4],
    /// Last frame's `world_from_local`, for last frame's occlusion test.
    pub previous_world_from_local: [[f32; 4]; 4],
    /// World space to mesh space; its transposed upper 3 × 3 transforms normals.
    pub local_from_world: [[f32; 4]; 4],
    /// xyz origin, w step: the mesh's [`Mesh::position_grid`].
    pub position_grid: [f32; 4],
    /// Index into the material table.
    pub material: u32,
    /// The mesh's first meshlet in the shared meshlet array, copied so culling needs no
    /// mesh lookup.
    pub first_meshlet: u32,
    /// How many meshlets the mesh has (all LOD levels).
    pub meshlet_count: u32,
    /// Index into the mesh table.
    pub mesh: u32,
}

/// `meshlight::instance::Material`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct Material {
    /// Linear RGB albedo, and in `[3]` the alpha factor.
    pub base_color: [f32; 4],
    /// Linear RGB emitted light, and in `[3]` the normal map's scale.
    pub emissive: [f32; 4],
    /// 0 dielectric, 1 metal.
    pub metallic: f32,
    /// Perceptual roughness, 0 to 1.
    pub roughness: f32,
    /// How much of the occlusion map applies, 0 to 1.
    pub occlusion_strength: f32,
    /// MASK materials: texels whose alpha is below this are cut out (0 for opaque).
    pub alpha_cutoff: f32,
    /// [`MATERIAL_FLAG_CHECKER`], [`MATERIAL_FLAG_DOUBLE_SIDED`] and [`MATERIAL_FLAG_MASK`],
    /// or 0.
    pub flags: u32,
    /// Where the texture transform the maps are sampled through lies in the scene's
    /// `textures` buffer ([`uv_transform_at`]), or 0 for none (word 0 is the sRGB
    /// table's, never a transform). Kept out of the record, which stays 96 bytes: the
    /// resolve loads each pixel's material, and 32 bytes more there cost it 1%.
    pub uv_transform: u32,
    /// The textures, by `MAP_*` index: each a [`TextureRef`]'s two words, `[0, 0]` for
    /// none.
    pub maps: [[u32; 2]; MAP_COUNT],
}

/// A texture transform: row `r` gives coordinate `r` as `row · (u, v, 1)`.
pub type UvTransform = [[f32; 3]; 2];

/// Words a [`UvTransform`] takes in the `textures` buffer: its rows, as f32 bits.
pub const UV_TRANSFORM_WORDS: usize = 6;

/// The transform at word `word` of a `textures` buffer (`Material::uv_transform`), or
/// `None` for 0 or a word past the buffer.
pub fn uv_transform_at(textures: &[u32], word: u32) -> Option<UvTransform> {
    let w = textures.get(word as usize..word as usize + UV_TRANSFORM_WORDS)?;
    (word != 0)
        .then(|| std::array::from_fn(|r| std::array::from_fn(|k| f32::from_bits(w[3 * r + k]))))
}

/// instance.wgsl's `material_uv`: `uv` through the transform.
pub fn material_uv(t: &UvTransform, uv: [f32; 2]) -> [f32; 2] {
    t.map(|r| r[0] * uv[0] + r[1] * uv[1] + r[2])
}

/// instance.wgsl's `material_uv_step`: a change of uv through the transform's linear
/// part (how the pixel's UV derivatives transform).
pub fn material_uv_step(t: &UvTransform, d: [f32; 2]) -> [f32; 2] {
    t.map(|r| r[0] * d[0] + r[1] * d[1])
}

/// `Material::flags`: the base colour is modulated by a checkerboard over the UVs.
pub const MATERIAL_FLAG_CHECKER: u32 = 1;
/// `Material::flags`: back faces are drawn too (both rasterisers turn them to face the
/// eye) and shaded with the normal reversed, as glTF's `doubleSided` asks.
pub const MATERIAL_FLAG_DOUBLE_SIDED: u32 = 2;
/// `Material::flags`: glTF's `alphaMode` MASK. Where the base colour's alpha (factor ×
/// texture) is below `alpha_cutoff`, both rasterisers leave the pixel undrawn, so what
/// lies behind shows through.
pub const MATERIAL_FLAG_MASK: u32 = 4;

/// `Material::maps` index of the base colour texture (sRGB; alpha in A).
pub const MAP_BASE_COLOR: usize = 0;
/// ... of the metallic-roughness texture (roughness in G, metalness in B).
pub const MAP_METALLIC_ROUGHNESS: usize = 1;
/// ... of the tangent-space normal map.
pub const MAP_NORMAL: usize = 2;
/// ... of the occlusion texture (R).
pub const MAP_OCCLUSION: usize = 3;
/// ... of the emissive texture (sRGB).
pub const MAP_EMISSIVE: usize = 4;
/// Textures a material may sample.
pub const MAP_COUNT: usize = 5;

/// Where a texture lies in the scene's `textures` buffer and how it is sampled: two
/// words, as `Material::maps` holds them.
///
/// A texture is square with a power-of-two side `2^size_log2` and a full mip chain;
/// level `L` (side `s = 2^size_log2 >> L`) starts `(4·S² − 4·s²) / 3` words after
/// `texels`, rows top to bottom, one RGBA8 texel per word (R in the low byte).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub struct TextureRef {
    /// The word of level 0's first texel.
    pub texels: u32,
    /// log2 of the side of level 0 (0 to [`MAX_TEXTURE_SIZE_LOG2`]).
    pub size_log2: u32,
    /// Colour channels are sRGB-encoded (decoded to linear light before filtering).
    pub srgb: bool,
    /// How U and V coordinates outside 0..1 wrap.
    pub wrap: [TextureWrap; 2],
}

/// Words at the start of the scene's `textures` buffer that hold the sRGB decoding
/// table: word `v` is the f32 bits of the linear light of 8-bit sRGB value `v`
/// (`meshlight_gpu_scene::data::srgb_table`). Texel words follow it.
pub const SRGB_TABLE_WORDS: usize = 256;

/// The largest texture side, as a power of two (4096).
pub const MAX_TEXTURE_SIZE_LOG2: u32 = 12;

/// How a texture coordinate outside 0..1 is brought back in (glTF's sampler wrap modes).
#[repr(u32)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum TextureWrap {
    /// Repeats (the default).
    #[default]
    Repeat = 0,
    /// Clamps to the edge texel.
    Clamp = 1,
    /// Repeats, every other copy mirrored.
    Mirror = 2,
}

/// `TextureRef` word 1: a texture is present.
const TEXTURE_PRESENT: u32 = 1 << 31;
/// `TextureRef` word 1: sRGB colour.
const TEXTURE_SRGB: u32 = 1 << 4;

impl TextureRef {
    /// The two words `Material::maps` holds: `texels`, then `size_log2` in bits 0..4,
    /// sRGB in bit 4, the U wrap in bits 5..7, the V wrap in bits 7..9, and bit 31 set.
    pub fn words(&self) -> [u32; 2] {
        [
            self.texels,
            TEXTURE_PRESENT
                | self.size_log2
                | if self.srgb { TEXTURE_SRGB } else { 0 }
                | (self.wrap[0] as u32) << 5
                | (self.wrap[1] as u32) << 7,
        ]
    }

    /// The reference two words hold, or `None` for no texture (or a mode that is no
    /// [`TextureWrap`]).
    pub fn from_words(words: [u32; 2]) -> Option<Self> {
        if words[1] & TEXTURE_PRESENT == 0 {
            return None;
        }
        let wrap = |bits: u32| match bits & 3 {
            0 => Some(TextureWrap::Repeat),
            1 => Some(TextureWrap::Clamp),
            2 => Some(TextureWrap::Mirror),
            _ => None,
        };
        Some(Self {
            texels: words[0],
            size_log2: words[1] & 15,
            srgb: words[1] & TEXTURE_SRGB != 0,
            wrap: [wrap(words[1] >> 5)?, wrap(words[1] >> 7)?],
        })
    }

    /// Side of level 0.
    pub fn size(&self) -> u32 {
        1 << self.size_log2
    }

    /// Mip levels, down to 1 × 1.
    pub fn levels(&self) -> u32 {
        self.size_log2 + 1
    }

    /// Words of the whole chain.
    pub fn words_len(&self) -> u64 {
        mip_offset(self.size_log2, self.levels())
    }
}

/// Words before level `level` (at most `size_log2 + 1`, the chain's end) of a chain whose
/// level 0 has side `S = 2^size_log2`: `(4·S² − 4·s²) / 3` with `s = S / 2^level`,
/// computed as `(4^(n+1) − 4^(n+1−level)) / 3` with `n = size_log2`, which stays exact.
pub fn mip_offset(size_log2: u32, level: u32) -> u64 {
    let n1 = size_log2 + 1;
    let level = level.min(n1);
    ((1u64 << (2 * n1)) - (1u64 << (2 * (n1 - level)))) / 3
}

/// The `kind` values of [`ClusterableObject`], as the `CLUSTERABLE_*` WGSL constants.
#[repr(u32)]
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum ClusterableKind {
    /// A point light: a sphere of influence.
    PointLight = 0,
    /// A spot light: a sphere cut to a cone.
    SpotLight = 1,
    /// A reflection probe: an oriented box.
    Probe = 2,
    /// A decal: a box projected along its direction.
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
    /// xyz world-space position; w the range beyond which it affects nothing.
    pub position_range: [f32; 4],
    /// xyz world-space unit direction (spot axis, decal projection); w cosine of a spot's
    /// outer half-angle.
    pub direction_cos_angle: [f32; 4],
    /// rgb linear colour, w intensity (lights).
    pub color_intensity: [f32; 4],
    /// A [`ClusterableKind`] as u32.
    pub kind: u32,
    /// Sine of a spot's outer half-angle, precomputed for the cone test.
    pub sin_angle: f32,
    /// Index into the probe or decal table of the pass that shades with it.
    pub payload: u32,
    /// Pads the struct to a 16-byte multiple.
    pub padding: u32,
}

/// `meshlight::light::ClusterGrid`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct ClusterGrid {
    /// Clusters along x (tile columns), y (tile rows) and z (depth slices).
    pub dims: [u32; 3],
    /// `dims.x * dims.y * dims.z`.
    pub cluster_count: u32,
    /// One tile's size in pixels (viewport size / `dims.xy`, rounded up).
    pub tile_size: [f32; 2],
    /// View-space distance where slice 0 begins; nearer depths fall into it.
    pub near: f32,
    /// View-space distance where the last slice ends; farther depths fall into it.
    pub far: f32,
    /// `dims.z / log2(far / near)`: slices per doubling of distance.
    pub z_slice_scale: f32,
    /// `-log2(near) * z_slice_scale`, so `slice = floor(log2(z) * scale + bias)`.
    pub z_slice_bias: f32,
    /// Pads the struct to a 16-byte multiple.
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
