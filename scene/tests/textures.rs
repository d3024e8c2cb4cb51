//! Textures: PNG and JPEG decode to RGBA, damaged or foreign images are refused naming
//! what they are, and a glTF scene's sampled images are decoded once, with their wrap
//! modes; an image that cannot be used falls back to the factors with a warning, or is
//! an error with `strict_textures`.

mod common;

use std::sync::Arc;

use meshlight_scene::SceneError;
use meshlight_scene::load::{
    GltfScene, IDENTITY_UV_TRANSFORM, LoadOptions, UvTransform, Wrap, load_gltf_scene,
    load_gltf_scene_with,
};
use meshlight_scene::texture::{
    ColorSpace, Image, MAX_IMAGE_SIDE, TextureError, decode_image, mip_chain, resample_square,
};
use meshlight_testing::gltf_writer::{GltfWriter, Node, Primitive, jpeg_bytes, json, png_bytes};

/// An `n × n` checkerboard of `a` and `b` squares of `cell` pixels.
fn checker(n: u32, cell: u32, a: [u8; 4], b: [u8; 4]) -> Image {
    let mut rgba = Vec::new();
    for y in 0..n {
        for x in 0..n {
            rgba.extend_from_slice(if (x / cell + y / cell).is_multiple_of(2) {
                &a
            } else {
                &b
            });
        }
    }
    Image {
        width: n,
        height: n,
        rgba,
    }
}

#[test]
fn a_png_decodes_exactly_and_a_jpeg_closely() {
    let image = checker(8, 2, [250, 20, 30, 255], [10, 40, 200, 128]);
    let png = png_bytes(8, 8, &image.rgba);
    assert_eq!(decode_image(&png, "checker.png").unwrap(), image);

    // A smooth gradient survives JPEG at quality 95 within a few steps per channel.
    let (w, h) = (48u16, 32u16);
    let rgb: Vec<u8> = (0..h as u32)
        .flat_map(|y| (0..w as u32).flat_map(move |x| [(x * 5) as u8, (y * 7) as u8, 128]))
        .collect();
    let jpeg = jpeg_bytes(w, h, &rgb, 95);
    let got = decode_image(&jpeg, "gradient.jpg").unwrap();
    assert_eq!((got.width, got.height), (48, 32));
    let mut error = 0u64;
    for (p, q) in got.rgba.chunks_exact(4).zip(rgb.chunks_exact(3)) {
        assert_eq!(p[3], 255);
        for c in 0..3 {
            error += (p[c] as i32 - q[c] as i32).unsigned_abs() as u64;
        }
    }
    let mean = error as f64 / (w as f64 * h as f64 * 3.0);
    assert!(mean < 3.0, "mean error {mean}");
}

#[test]
fn damaged_and_foreign_images_are_refused_naming_what_they_are() {
    let refused = |bytes: &[u8]| decode_image(bytes, "t.img").unwrap_err();
    let ktx2 = b"\xabKTX 20\xbb\r\n\x1a\n and more";
    for (bytes, says) in [
        (&b""[..], "empty"),
        (&ktx2[..], "KTX2"),
        (&b"RIFF\0\0\0\0WEBPVP8 "[..], "WebP"),
        (&b"GIF89a"[..], "GIF"),
        (&b"hello world"[..], "68 65 6c 6c"),
    ] {
        match refused(bytes) {
            e @ TextureError::UnsupportedFormat { .. } => {
                let msg = e.to_string();
                assert!(
                    msg.contains(says) && msg.contains("t.img") && msg.contains("PNG or JPEG"),
                    "{msg}"
                );
            }
            other => panic!("{says}: {other:?}"),
        }
    }
    let png = png_bytes(8, 8, &[7; 256]);
    for cut in [20, 40, png.len() - 13] {
        match refused(&png[..cut]) {
            TextureError::Corrupt { format: "PNG", .. } => {}
            other => panic!("PNG cut at {cut}: {other:?}"),
        }
    }
    let jpeg = jpeg_bytes(16, 16, &[90; 768], 80);
    match refused(&jpeg[..jpeg.len() / 3]) {
        TextureError::Corrupt { format: "JPEG", .. } => {}
        // A truncated scan may still decode (with grey blocks), but never panics.
        other => panic!("truncated JPEG: {other:?}"),
    }
    let wide = png_bytes(
        MAX_IMAGE_SIDE + 1,
        1,
        &vec![0; (MAX_IMAGE_SIDE as usize + 1) * 4],
    );
    match refused(&wide) {
        e @ TextureError::Size { .. } => assert!(e.to_string().contains("16385 × 1"), "{e}"),
        other => panic!("too wide: {other:?}"),
    }
}

