//! A glTF file's materials (metallic-roughness PBR) as the scene carries them: factors
//! checked (finite, in their ranges), texture references checked against the file's
//! textures, so nothing a renderer reads later can index out of range or shade NaN.

use gltf::json::Value;
use gltf::json::material::AlphaMode as JsonAlphaMode;
use gltf::json::validation::Checked;

use super::GltfFile;
use crate::error::SceneError;

/// Where [`SceneMesh::materials`](super::SceneMesh::materials) says a slot's
/// primitives have no material of the file's: glTF's default material (white, fully rough,
/// not metallic) applies.
pub const DEFAULT_MATERIAL: u32 = u32::MAX;

/// An affine map of texture coordinates: row `r` gives coordinate `r` as
/// `row · (u, v, 1)`.
pub type UvTransform = [[f32; 3]; 2];

/// The [`UvTransform`] that leaves coordinates as they are.
pub const IDENTITY_UV_TRANSFORM: UvTransform = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];

/// A texture a material samples.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TextureRef {
    /// Index into the file's textures.
    pub texture: usize,
    /// Which `TEXCOORD_n` it is sampled with (only `TEXCOORD_0` is read).
    pub tex_coord: u32,
    /// Its `KHR_texture_transform` (offset, rotation and scale) as one affine map, or
    /// [`IDENTITY_UV_TRANSFORM`].
    pub transform: UvTransform,
}

/// `KHR_texture_transform`'s `T · R · S`: coordinates scaled, then rotated by `rotation`
/// radians (counter-clockwise in the image, whose V runs down), then offset; the
/// extension's example (offset (0, 1), a quarter turn, half scale: the image's
/// lower-left quarter turned) fixes the rotation's sense.
pub fn texture_transform(offset: [f32; 2], rotation: f32, scale: [f32; 2]) -> UvTransform {
    let (sin, cos) = rotation.sin_cos();
    [
        [cos * scale[0], sin * scale[1], offset[0]],
        [-sin * scale[0], cos * scale[1], offset[1]],
    ]
}

/// How a material's alpha is used.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum AlphaMode {
    /// Alpha is ignored.
    Opaque,
    /// Texels whose alpha is below `cutoff` are not drawn.
    Mask {
        /// The alpha below which a texel is cut out.
        cutoff: f32,
    },
    /// Alpha blends: meshlight draws such materials opaque (and says so when it draws them).
    Blend,
}

/// One glTF material.
#[derive(Debug, Clone, PartialEq)]
pub struct SceneMaterial {
    /// Its name, or `#index`.
    pub name: String,
    /// Linear RGBA multiplied into the base colour texture (and vertex colours).
    pub base_color: [f32; 4],
    /// The base colour texture (sRGB).
    pub base_color_texture: Option<TextureRef>,
    /// Metalness, 0 to 1.
    pub metallic: f32,
    /// Perceptual roughness, 0 to 1.
    pub roughness: f32,
    /// Roughness in G and metalness in B.
    pub metallic_roughness_texture: Option<TextureRef>,
    /// A tangent-space normal map.
    pub normal_texture: Option<TextureRef>,
    /// How strongly the normal map bends the normal.
    pub normal_scale: f32,
    /// Ambient occlusion in R.
    pub occlusion_texture: Option<TextureRef>,
    /// How much of the occlusion applies, 0 to 1.
    pub occlusion_strength: f32,
    /// Linear emitted colour, multiplied into the emissive texture.
    pub emissive: [f32; 3],
    /// The emissive texture (sRGB).
    pub emissive_texture: Option<TextureRef>,
    /// How alpha is used.
    pub alpha: AlphaMode,
    /// Whether back faces are drawn too.
    pub double_sided: bool,
}

