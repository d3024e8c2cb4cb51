//! PNG and JPEG to 8-bit RGBA, with the declared size checked before the pixels are
//! allocated.

use super::{Image, MAX_IMAGE_PIXELS, MAX_IMAGE_SIDE, TextureError};

/// The image formats [`decode_image`] reads.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ImageFormat {
    /// PNG, any colour type and bit depth (16-bit channels keep their high byte).
    Png,
    /// Baseline or progressive JPEG (greyscale, YCbCr, CMYK).
    Jpeg,
}

/// The format of `bytes` from their first bytes, or what they look like instead (named
/// in the error, so that a KTX2 or WebP texture says so).
pub fn sniff_format(bytes: &[u8]) -> Result<ImageFormat, String> {
    const PNG: &[u8] = b"\x89PNG\r\n\x1a\n";
    if bytes.starts_with(PNG) {
        return Ok(ImageFormat::Png);
    }
    if bytes.starts_with(&[0xff, 0xd8, 0xff]) {
        return Ok(ImageFormat::Jpeg);
    }
    let known: [(&[u8], &str); 6] = [
        (b"\xabKTX 20", "a KTX2 texture (not supported yet)"),
        (b"\xabKTX 11", "a KTX texture"),
        (b"DDS ", "a DDS texture"),
        (b"GIF8", "a GIF image"),
        (b"BM", "a BMP image"),
        (b"sB", "a Basis Universal texture"),
    ];
    if bytes.len() >= 12 && &bytes[..4] == b"RIFF" && &bytes[8..12] == b"WEBP" {
        return Err("a WebP image".into());
    }
    for (magic, what) in known {
        if bytes.starts_with(magic) {
            return Err(what.into());
        }
    }
    Err(match bytes.len() {
        0 => "empty".into(),
        n => format!(
            "{n} bytes starting {}",
            bytes
                .iter()
                .take(8)
                .map(|b| format!("{b:02x}"))
                .collect::<Vec<_>>()
                .join(" ")
        ),
    })
}

/// Decodes a PNG or JPEG file's bytes to RGBA; `name` is quoted in errors.
pub fn decode_image(bytes: &[u8], name: &str) -> Result<Image, TextureError> {
    match sniff_format(bytes) {
        Ok(ImageFormat::Png) => decode_png(bytes, name),
        Ok(ImageFormat::Jpeg) => decode_jpeg(bytes, name),
        Err(found) => Err(TextureError::UnsupportedFormat {
            name: name.to_owned(),
            found,
        }),
    }
}

fn check_size(name: &str, width: u32, height: u32) -> Result<(), TextureError> {
    let pixels = width as u64 * height as u64;
    if width == 0
        || height == 0
        || width > MAX_IMAGE_SIDE
        || height > MAX_IMAGE_SIDE
        || pixels > MAX_IMAGE_PIXELS
    {
        return Err(TextureError::Size {
            name: name.to_owned(),
            width,
            height,
        });
    }
    Ok(())
}

fn decode_png(bytes: &[u8], name: &str) -> Result<Image, TextureError> {
    let corrupt = |e: png::DecodingError| TextureError::Corrupt {
        name: name.to_owned(),
        format: "PNG",
        reason: e.to_string(),
    };
    // The decoder's own allocation limit, above the largest image allowed.
    let limits = png::Limits {
        bytes: (MAX_IMAGE_PIXELS * 8) as usize,
    };
    let mut decoder = png::Decoder::new_with_limits(std::io::Cursor::new(bytes), limits);
    decoder.set_transformations(png::Transformations::normalize_to_color8());
    let mut reader = decoder.read_info().map_err(corrupt)?;
    let (width, height) = (reader.info().width, reader.info().height);
    check_size(name, width, height)?;
    let size = reader
        .output_buffer_size()
        .ok_or_else(|| TextureError::Size {
            name: name.to_owned(),
            width,
            height,
        })?;
    let mut buffer = vec![0u8; size];
    let frame = reader.next_frame(&mut buffer).map_err(corrupt)?;
    let data = &buffer[..frame.buffer_size()];
    let pixels = width as usize * height as usize;
    let rgba: Vec<u8> = match frame.color_type {
        png::ColorType::Rgba => data.to_vec(),
        png::ColorType::Rgb => data
            .chunks_exact(3)
            .flat_map(|p| [p[0], p[1], p[2], 255])
            .collect(),
        png::ColorType::GrayscaleAlpha => data
            .chunks_exact(2)
            .flat_map(|p| [p[0], p[0], p[0], p[1]])
            .collect(),
        png::ColorType::Grayscale => data.iter().flat_map(|&g| [g, g, g, 255]).collect(),
        png::ColorType::Indexed => {
            return Err(TextureError::Corrupt {
                name: name.to_owned(),
                format: "PNG",
                reason: "a palette image the decoder did not expand".into(),
            });
        }
    };
    if rgba.len() != pixels * 4 {
        return Err(TextureError::Corrupt {
            name: name.to_owned(),
            format: "PNG",
            reason: format!(
                "{} bytes of pixels for {width} × {height}",
                frame.buffer_size()
            ),
        });
    }
    Ok(Image {
        width,
        height,
        rgba,
    })
}

fn decode_jpeg(bytes: &[u8], name: &str) -> Result<Image, TextureError> {
    use zune_jpeg::JpegDecoder;
    use zune_jpeg::zune_core::bytestream::ZCursor;
    use zune_jpeg::zune_core::colorspace::ColorSpace;
    use zune_jpeg::zune_core::options::DecoderOptions;
    let corrupt = |reason: String| TextureError::Corrupt {
        name: name.to_owned(),
        format: "JPEG",
        reason,
    };
    let options = DecoderOptions::default()
        .jpeg_set_out_colorspace(ColorSpace::RGBA)
        .set_max_width(MAX_IMAGE_SIDE as usize)
        .set_max_height(MAX_IMAGE_SIDE as usize);
    let mut decoder = JpegDecoder::new_with_options(ZCursor::new(bytes), options);
    decoder
        .decode_headers()
        .map_err(|e| corrupt(format!("{e:?}")))?;
    let (width, height) = decoder
        .dimensions()
        .ok_or_else(|| corrupt("no frame header".into()))?;
    let (width, height) = (width as u32, height as u32);
    check_size(name, width, height)?;
    let rgba = decoder.decode().map_err(|e| corrupt(format!("{e:?}")))?;
    if rgba.len() != width as usize * height as usize * 4 {
        return Err(corrupt(format!(
            "{} bytes of pixels for {width} × {height}",
            rgba.len()
        )));
    }
    Ok(Image {
        width,
        height,
        rgba,
    })
}
