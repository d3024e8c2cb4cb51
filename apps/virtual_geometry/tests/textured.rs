//! Textured glTF scenes drawn through the whole frame, checked against what the texture
//! and the camera say a pixel must show, not against the reference shader: the mip level
//! a footprint asks for, the texel colour a magnified checker shows, the average a
//! minified one fades to, and the tilt a normal map gives a plane.

use glam::{Vec2, Vec3};
use meshlight::gpu_scene::data::Limits;
use meshlight::gpu_scene::{Camera, SceneData};
use meshlight::resolve::DebugView;
use meshlight::resolve::cpu::id_color;
use meshlight::scene::texture::to_linear;
use meshlight_testing::gltf_writer::{GltfWriter, Node, Primitive, json, png_bytes};
use meshlight_virtual_geometry::gltf_scene::gltf_scene;
use meshlight_virtual_geometry::{FrameSettings, GraphSource, Renderer};
use std::path::{Path, PathBuf};

const W: u32 = 128;
const H: u32 = 96;
const FOV_Y: f32 = 1.0;
/// The checker texture: 64 texels a side, squares of 8.
const SIDE: u32 = 64;
const SQUARE: u32 = 8;
const LIGHT: [u8; 3] = [200, 60, 40];
const DARK: [u8; 3] = [40, 80, 220];
/// The quad spans -2..2 in X and Y with UVs 0..4: one UV unit per world unit.
const HALF: f32 = 2.0;
const TILES: f32 = 4.0;