/// Every prefix and many single-byte changes of a PNG and a JPEG: decoded or refused,
/// never a panic.
#[test]
fn mutated_images_never_panic() {
    let png = png_bytes(8, 8, &checker(8, 2, [1, 2, 3, 4], [200; 4]).rgba);
    let jpeg = jpeg_bytes(16, 8, &[120; 16 * 8 * 3], 70);
    for bytes in [png, jpeg] {
        for cut in 0..bytes.len() {
            let _ = decode_image(&bytes[..cut], "cut");
        }
        for i in 0..bytes.len() {
            for flip in [0x01u8, 0x80, 0xff] {
                let mut b = bytes.clone();
                b[i] ^= flip;
                let _ = decode_image(&b, "flipped");
            }
        }
    }
}

#[test]
fn a_non_square_texture_is_resampled_and_mipped_to_one_texel() {
    let image = checker(6, 1, [255, 255, 255, 255], [0, 0, 0, 255]);
    let square = resample_square(&image, 8, ColorSpace::Srgb);
    let chain = mip_chain(&square, ColorSpace::Srgb);
    assert_eq!(
        chain.levels.iter().map(|l| l.width).collect::<Vec<_>>(),
        [8, 4, 2, 1]
    );
    // Half the light of white, whichever way it was resampled: sRGB 188 give or take.
    let grey = chain.levels[3].texel(0, 0)[0];
    assert!((180..=196).contains(&grey), "{grey}");
}

/// The unit quad with UVs (the image upright on it) in `material`.
fn quad(material: usize) -> Primitive {
    Primitive {
        uvs: Some(vec![[0.0, 1.0], [1.0, 1.0], [1.0, 0.0], [0.0, 0.0]]),
        material: Some(material),
        ..common::gltf::unit_quad()
    }
}

/// A quad whose material samples `base` as its base colour and `normal` as its normal
/// texture.
fn textured_scene(w: &mut GltfWriter, base: usize, normal: Option<usize>) {
    let mut material = json!({"pbrMetallicRoughness": {"baseColorTexture": {"index": base}}});
    if let Some(n) = normal {
        material["normalTexture"] = json!({"index": n, "scale": 0.5});
    }
    let m = w.material(material);
    quad_scene(w, m);
}

/// `w`'s scene: one node placing the quad in material `m`.
fn quad_scene(w: &mut GltfWriter, m: usize) {
    let mesh = w.mesh("quad", &[quad(m)]);
    let node = w.node(Node {
        mesh: Some(mesh),
        ..Node::default()
    });
    w.scene(&[node]);
}

#[test]
fn a_scenes_sampled_images_are_decoded_once_with_their_wrap_modes() {
    let image = checker(4, 1, [255, 0, 0, 255], [0, 0, 255, 255]);
    let mut w = GltfWriter::new();
    let png = w.image_bytes(&png_bytes(4, 4, &image.rgba), "image/png");
    let jpeg = jpeg_bytes(8, 8, &[128; 192], 90);
    let uri = format!("data:image/jpeg;base64,{}", common::base64(&jpeg));
    let normal_image = w.image_uri(&uri);
    // Never sampled: not decoded, though it would not decode.
    let unused_image = w.image_bytes(b"not an image", "image/png");
    let clamped = w.texture(png, Some(json!({"wrapS": 33071, "wrapT": 33648})));
    let normal = w.texture(normal_image, None);
    let _unused = w.texture(unused_image, None);
    let again = w.texture(png, None);
    textured_scene(&mut w, clamped, Some(normal));
    // A second material samples the same image through another texture.
    w.material(json!({"emissiveTexture": {"index": again}}));
    let dir = common::scratch("gltf-textures");
    let path = dir.join("textured.glb");
    std::fs::write(&path, w.glb()).unwrap();
    let scene = load_gltf_scene(&path).unwrap();
    assert!(scene.warnings.is_empty(), "{:?}", scene.warnings);
    assert_eq!(scene.textures.len(), 4);
    let t = &scene.textures;
    assert_eq!(t[clamped].image.as_deref(), Some(&image));
    assert_eq!(t[clamped].wrap, [Wrap::ClampToEdge, Wrap::MirroredRepeat]);
    assert_eq!(t[normal].wrap, [Wrap::Repeat; 2]);
    let n = t[normal].image.as_ref().unwrap();
    assert_eq!((n.width, n.height), (8, 8));
    assert!(t[2].image.is_none());
    // One decode shared by both textures of the image.
    assert!(Arc::ptr_eq(
        t[clamped].image.as_ref().unwrap(),
        t[again].image.as_ref().unwrap()
    ));
    let m = &scene.materials[0];
    assert_eq!(m.base_color_texture.map(|r| r.texture), Some(clamped));
    assert_eq!(m.normal_scale, 0.5);
}