impl SceneMaterial {
    /// The one texture transform meshlight samples all of the material's maps with (the
    /// base colour texture's, or else the first map's that has one), and whether another
    /// map asks for a different one (which is then drawn with this one).
    pub fn uv_transform(&self) -> (UvTransform, bool) {
        let maps = [
            self.base_color_texture,
            self.metallic_roughness_texture,
            self.normal_texture,
            self.occlusion_texture,
            self.emissive_texture,
        ];
        let mut present = maps.iter().flatten().map(|t| t.transform);
        let chosen = present.next().unwrap_or(IDENTITY_UV_TRANSFORM);
        (chosen, present.any(|t| t != chosen))
    }
}

impl Default for SceneMaterial {
    /// glTF's default material.
    fn default() -> Self {
        Self {
            name: "default".into(),
            base_color: [1.0; 4],
            base_color_texture: None,
            metallic: 1.0,
            roughness: 1.0,
            metallic_roughness_texture: None,
            normal_texture: None,
            normal_scale: 1.0,
            occlusion_texture: None,
            occlusion_strength: 1.0,
            emissive: [0.0; 3],
            emissive_texture: None,
            alpha: AlphaMode::Opaque,
            double_sided: false,
        }
    }
}

/// A texture reference's `KHR_texture_transform` object, whichever kind of reference (the
/// core, normal and occlusion ones are three types with the same `extensions`).
macro_rules! transform_of {
    ($t:expr) => {
        $t.extensions
            .as_ref()
            .and_then(|e| e.others.get("KHR_texture_transform"))
    };
}

/// Every material of the file, checked.
pub(super) fn read_materials(file: &GltfFile) -> Result<Vec<SceneMaterial>, SceneError> {
    let root = file.root();
    root.materials
        .iter()
        .enumerate()
        .map(|(i, m)| {
            let name = m.name.clone().unwrap_or_else(|| format!("#{i}"));
            let bad = |what: String| {
                file.err(format!(
                    "material {name:?}: {what}; fix the material in the file (a glTF editor or \
                     exporter writes it)"
                ))
            };
            let texture = |index: usize, tex_coord: u32, extension: Option<&Value>, role: &str| {
                let (transform, tex_coord) = match extension {
                    None => (IDENTITY_UV_TRANSFORM, tex_coord),
                    Some(e) => read_transform(e, tex_coord)
                        .map_err(|e| bad(format!("its {role}'s KHR_texture_transform {e}")))?,
                };
                if index >= root.textures.len() {
                    return Err(bad(format!(
                        "its {role} is texture {index}, but the file has only {} textures",
                        root.textures.len()
                    )));
                }
                if tex_coord != 0 {
                    log::warn!(
                        "{}: material {name:?} samples its {role} with TEXCOORD_{tex_coord}; \
                         only TEXCOORD_0 is read, so it is sampled with that",
                        file.path.display()
                    );
                }
                Ok(TextureRef {
                    texture: index,
                    tex_coord,
                    transform,
                })
            };
            let unit = |v: f32, what: &str| {
                if (0.0..=1.0).contains(&v) {
                    Ok(v)
                } else {
                    Err(bad(format!("its {what} is {v}, not between 0 and 1")))
                }
            };
            let pbr = &m.pbr_metallic_roughness;
            let mut base_color = pbr.base_color_factor.0;
            for (k, c) in base_color.iter_mut().enumerate() {
                *c = unit(*c, &format!("baseColorFactor[{k}]"))?;
            }
            let emissive = m.emissive_factor.0;
            if let Some(e) = emissive.iter().find(|e| !(e.is_finite() && **e >= 0.0)) {
                return Err(bad(format!(
                    "its emissiveFactor holds {e}, not a finite value ≥ 0"
                )));
            }
            let normal_scale = m.normal_texture.as_ref().map_or(1.0, |n| n.scale);
            if !normal_scale.is_finite() {
                return Err(bad(format!("its normal texture's scale is {normal_scale}")));
            }
            let alpha = match m.alpha_mode {
                Checked::Valid(JsonAlphaMode::Opaque) => AlphaMode::Opaque,
                Checked::Valid(JsonAlphaMode::Mask) => {
                    let cutoff = m.alpha_cutoff.map_or(0.5, |c| c.0);
                    if !(cutoff.is_finite() && cutoff >= 0.0) {
                        return Err(bad(format!("its alphaCutoff is {cutoff}, not ≥ 0")));
                    }
                    AlphaMode::Mask { cutoff }
                }
                Checked::Valid(JsonAlphaMode::Blend) => AlphaMode::Blend,
                Checked::Invalid => {
                    return Err(bad("its alphaMode is not OPAQUE, MASK or BLEND".to_string()));
                }
            };
            Ok(SceneMaterial {
                name: name.clone(),
                base_color,
                base_color_texture: pbr
                    .base_color_texture
                    .as_ref()
                    .map(|t| {
                        texture(
                            t.index.value(),
                            t.tex_coord,
                            transform_of!(t),
                            "base colour texture",
                        )
                    })
                    .transpose()?,
                metallic: unit(pbr.metallic_factor.0, "metallicFactor")?,
                roughness: unit(pbr.roughness_factor.0, "roughnessFactor")?,
                metallic_roughness_texture: pbr
                    .metallic_roughness_texture
                    .as_ref()
                    .map(|t| {
                        texture(
                            t.index.value(),
                            t.tex_coord,
                            transform_of!(t),
                            "metallic-roughness texture",
                        )
                    })
                    .transpose()?,
                normal_texture: m
                    .normal_texture
                    .as_ref()
                    .map(|t| {
                        texture(
                            t.index.value(),
                            t.tex_coord,
                            transform_of!(t),
                            "normal texture",
                        )
                    })
                    .transpose()?,
                normal_scale,
                occlusion_texture: m
                    .occlusion_texture
                    .as_ref()
                    .map(|t| {
                        texture(
                            t.index.value(),
                            t.tex_coord,
                            transform_of!(t),
                            "occlusion texture",
                        )
                    })
                    .transpose()?,
                occlusion_strength: m
                    .occlusion_texture
                    .as_ref()
                    .map_or(Ok(1.0), |t| unit(t.strength.0, "occlusion strength"))?,
                emissive,
                emissive_texture: m
                    .emissive_texture
                    .as_ref()
                    .map(|t| {
                        texture(
                            t.index.value(),
                            t.tex_coord,
                            transform_of!(t),
                            "emissive texture",
                        )
                    })
                    .transpose()?,
                alpha,
                double_sided: m.double_sided,
            })
        })
        .collect()
}

