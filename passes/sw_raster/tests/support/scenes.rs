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
        indices,
        materials: Vec::new(),
    }
}
