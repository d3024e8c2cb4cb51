//! The virtual-geometry benchmark's scene (the app's `scenes::lattice`): `n`³ copies of a
//! mesh in a lattice 2.5 mesh radii apart, seen from outside one corner at 2240×1260.

use glam::{Mat4, Vec3};
use meshlight_gpu_scene::{Camera, Material, SceneData, data::Limits};
use meshlight_scene::MeshletAsset;
use meshlight_shaders::cpu::layout::View;

/// The viewport the benchmark draws the lattice at.
pub const VIEWPORT: [u32; 2] = [2240, 1260];

/// The lattice of `asset` and the view of it.
pub fn lattice(asset: &MeshletAsset, n: u32) -> (SceneData, View) {
    let mut data = SceneData::new(Limits::default());
    let material = data.add_material(Material {
        base_color: [1.0; 3],
    });
    let mesh = data.add_mesh("bunny", asset).unwrap();
    let radius = data.meshes[0].bounding_sphere[3];
    let spacing = radius * 2.5;
    for i in 0..n * n * n {
        let cell = Vec3::new((i % n) as f32, (i / n % n) as f32, (i / (n * n)) as f32);
        data.add_instance(mesh, Mat4::from_translation(cell * spacing), material)
            .unwrap();
    }
    let centre = Vec3::splat((n as f32 - 1.0) * 0.5 * spacing);
    let extent = n as f32 * spacing;
    let camera = Camera::perspective(
        centre + Vec3::new(0.9, 0.6, 1.2).normalize() * extent * 1.3,
        centre,
        50f32.to_radians(),
        radius * 0.05,
    );
    (data, camera.view(VIEWPORT, 0, None))
}
