//! What the GPU tests of `cull_lod` share: the adapter, a real multi-level asset
//! (spot.obj) placed a few times, every cluster of a scene, seeded random numbers.
#![allow(dead_code)]

use glam::{Mat4, Quat, Vec3};
use meshlight_gpu_scene::{Material, SceneData, data::Limits};
use meshlight_graph::GpuContext;
use meshlight_shaders::cpu::layout::Cluster;

#[allow(unused_imports)] // not every test binary that includes this module uses each
pub use meshlight_testing::{Rng, USAGE, gpu, meshes::spot};

pub fn scene_with(placements: &[Mat4]) -> SceneData {
    let mut data = SceneData::new(Limits::default());
    let material = data
        .add_material(Material {
            base_color: [1.0; 3],
            ..Material::default()
        })
        .unwrap();
    let mesh = data.add_mesh("spot", spot()).unwrap();
    for &transform in placements {
        data.add_instance(mesh, transform, material)
            .unwrap()
            .expect("an invertible transform");
    }
    data
}

/// Six instances on a 3 × 2 grid, turned and scaled differently (one unevenly).
pub fn scene() -> SceneData {
    let placements: Vec<Mat4> = (0..6)
        .map(|i| {
            let (x, z) = ((i % 3) as f32 * 3.0 - 3.0, (i / 3) as f32 * 3.0 - 1.5);
            let scale = if i == 4 {
                Vec3::new(1.5, 0.7, 1.0)
            } else {
                Vec3::splat(0.8 + 0.15 * i as f32)
            };
            Mat4::from_scale_rotation_translation(
                scale,
                Quat::from_rotation_y(i as f32 * 1.1),
                Vec3::new(x, 0.0, z),
            )
        })
        .collect();
    scene_with(&placements)
}

/// What a raster slot holds before the cull: no cluster of any scene, so a slot the pass
/// left unwritten shows.
pub const SENTINEL: Cluster = Cluster {
    instance: 0xdead_beef,
    meshlet: 0xfeed_f00d,
};

/// The buffers a cull is imported with, filled: the candidate `clusters`, their two
/// count words (every candidate written, none dropped) and `slots` raster slots holding
/// [`SENTINEL`].
pub fn cull_buffers(gpu: &GpuContext, clusters: &[Cluster], slots: u32) -> [wgpu::Buffer; 3] {
    let n = clusters.len() as u32;
    [
        gpu.buffer_with_data("clusters", bytemuck::cast_slice(clusters), USAGE),
        gpu.buffer_with_data("cluster_count", bytemuck::cast_slice(&[n; 2]), USAGE),
        gpu.buffer_with_data(
            "raster_clusters",
            bytemuck::cast_slice(&vec![SENTINEL; slots as usize]),
            USAGE,
        ),
    ]
}

/// A random camera aim: a target in the box `±extent` about the origin, and the unit
/// direction from it toward the eye, its y drawn from `rise` before normalising (so the
/// camera looks down at the scene as much as the test wants).
pub fn random_aim(rng: &mut Rng, extent: Vec3, rise: [f32; 2]) -> (Vec3, Vec3) {
    let target = Vec3::new(
        rng.range(-extent.x, extent.x),
        rng.range(-extent.y, extent.y),
        rng.range(-extent.z, extent.z),
    );
    let direction = Vec3::new(
        rng.range(-1.0, 1.0),
        rng.range(rise[0], rise[1]),
        rng.range(-1.0, 1.0),
    )
    .normalize_or(Vec3::Z);
    (target, direction)
}

/// A test's starting point: the generator seeded with `seed`, the scene, and every
/// cluster of it shuffled by that generator, which the test draws from after.
pub fn seeded(seed: u64, data: SceneData) -> (Rng, SceneData, Vec<Cluster>) {
    let mut rng = Rng(seed);
    let clusters = all_clusters(&data, &mut rng);
    (rng, data, clusters)
}

/// Every meshlet of every instance, in a seeded shuffled order.
pub fn all_clusters(data: &SceneData, rng: &mut Rng) -> Vec<Cluster> {
    let mut clusters: Vec<Cluster> = data
        .instances
        .iter()
        .enumerate()
        .flat_map(|(i, inst)| {
            (0..inst.meshlet_count).map(move |k| Cluster {
                instance: i as u32,
                meshlet: inst.first_meshlet + k,
            })
        })
        .collect();
    for i in (1..clusters.len()).rev() {
        clusters.swap(i, rng.below(i as u32 + 1) as usize);
    }
    clusters
}