/// A `KHR_texture_transform` object as one affine map, with the `texCoord` it overrides
/// `tex_coord` with; an error says which field is wrong.
fn read_transform(e: &Value, tex_coord: u32) -> Result<(UvTransform, u32), String> {
    let number = |v: &Value, what: &str| -> Result<f32, String> {
        match v.as_f64() {
            Some(x) if x.is_finite() && (x as f32).is_finite() => Ok(x as f32),
            _ => Err(format!("has {what} {v}, not a number a 32-bit float holds")),
        }
    };
    let pair = |name: &str, default: [f32; 2]| -> Result<[f32; 2], String> {
        match e.get(name) {
            None => Ok(default),
            Some(Value::Array(a)) if a.len() == 2 => {
                Ok([number(&a[0], name)?, number(&a[1], name)?])
            }
            Some(v) => Err(format!("has {name} {v}, not two numbers")),
        }
    };
    let offset = pair("offset", [0.0, 0.0])?;
    let scale = pair("scale", [1.0, 1.0])?;
    let rotation = e
        .get("rotation")
        .map_or(Ok(0.0), |r| number(r, "rotation"))?;
    let tex_coord = match e.get("texCoord") {
        None => tex_coord,
        Some(v) => v
            .as_u64()
            .and_then(|n| u32::try_from(n).ok())
            .ok_or_else(|| format!("has texCoord {v}, not a set index"))?,
    };
    Ok((texture_transform(offset, rotation, scale), tex_coord))
}
