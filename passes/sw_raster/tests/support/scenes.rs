//! Scenes the rasteriser and resolve tests draw: meshes baked with the default options,
//! and the procedural knot placed as overlapping instances. Shared by the GPU tests of
//! `sw_raster`, `hw_raster`, `brute_force` and `resolve`; each uses what it needs.
#![allow(dead_code)]

use glam::{Mat4, Quat, Vec3};
use meshlight_gpu_scene::data::Limits;
use meshlight_gpu_scene::{Material, MeshId, SceneData};
use meshlight_scene::{BuildOptions, Mesh, build_asset};

/// `mesh` baked with the default options and added to `scene` as `name`.
pub fn add_mesh(scene: &mut SceneData, name: &str, mesh: &Mesh) -> MeshId {
    let asset = build_asset(mesh, &BuildOptions::default(), &mut |_| {})
        .unwrap_or_else(|e| panic!("{e}"))
        .asset;
    scene.add_mesh(name, &asset).unwrap()
}

/// The knot (`mesh`, a `procedural_mesh`) at its place and a smaller copy moved up and
/// turned, which overlap in most views, then one more instance at each of `more`; all of
/// one material.
pub fn knot_scene(mesh: &Mesh, more: &[Mat4]) -> SceneData {
    let mut scene = SceneData::new(Limits::default());
    let knot = add_mesh(&mut scene, "knot", mesh);
    let material = scene
        .add_material(Material {
            base_color: [0.8, 0.5, 0.3],
            ..Material::default()
        })
        .unwrap();
    let moved = Mat4::from_scale_rotation_translation(
        Vec3::splat(0.6),
        Quat::from_rotation_y(0.7),
        Vec3::new(2.5, 1.0, 2.0),
    );
    for placement in [Mat4::IDENTITY, moved].iter().chain(more) {
        scene
            .add_instance(knot, *placement, material)
            .unwrap()
            .unwrap();
    }
    scene
}

/// A flat square in the plane z = 0 (facing +z), `n` × `n` cells, diagonals alternating,
/// inner vertices moved in the plane by `jitter` cells so edges cross pixels at odd
/// angles.
pub fn flat_quad(n: u32, jitter: f32) -> Mesh {
    let mut rng = meshlight_testing::Rng(3);
    let mut positions = Vec::new();
    for j in 0..=n {
        for i in 0..=n {
            let inner = i > 0 && i < n && j > 0 && j < n;
            let (dx, dy) = if inner {
                (rng.range(-jitter, jitter), rng.range(-jitter, jitter))
            } else {
                (0.0, 0.0)
            };
            positions.push(Vec3::new(
                -1.0 + 2.0 * (i as f32 + dx) / n as f32,
                -1.0 + 2.0 * (j as f32 + dy) / n as f32,
                0.0,
            ));
        }
    }
    let at = |i: u32, j: u32| j * (n + 1) + i;
    let mut indices = Vec::new();
    for j in 0..n {
        for i in 0..n {
            let [a, b, c, d] = [at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1)];
            // Counter-clockwise seen from +z.
            if (i + j) % 2 == 0 {
                indices.extend([a, b, c, a, c, d]);
            } else {
                indices.extend([a, b, d, b, c, d]);
            }
        }
    }
    Mesh {
        source: "flat quad".into(),
        normals: vec![Vec3::Z; positions.len()],
        positions,
        uvs: Vec::new(),
        colors: Vec::new(),
        indices,
        materials: Vec::new(),
    }
}

/// The cutoff of [`masked_scene`]'s MASK material.
pub const MASK_CUTOFF: f32 = 0.5;

/// A MASK material over an opaque one: instance 0 is `flat_quad(n, 0.2)` with UVs that
/// run over the texture `tiles` times, drawn with a MASK material (cutoff
/// [`MASK_CUTOFF`]) whose base colour texture is a 4 × 4 checker of alpha 0 and 255
/// (repeating), so magnified it cuts the quad into squares; instance 1 is a larger
/// opaque square half a unit behind it (z = -0.5), which the cut-out squares show.
pub fn masked_scene(n: u32, tiles: f32) -> SceneData {
    use meshlight_scene::texture::Image;
    use meshlight_shaders::cpu::layout::{MAP_BASE_COLOR, TextureWrap};
    let mut scene = SceneData::new(Limits::default());
    let mut front = flat_quad(n, 0.2);
    front.uvs = front
        .positions
        .iter()
        .map(|p| [(p.x + 1.0) * 0.5 * tiles, (1.0 - p.y) * 0.5 * tiles])
        .collect();
    let front = add_mesh(&mut scene, "masked", &front);
    let back = add_mesh(&mut scene, "behind", &flat_quad(2, 0.0));
    let checker = Image {
        width: 4,
        height: 4,
        rgba: (0..16u32)
            .flat_map(|i| {
                [
                    230,
                    200,
                    120,
                    if (i % 4 + i / 4) % 2 == 0 { 255 } else { 0 },
                ]
            })
            .collect(),
    };
    let texture = scene
        .add_image(&checker, true, [TextureWrap::Repeat; 2])
        .unwrap();
    let mut maps = [None; meshlight_shaders::cpu::layout::MAP_COUNT];
    maps[MAP_BASE_COLOR] = Some(texture);
    let masked = scene
        .add_material(Material {
            maps,
            checker: false,
            alpha_cutoff: Some(MASK_CUTOFF),
            ..Material::default()
        })
        .unwrap();
    let opaque = scene.add_material(Material::default()).unwrap();
    scene
        .add_instance(front, Mat4::IDENTITY, masked)
        .unwrap()
        .unwrap();
    let behind = Mat4::from_scale_rotation_translation(
        Vec3::new(1.6, 1.6, 1.0),
        Quat::IDENTITY,
        Vec3::new(0.0, 0.0, -0.5),
    );
    scene.add_instance(back, behind, opaque).unwrap().unwrap();
    scene
}

/// `scene` with the cutoff of every MASK material set to `cutoff` (`None`: made opaque),
/// for references that bracket pixels whose alpha lies within rounding of the cutoff.
pub fn with_cutoff(scene: &SceneData, cutoff: Option<f32>) -> SceneData {
    use meshlight_shaders::cpu::layout::MATERIAL_FLAG_MASK;
    let mut s = scene.clone();
    for m in &mut s.materials {
        if m.flags & MATERIAL_FLAG_MASK != 0 {
            match cutoff {
                Some(c) => m.alpha_cutoff = c,
                None => m.flags &= !MATERIAL_FLAG_MASK,
            }
        }
    }
    s
}