fn scratch(name: &str) -> PathBuf {
    let dir =
        std::env::temp_dir().join(format!("meshlight-textured-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn checker_png() -> Vec<u8> {
    let mut rgba = Vec::new();
    for y in 0..SIDE {
        for x in 0..SIDE {
            let light = (x / SQUARE + y / SQUARE).is_multiple_of(2);
            rgba.extend(if light { LIGHT } else { DARK });
            rgba.push(255);
        }
    }
    png_bytes(SIDE, SIDE, &rgba)
}

/// A quad facing +Z, UVs tiling `TILES` times with V running down the image (glTF's
/// convention), `mirror_u` flipping U; its material samples `texture` as `role`.
fn quad_file(name: &str, image: &[u8], role: &str, mirror_u: bool) -> PathBuf {
    let mut w = GltfWriter::new();
    let image = w.image_bytes(image, "image/png");
    let texture = w.texture(image, None);
    let material = match role {
        "normal" => w.material(json!({
            "normalTexture": {"index": texture},
            "pbrMetallicRoughness": {"metallicFactor": 0.0}
        })),
        _ => w.material(json!({
            "pbrMetallicRoughness": {"baseColorTexture": {"index": texture}, "metallicFactor": 0.0}
        })),
    };
    let corners = [[-HALF, -HALF], [HALF, -HALF], [HALF, HALF], [-HALF, HALF]];
    let uv = |p: [f32; 2]| {
        let u = (p[0] + HALF) / (2.0 * HALF) * TILES;
        let v = (HALF - p[1]) / (2.0 * HALF) * TILES;
        [if mirror_u { TILES - u } else { u }, v]
    };
    let quad = w.mesh(
        "quad",
        &[Primitive {
            positions: corners.iter().map(|p| [p[0], p[1], 0.0]).collect(),
            normals: Some(vec![[0.0, 0.0, 1.0]; 4]),
            colors: None,
            uvs: Some(corners.iter().map(|&p| uv(p)).collect()),
            indices: vec![0, 1, 2, 0, 2, 3],
            material: Some(material),
        }],
    );
    let node = w.node(Node {
        mesh: Some(quad),
        ..Node::default()
    });
    w.scene(&[node]);
    let path = scratch(name).join("quad.glb");
    std::fs::write(&path, w.glb()).unwrap();
    path
}

fn camera_at(distance: f32) -> Camera {
    Camera::perspective(Vec3::new(0.0, 0.0, distance), Vec3::ZERO, FOV_Y, 0.05)
}

/// The world point on the plane z = 0 under the centre of pixel `(x, y)`, for a
/// camera on the +Z axis looking at the origin.
fn world_at(distance: f32, x: u32, y: u32) -> Vec2 {
    let t = (FOV_Y * 0.5).tan();
    let ndc = Vec2::new(
        (x as f32 + 0.5) / W as f32 * 2.0 - 1.0,
        1.0 - (y as f32 + 0.5) / H as f32 * 2.0,
    );
    Vec2::new(ndc.x * t * W as f32 / H as f32, ndc.y * t) * distance
}

fn render(path: &Path, view: DebugView, distance: f32) -> Vec<u8> {
    let placed =
        gltf_scene(SceneData::new(Limits::default()), path, None).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(placed.data.texture_refs.len(), 1, "one texture uploaded");
    let mut settings = FrameSettings::new(W, H);
    settings.view = Some(view);
    let mut r = Renderer::new(placed.data, settings, &GraphSource::Shipped)
        .unwrap_or_else(|e| panic!("{e}"));
    r.render_still(&camera_at(distance))
        .unwrap_or_else(|e| panic!("{e}"))
        .rgba
}

fn pixel(image: &[u8], x: u32, y: u32) -> [u8; 3] {
    let at = ((y * W + x) * 4) as usize;
    [image[at], image[at + 1], image[at + 2]]
}

fn close(got: [u8; 3], want: [f32; 3], tolerance: f32) -> bool {
    (0..3).all(|c| (got[c] as f32 - want[c]).abs() <= tolerance)
}

/// Level-0 texels per pixel at the screen's centre, for a camera `distance` away:
/// a pixel spans `2·d·tan(fov/2) / H` world units, one UV unit per world unit, `SIDE`
/// texels per UV unit.
fn texels_per_pixel(distance: f32) -> f32 {
    2.0 * distance * (FOV_Y * 0.5).tan() / H as f32 * SIDE as f32
}

#[test]
fn the_mip_view_shows_the_level_the_footprint_asks_for() {
    let path = quad_file("mip", &checker_png(), "base", false);
    for level in [0u32, 1, 2, 3] {
        // Halfway between two levels (log2 ρ = level + 0.5), so rounding cannot move it.
        let distance = 2f32.powf(level as f32 + 0.5) / texels_per_pixel(1.0);
        let image = render(&path, DebugView::Mip, distance);
        let got = pixel(&image, W / 2, H / 2);
        assert_eq!(
            got,
            id_color(level),
            "camera {distance:.2} away: {:.2} texels a pixel",
            texels_per_pixel(distance)
        );
    }
}

#[test]
fn a_magnified_checker_shows_its_texels_and_a_distant_one_their_average() {
    let path = quad_file("checker", &checker_png(), "base", false);
    let linear = |c: [u8; 3]| c.map(|v| to_linear(v) * 255.0);
    // Magnified (half a texel a pixel, level 0): a pixel whose UV lies a texel or more
    // inside a square shows that square's colour, in linear light.
    let distance = 0.5 / texels_per_pixel(1.0);
    let image = render(&path, DebugView::BaseColor, distance);
    let mut checked = 0;
    for y in (0..H).step_by(3) {
        for x in (0..W).step_by(3) {
            let p = world_at(distance, x, y);
            if p.x.abs() >= HALF || p.y.abs() >= HALF {
                continue;
            }
            let texel = Vec2::new(p.x + HALF, HALF - p.y) * (TILES / (2.0 * HALF)) * SIDE as f32;
            let inside = |t: f32| {
                let r = t.rem_euclid(SQUARE as f32);
                r > 1.0 && r < SQUARE as f32 - 1.0
            };
            if !(inside(texel.x) && inside(texel.y)) {
                continue;
            }
            let square = (texel.x as u32 / SQUARE + texel.y as u32 / SQUARE) % 2;
            let want = linear(if square == 0 { LIGHT } else { DARK });
            let got = pixel(&image, x, y);
            assert!(
                close(got, want, 1.0),
                "pixel ({x}, {y}): {got:?}, want {want:?}"
            );
            checked += 1;
        }
    }
    assert!(checked > 200, "only {checked} pixels checked");
    // Minified past the last level (64 texels a pixel and more): the 1 × 1 level, the
    // average of the two colours in linear light (its one texel is stored in sRGB, so
    // within a step or two).
    let distance = 100.0 / texels_per_pixel(1.0);
    let image = render(&path, DebugView::BaseColor, distance);
    let [a, b] = [linear(LIGHT), linear(DARK)];
    let want = [0, 1, 2].map(|c| (a[c] + b[c]) * 0.5);
    let got = pixel(&image, W / 2, H / 2);
    assert!(close(got, want, 2.0), "{got:?}, want {want:?}");
}

/// A normal map of one tilt, `(0.3, 0.4, √0.75)` in tangent space, on a plane facing +Z
/// whose U runs along +X and V down the image: the shading normal is the tilt with
/// tangent space's X along world +X and its Y (up the image) along world +Y; with U
/// mirrored, X runs along world −X and Y stays.
#[test]
fn a_normal_map_tilts_a_plane_along_its_derived_tangents() {
    let tilt = Vec3::new(0.3, 0.4, 0.75f32.sqrt());
    let encode = |c: f32| ((c * 0.5 + 0.5) * 255.0).round() as u8;
    let texel = [encode(tilt.x), encode(tilt.y), encode(tilt.z), 255];
    let png = png_bytes(4, 4, &texel.repeat(16));
    let decoded =
        Vec3::new(texel[0] as f32, texel[1] as f32, texel[2] as f32) / 255.0 * 2.0 - Vec3::ONE;
    for (mirror_u, world) in [
        (false, Vec3::new(decoded.x, decoded.y, decoded.z)),
        (true, Vec3::new(-decoded.x, decoded.y, decoded.z)),
    ] {
        let path = quad_file(&format!("normal-{mirror_u}"), &png, "normal", mirror_u);
        let image = render(&path, DebugView::Normal, 3.0);
        let n = world.normalize();
        let want = (n * 0.5 + Vec3::splat(0.5)).to_array().map(|c| c * 255.0);
        for (x, y) in [(W / 2, H / 2), (W / 3, H / 3), (2 * W / 3, 2 * H / 3)] {
            let got = pixel(&image, x, y);
            assert!(
                close(got, want, 1.5),
                "mirrored {mirror_u}, pixel ({x}, {y}): {got:?}, want {want:?}"
            );
        }
    }
}
