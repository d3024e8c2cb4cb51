//! The textures a glTF file's materials sample: each image read once, from a buffer view
//! (a .glb's binary chunk), a base64 `data:` URI or a file in the model's folder (the
//! buffers' containment rule), and decoded in parallel; with each texture's wrap modes.
//!
//! An image that cannot be used (missing, outside the folder, not PNG or JPEG, corrupt,
//! too large) is, by default, not fatal: the materials that sample it fall back to
//! their factors, and a warning names the image, the file and what to change, so that
//! a scene missing one texture still opens. [`LoadOptions::strict_textures`] makes it
//! an error instead.

use std::sync::Arc;

use gltf::json::texture::WrappingMode;
use gltf::json::validation::Checked;
use rayon::prelude::*;

use super::GltfFile;
use super::buffers::{decode_base64, referenced_path};
use super::materials::SceneMaterial;
use crate::error::SceneError;
use crate::load::{LoadOptions, read_file};
use crate::texture::{Image, TextureError, decode_image};

/// How a texture repeats outside 0..1 along one axis (glTF's sampler `wrapS`/`wrapT`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Wrap {
    /// Tiles (the default).
    #[default]
    Repeat,
    /// Holds the edge texel.
    ClampToEdge,
    /// Tiles, every other copy mirrored.
    MirroredRepeat,
}

/// One glTF texture: its image, decoded, and how it wraps.
#[derive(Debug, Clone)]
pub struct SceneTexture {
    /// The image's name (or its URI, or `#index`), as warnings quote it.
    pub name: String,
    /// The decoded image; `None` when no material samples the texture or the image
    /// could not be used (the warning says why): the materials use their factors.
    pub image: Option<Arc<Image>>,
    /// Wrap along U and V.
    pub wrap: [Wrap; 2],
}

/// Every texture of the file, decoding the images that `materials` sample; the second
/// list holds a warning per image that could not be used (an error instead with
/// `strict_textures`).
pub(super) fn read_textures(
    file: &GltfFile,
    buffers: &[Vec<u8>],
    materials: &[SceneMaterial],
    options: &LoadOptions,
) -> Result<(Vec<SceneTexture>, Vec<String>), SceneError> {
    let root = file.root();
    let mut sampled = vec![false; root.textures.len()];
    for m in materials {
        for t in [
            m.base_color_texture,
            m.metallic_roughness_texture,
            m.normal_texture,
            m.occlusion_texture,
            m.emissive_texture,
        ]
        .into_iter()
        .flatten()
        {
            sampled[t.texture] = true;
        }
    }
    // The images behind sampled textures, each decoded once.
    let mut wanted = vec![false; root.images.len()];
    let mut sources = Vec::with_capacity(root.textures.len());
    for (i, t) in root.textures.iter().enumerate() {
        let source = t.source.value();
        if source >= root.images.len() {
            return Err(file.err(format!(
                "texture {i} has image {source}, but the file has only {} images; fix the \
                 texture's source",
                root.images.len()
            )));
        }
        wanted[source] |= sampled[i];
        sources.push(source);
    }
    let decoded: Vec<Option<Result<Image, TextureError>>> = (0..root.images.len())
        .into_par_iter()
        .map(|k| wanted[k].then(|| read_image(file, buffers, k)))
        .collect();
    let mut warnings = Vec::new();
    let mut images: Vec<Option<Arc<Image>>> = Vec::with_capacity(decoded.len());
    for (k, result) in decoded.into_iter().enumerate() {
        images.push(match result {
            None => None,
            Some(Ok(image)) => Some(Arc::new(image)),
            Some(Err(e)) if options.strict_textures => {
                return Err(SceneError::GltfTexture {
                    path: file.path.to_owned(),
                    image: k,
                    reason: e,
                });
            }
            Some(Err(e)) => {
                let warning = format!(
                    "{}: image {k} cannot be used, so the materials sampling it use their \
                     factors: {e}",
                    file.path.display()
                );
                log::warn!("{warning}");
                warnings.push(warning);
                None
            }
        });
    }
    let textures = root
        .textures
        .iter()
        .zip(sources)
        .map(|(t, source)| {
            let wrap = t
                .sampler
                .and_then(|s| root.samplers.get(s.value()))
                .map_or([Wrap::Repeat; 2], |s| {
                    [wrap_of(s.wrap_s), wrap_of(s.wrap_t)]
                });
            SceneTexture {
                name: image_name(file, source),
                image: images[source].clone(),
                wrap,
            }
        })
        .collect();
    Ok((textures, warnings))
}

fn wrap_of(mode: Checked<WrappingMode>) -> Wrap {
    match mode {
        Checked::Valid(WrappingMode::ClampToEdge) => Wrap::ClampToEdge,
        Checked::Valid(WrappingMode::MirroredRepeat) => Wrap::MirroredRepeat,
        // An unknown mode is glTF's default.
        _ => Wrap::Repeat,
    }
}

fn image_name(file: &GltfFile, k: usize) -> String {
    let image = &file.root().images[k];
    match (&image.name, &image.uri) {
        (Some(name), _) => format!("image {k} ({name:?})"),
        (None, Some(uri)) if !uri.starts_with("data:") => format!("image {k} ({uri:?})"),
        _ => format!("image {k}"),
    }
}

/// Image `k`'s bytes, decoded.
fn read_image(file: &GltfFile, buffers: &[Vec<u8>], k: usize) -> Result<Image, TextureError> {
    let name = format!("{} of {}", image_name(file, k), file.path.display());
    let unreadable = |found: String| TextureError::Unreadable {
        name: name.clone(),
        reason: found,
    };
    let image = &file.root().images[k];
    let bytes: Vec<u8> = match (&image.uri, image.buffer_view) {
        (Some(uri), _) if uri.starts_with("data:") => {
            let (_, payload) = uri
                .split_once(";base64,")
                .ok_or_else(|| unreadable("its data URI is not base64".into()))?;
            decode_base64(payload)
                .ok_or_else(|| unreadable("its data URI holds invalid base64".into()))?
        }
        (Some(uri), _) => {
            let path = referenced_path(file.path, uri).map_err(|reason| {
                unreadable(format!(
                    "its uri {uri:?} {reason}; an image is a `data:` URI, a buffer view or a \
                     file in the model's folder named relative to it"
                ))
            })?;
            read_file(&path).map_err(|e| {
                unreadable(format!(
                    "{e}; keep the images beside the .gltf as it names them"
                ))
            })?
        }
        (None, Some(view)) => {
            let root = file.root();
            let v = root.buffer_views.get(view.value()).ok_or_else(|| {
                unreadable(format!("buffer view {} does not exist", view.value()))
            })?;
            let buffer = buffers.get(v.buffer.value()).ok_or_else(|| {
                unreadable(format!(
                    "buffer view {} names a missing buffer",
                    view.value()
                ))
            })?;
            let start = v.byte_offset.map_or(0, |o| o.0) as usize;
            let end = start.checked_add(v.byte_length.0 as usize);
            match end.and_then(|end| buffer.get(start..end)) {
                Some(bytes) => bytes.to_vec(),
                None => {
                    return Err(unreadable(format!(
                        "buffer view {} runs past its buffer's {} bytes",
                        view.value(),
                        buffer.len()
                    )));
                }
            }
        }
        (None, None) => return Err(unreadable("it has neither a uri nor a buffer view".into())),
    };
    decode_image(&bytes, &name)
}
