use thiserror::Error;

/// What can go wrong when assets and instances are added to a scene.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum SceneDataError {
    /// Adding this would take a buffer past what one binding of the device holds.
    #[error("the scene would hold {requested} {what}, above the limit of {limit}; {advice}")]
    Limit {
        /// What would grow (meshlets, payload words, instances, …).
        what: &'static str,
        /// How many the scene would then hold.
        requested: u64,
        /// The most the device can bind.
        limit: u64,
        /// What to change to stay under it.
        advice: &'static str,
    },
    /// A streaming operation the scene cannot do (see [`crate::streaming`]).
    #[error("streaming: {reason}")]
    Streaming {
        /// What was wrong.
        reason: String,
    },
    /// An instance named a mesh this scene was never given.
    #[error("mesh id {0} does not exist in this scene; add the mesh first with `add_mesh`")]
    UnknownMesh(u32),
    /// An instance named a material this scene was never given, or a mesh of several
    /// material slots runs past the materials added.
    #[error(
        "material id {material} with the mesh's {slots} slot(s) needs materials up to \
         {material} + {slots} - 1, but the scene has {added}; add them first with \
         `add_material`"
    )]
    UnknownMaterial {
        /// The instance's first material.
        material: u32,
        /// The mesh's material slots.
        slots: u32,
        /// Materials the scene holds.
        added: u32,
    },
    /// A material named a texture this scene was never given.
    #[error(
        "texture id {texture} does not exist in this scene, which has {added} texture(s); \
         add it first with `add_texture`"
    )]
    UnknownTexture {
        /// The texture named.
        texture: u32,
        /// Textures the scene holds.
        added: u32,
    },
    /// A material whose texture transform holds a NaN or an infinity, which would sample
    /// every texel at NaN.
    #[error(
        "a material's uv_transform holds {value}; give it finite values (IDENTITY_UV samples \
         at the mesh's own coordinates)"
    )]
    NonFiniteUvTransform {
        /// The first value that is not finite.
        value: f32,
    },
    /// A MASK material whose cutoff is not a finite number.
    #[error(
        "a material's alpha_cutoff is {value}; give a finite cutoff (glTF's default is 0.5), \
         or None for an opaque material"
    )]
    NonFiniteAlphaCutoff {
        /// The cutoff given.
        value: f32,
    },
    /// A texture that is not a square power-of-two mip chain.
    #[error(
        "a texture of side {size} is not a square power-of-two mip chain of at most 4096 \
         texels a side with every level down to 1 × 1; make it with \
         `meshlight_scene::texture::mip_chain` after `resample_square`"
    )]
    TextureShape {
        /// Side of level 0.
        size: u32,
    },
    /// An instance id past the scene's instances.
    #[error("instance id {0} does not exist in this scene")]
    UnknownInstance(u32),
    /// An asset failed the checks that keep damaged data off the GPU.
    #[error("asset `{name}` is invalid: {reason}; re-bake it with `meshlight bake`")]
    InvalidAsset {
        /// The name the asset was added under.
        name: String,
        /// The check it failed.
        reason: String,
    },
}
