//! The virtual-geometry benchmark's scene (the app's `scenes::lattice`): `n`³ copies of a
//! mesh in a lattice 2.5 mesh radii apart, seen from outside one corner at 2240×1260.

use meshlight_gpu_scene::lattice::Lattice;
use meshlight_gpu_scene::{Material, SceneData, data::Limits};
use meshlight_scene::MeshletAsset;
use meshlight_shaders::cpu::layout::View;

/// The viewport the benchmark draws the lattice at.
pub const VIEWPORT: [u32; 2] = [2240, 1260];

/// The lattice of `asset` and the view of it.
pub fn lattice(asset: &MeshletAsset, n: u32) -> (SceneData, View) {
    let mut data = SceneData::new(Limits::default());
    let material = data
        .add_material(Material {
            base_color: [1.0; 3],
            ..Material::default()
        })
        .unwrap();
    let mesh = data.add_mesh("bunny", asset).unwrap();
    let lattice = Lattice {
        n,
        radius: data.meshes[0].bounding_sphere[3],
    };
    for transform in lattice.transforms() {
        data.add_instance(mesh, transform, material).unwrap();
    }
    (data, lattice.camera().view(VIEWPORT, 0, None))
}
