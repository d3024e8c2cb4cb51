//! What the frame's tests share: the small procedural mesh they draw, and an empty scene
//! holding it for tests that place their own instances.

#![allow(dead_code)]

use meshlight::gpu_scene::data::{Limits, MeshId};
use meshlight::gpu_scene::{Material, SceneData};
use meshlight::scene::{BuildOptions, MeshletAsset, build_asset, procedural_mesh};
use std::sync::OnceLock;

/// A small procedural mesh (9,216 triangles, several LOD levels), baked once.
pub fn asset() -> &'static MeshletAsset {
    static ASSET: OnceLock<MeshletAsset> = OnceLock::new();
    ASSET.get_or_init(|| {
        build_asset(&procedural_mesh(24), &BuildOptions::default(), &mut |_| {})
            .unwrap()
            .asset
    })
}

/// A scene with [`asset`] as its mesh and one grey material, and no instances yet: the
/// scene, the mesh and the material.
pub fn grey_scene() -> (SceneData, MeshId, u32) {
    let mut data = SceneData::new(Limits::default());
    let material = data
        .add_material(Material {
            base_color: [0.8; 3],
            ..Material::default()
        })
        .unwrap();
    let mesh = data.add_mesh("procedural", asset()).unwrap();
    (data, mesh, material)
}