fn scene_with_image(
    name: &str,
    set_up: impl FnOnce(&mut GltfWriter) -> usize,
) -> std::path::PathBuf {
    let mut w = GltfWriter::new();
    let image = set_up(&mut w);
    let texture = w.texture(image, None);
    textured_scene(&mut w, texture, None);
    let dir = common::scratch(&format!("gltf-bad-image-{name}"));
    let path = dir.join("model.glb");
    std::fs::write(&path, w.glb()).unwrap();
    path
}

#[test]
fn an_image_that_cannot_be_used_is_a_warning_or_with_strict_textures_an_error() {
    let outside = common::scratch("gltf-bad-image-outside-target").join("secret.png");
    std::fs::write(&outside, png_bytes(1, 1, &[1, 2, 3, 4])).unwrap();
    type SetUp = Box<dyn FnOnce(&mut GltfWriter) -> usize>;
    let cases: [(&str, SetUp, &str); 5] = [
        (
            "missing",
            Box::new(|w| w.image_uri("missing.png")),
            "missing.png",
        ),
        (
            "outside",
            Box::new(|w| w.image_uri("../gltf-bad-image-outside-target/secret.png")),
            "leaves the model's folder",
        ),
        (
            "corrupt",
            Box::new(|w| w.image_bytes(b"\x89PNG\r\n\x1a\n\0\0\0\rIHDR", "image/png")),
            "does not decode",
        ),
        (
            "ktx2",
            Box::new(|w| w.image_bytes(b"\xabKTX 20\xbb\r\n\x1a\n", "image/ktx2")),
            "KTX2",
        ),
        (
            "no-source",
            Box::new(|w| w.image_uri("data:image/png,plain")),
            "not base64",
        ),
    ];
    for (name, set_up, says) in cases {
        let path = scene_with_image(name, set_up);
        let scene = load_gltf_scene(&path).unwrap_or_else(|e| panic!("{name}: {e}"));
        assert_eq!(scene.warnings.len(), 1, "{name}: {:?}", scene.warnings);
        let warning = &scene.warnings[0];
        assert!(
            warning.contains(says) && warning.contains("image 0") && warning.contains("factors"),
            "{name}: {warning}"
        );
        assert!(scene.textures[0].image.is_none(), "{name}");
        let strict = LoadOptions {
            strict_textures: true,
            ..LoadOptions::default()
        };
        match load_gltf_scene_with(&path, &strict) {
            Err(e @ SceneError::GltfTexture { image: 0, .. }) => {
                let msg = e.to_string();
                assert!(
                    msg.contains(says) && msg.contains("model.glb"),
                    "{name}: {msg}"
                );
            }
            other => panic!("{name}: expected GltfTexture, got {other:?}"),
        }
    }
}

#[test]
fn a_texture_without_an_existing_image_is_refused() {
    let mut w = GltfWriter::new();
    let texture = w.texture(3, None);
    textured_scene(&mut w, texture, None);
    let path = common::scratch("gltf-texture-source").join("model.glb");
    std::fs::write(&path, w.glb()).unwrap();
    match load_gltf_scene(&path) {
        Err(e @ SceneError::Gltf { .. }) => {
            assert!(e.to_string().contains("texture 0 has image 3"), "{e}")
        }
        other => panic!("expected a glTF error, got {other:?}"),
    }
}

