//! Textures as the renderer takes them: decoded once from PNG or JPEG into 8-bit RGBA,
//! brought to a square power-of-two size, and given a full mip chain, filtered in linear
//! light where the texels are sRGB.
//!
//! Why square powers of two: the GPU keeps every texture in one storage buffer, which a
//! shader without descriptor arrays can still index per pixel, and filters them itself;
//! a square power-of-two chain is addressed from its side alone (level `L` starts at a
//! closed-form offset), keeps its UV mapping (UVs are relative to the image), wraps
//! exactly, and its mips halve evenly down to 1 × 1. The decoders need the `build`
//! feature; the resampling and mips do not.

#[cfg(feature = "build")]
mod decode;
mod mips;

#[cfg(feature = "build")]
pub use decode::{ImageFormat, decode_image, sniff_format};
pub use mips::{MipChain, from_linear, mip_chain, resample_square, srgb_to_linear, to_linear};

/// Largest width or height an image file may declare: past it, decoding is refused
/// before anything is allocated (16384 is the largest 2-D texture most GPUs take).
pub const MAX_IMAGE_SIDE: u32 = 16384;
/// Most pixels an image file may declare (a 8192 × 8192 image; 256 MiB decoded).
pub const MAX_IMAGE_PIXELS: u64 = 1 << 26;

/// A decoded image: rows top to bottom, 8-bit RGBA.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Image {
    /// Pixels per row.
    pub width: u32,
    /// Rows.
    pub height: u32,
    /// `width × height × 4` bytes.
    pub rgba: Vec<u8>,
}

impl Image {
    /// A `width × height` image of one colour.
    pub fn filled(width: u32, height: u32, rgba: [u8; 4]) -> Self {
        Self {
            width,
            height,
            rgba: rgba.repeat(width as usize * height as usize),
        }
    }

    /// The texel at column `x`, row `y`.
    pub fn texel(&self, x: u32, y: u32) -> [u8; 4] {
        let at = (y as usize * self.width as usize + x as usize) * 4;
        [
            self.rgba[at],
            self.rgba[at + 1],
            self.rgba[at + 2],
            self.rgba[at + 3],
        ]
    }
}

/// How a texture's colour channels are encoded, which decides how they are filtered
/// and which GPU format holds them.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum ColorSpace {
    /// sRGB-encoded colour (base colour, emissive): averaged in linear light, sampled
    /// through an sRGB format. Alpha is linear either way.
    Srgb,
    /// Data (normals, metallic-roughness, occlusion): averaged as stored.
    Linear,
}

/// Why an image could not be used.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum TextureError {
    /// The image's bytes could not be read (a missing file, a bad reference).
    #[error("{name}: {reason}")]
    Unreadable {
        /// The image.
        name: String,
        /// What went wrong and what to change.
        reason: String,
    },
    /// The bytes are no format this crate decodes.
    #[error(
        "{name}: {found}, not PNG or JPEG; convert the image to PNG or JPEG (any image \
         editor or `convert`/`magick` does)"
    )]
    UnsupportedFormat {
        /// The image, as errors name it (a file or `image N of FILE`).
        name: String,
        /// What the first bytes look like.
        found: String,
    },
    /// The decoder refused the bytes.
    #[error("{name}: the {format} data does not decode ({reason}); re-export the image")]
    Corrupt {
        /// The image.
        name: String,
        /// PNG or JPEG.
        format: &'static str,
        /// The decoder's message.
        reason: String,
    },
    /// The image declares a size past [`MAX_IMAGE_SIDE`] or [`MAX_IMAGE_PIXELS`], or no
    /// pixels at all.
    #[error(
        "{name}: {width} × {height} pixels is outside what a texture may have (1 to \
         {MAX_IMAGE_SIDE} per side, at most {MAX_IMAGE_PIXELS} pixels); scale the image down"
    )]
    Size {
        /// The image.
        name: String,
        /// Declared width.
        width: u32,
        /// Declared height.
        height: u32,
    },
}