/// A scene of one quad whose material is `material` (textures 0 and 1 exist).
fn scene_with_material(name: &str, material: serde_json::Value) -> Result<GltfScene, SceneError> {
    let image = checker(4, 1, [255, 0, 0, 255], [0, 0, 255, 255]);
    let mut w = GltfWriter::new();
    let png = w.image_bytes(&png_bytes(4, 4, &image.rgba), "image/png");
    w.texture(png, None);
    w.texture(png, None);
    let m = w.material(material);
    quad_scene(&mut w, m);
    let path = common::scratch(&format!("gltf-transform-{name}")).join("t.glb");
    std::fs::write(&path, w.glb()).unwrap();
    load_gltf_scene(&path)
}

/// `KHR_texture_transform` as the extension's own example reads it: offset (0, 1), a
/// quarter turn and half scale take the unit square to the image's lower-left quarter
/// (V runs down). A material whose maps disagree says so; `texCoord` overrides the set.
#[test]
fn texture_transforms_are_read_as_the_extension_defines_them() {
    let quarter = std::f32::consts::FRAC_PI_2;
    let example = json!({"offset": [0.0, 1.0], "rotation": quarter, "scale": [0.5, 0.5]});
    let scene = scene_with_material(
        "example",
        json!({
            "pbrMetallicRoughness": {"baseColorTexture": {"index": 0,
                "extensions": {"KHR_texture_transform": example}}},
            "normalTexture": {"index": 1, "extensions": {"KHR_texture_transform":
                {"scale": [4.0, 4.0], "texCoord": 0}}},
            "emissiveTexture": {"index": 1, "extensions": {"KHR_texture_transform":
                {"texCoord": 1}}}
        }),
    )
    .unwrap();
    let m = &scene.materials[0];
    let base = m.base_color_texture.unwrap().transform;
    let apply = |t: UvTransform, [u, v]: [f32; 2]| t.map(|r| r[0] * u + r[1] * v + r[2]);
    for (corner, expected) in [
        ([0.0, 0.0], [0.0, 1.0]),
        ([1.0, 0.0], [0.0, 0.5]),
        ([1.0, 1.0], [0.5, 0.5]),
        ([0.0, 1.0], [0.5, 1.0]),
    ] {
        let got = apply(base, corner);
        assert!(
            (got[0] - expected[0]).abs() < 1e-6 && (got[1] - expected[1]).abs() < 1e-6,
            "{corner:?} went to {got:?}, not {expected:?}"
        );
    }
    let normal = m.normal_texture.unwrap();
    assert_eq!(normal.transform, [[4.0, 0.0, 0.0], [0.0, 4.0, 0.0]]);
    assert_eq!(normal.tex_coord, 0);
    let emissive = m.emissive_texture.unwrap();
    assert_eq!(emissive.transform, IDENTITY_UV_TRANSFORM);
    assert_eq!(
        emissive.tex_coord, 1,
        "texCoord overrides the texture's set"
    );
    assert_eq!(
        m.uv_transform(),
        (base, true),
        "the base colour's wins; maps disagree"
    );
    // Without a transform anywhere, the identity, and no disagreement.
    let plain = scene_with_material(
        "plain",
        json!({"pbrMetallicRoughness": {"baseColorTexture": {"index": 0}}}),
    )
    .unwrap();
    assert_eq!(
        plain.materials[0].uv_transform(),
        (IDENTITY_UV_TRANSFORM, false)
    );
}

#[test]
fn damaged_texture_transforms_are_refused_naming_the_field() {
    for (name, transform, needle) in [
        (
            "rotation",
            json!({"rotation": "quarter"}),
            "rotation \"quarter\"",
        ),
        (
            "offset",
            json!({"offset": [1.0]}),
            "offset [1.0], not two numbers",
        ),
        (
            "scale",
            json!({"scale": [1e300, 1.0]}),
            "scale 1e+300, not a number a 32-bit float holds",
        ),
        ("set", json!({"texCoord": -1}), "texCoord -1"),
    ] {
        let material = json!({"pbrMetallicRoughness": {"baseColorTexture": {"index": 0,
            "extensions": {"KHR_texture_transform": transform}}}});
        let err = scene_with_material(name, material).expect_err(name);
        let msg = err.to_string();
        assert!(matches!(err, SceneError::Gltf { .. }), "{name}: {err:?}");
        for needle in ["base colour texture's KHR_texture_transform", needle] {
            assert!(
                msg.contains(needle),
                "{name}: {needle:?} missing from: {msg}"
            );
        }
    }
}
