//! Scenes the command line, the examples and the benchmarks draw: meshes loaded (baked
//! once and cached, or read from an asset file) and instances placed.

use glam::{Mat4, Quat, Vec3};
use meshlight_gpu_scene::{Camera, Material, MeshId, SceneData};
use meshlight_scene::cache::{self, BakeProgress, Source};
use meshlight_scene::{BuildOptions, MeshletAsset, SceneError};
use meshlight_shaders::cpu::layout::{ClusterableKind, ClusterableObject};
use std::path::Path;

/// Instances of the default scene: with the 1,048,576-triangle procedural mesh, a little
/// over 10^9 source triangles.
pub const DEFAULT_INSTANCES: u32 = 1024;
/// Point lights of the default scene ([`field_lights`]).
pub const DEFAULT_LIGHTS: u32 = 256;

/// The asset of a mesh argument: `procedural` (the default mesh with `segments`), a
/// baked `.mlasset` file, or a mesh file baked on first use and cached (keyed by the
/// file's bytes and the bake options), with a progress spinner while it bakes.
pub fn load_asset(mesh: &Path, segments: u32) -> Result<MeshletAsset, SceneError> {
    if mesh.extension().is_some_and(|e| e == "mlasset") {
        return MeshletAsset::load(mesh);
    }
    let source = if mesh.as_os_str() == "procedural" {
        Source::Procedural { segments }
    } else {
        Source::File(mesh.to_path_buf())
    };
    let progress = BakeProgress::new(&source.name());
    let (asset, _) = cache::load_or_bake(
        &source,
        &BuildOptions::default(),
        &cache::cache_dir(),
        &mut |p| progress.report(p),
    )?;
    Ok(asset)
}

/// A small deterministic generator, so scenes are the same on every run.
struct Rng(u64);

impl Rng {
    fn unit(&mut self) -> f32 {
        self.0 = self
            .0
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(1_442_695_040_888_963_407);
        (self.0 >> 40) as f32 / (1u64 << 24) as f32
    }
}

/// A scene and the camera that frames it.
pub struct Placed {
    pub data: SceneData,
    pub camera: Camera,
}

fn palette(data: &mut SceneData) -> Vec<u32> {
    [
        [0.80, 0.34, 0.24],
        [0.86, 0.70, 0.30],
        [0.36, 0.62, 0.38],
        [0.30, 0.50, 0.78],
        [0.70, 0.70, 0.72],
        [0.58, 0.36, 0.66],
    ]
    .into_iter()
    .map(|base_color| data.add_material(Material { base_color }))
    .collect()
}

/// `instances` copies of `asset` on a square field of the ground plane, each turned
/// and scaled a little, seen from a low camera at one corner looking across the field
/// to the horizon: near copies fill the screen, far ones shrink to a few pixels, so
/// every LOD level shows.
pub fn field(
    mut data: SceneData,
    asset: &MeshletAsset,
    instances: u32,
) -> Result<Placed, meshlight_gpu_scene::SceneDataError> {
    let materials = palette(&mut data);
    let mesh = data.add_mesh("mesh", asset)?;
    let radius = mesh_radius(&data, mesh);
    let side = (instances as f32).sqrt().ceil().max(1.0) as u32;
    let spacing = radius * 2.6;
    let mut rng = Rng(0x6d65_7368_6c69_6768);
    for i in 0..instances {
        let (col, row) = (i % side, i / side);
        let jitter = Vec3::new(rng.unit() - 0.5, 0.0, rng.unit() - 0.5) * spacing * 0.3;
        let position = Vec3::new(col as f32, 0.0, row as f32) * spacing + jitter;
        let scale = 0.8 + 0.4 * rng.unit();
        let turn = Quat::from_rotation_y(rng.unit() * std::f32::consts::TAU);
        let transform = Mat4::from_scale_rotation_translation(
            Vec3::splat(scale),
            turn,
            position + Vec3::Y * radius * scale,
        );
        let material = materials[i as usize % materials.len()];
        data.add_instance(mesh, transform, material)?;
    }
    let extent = side as f32 * spacing;
    let camera = Camera::perspective(
        Vec3::new(-1.5 * radius, radius * 2.6, -1.5 * radius),
        Vec3::new(extent * 0.7, radius * 0.4, extent),
        55f32.to_radians(),
        radius * 0.05,
    );
    Ok(Placed { data, camera })
}

/// An `n × n × n` lattice of `asset` (the virtual-geometry benchmark's 15³ bunnies),
/// seen from outside one corner so the whole lattice is in view.
pub fn lattice(
    mut data: SceneData,
    asset: &MeshletAsset,
    n: u32,
) -> Result<Placed, meshlight_gpu_scene::SceneDataError> {
    let materials = palette(&mut data);
    let mesh = data.add_mesh("mesh", asset)?;
    let radius = mesh_radius(&data, mesh);
    let spacing = radius * 2.5;
    for i in 0..n * n * n {
        let cell = Vec3::new((i % n) as f32, (i / n % n) as f32, (i / (n * n)) as f32);
        let transform = Mat4::from_translation(cell * spacing);
        data.add_instance(mesh, transform, materials[i as usize % materials.len()])?;
    }
    let centre = Vec3::splat((n as f32 - 1.0) * 0.5 * spacing);
    let extent = n as f32 * spacing;
    let camera = Camera::perspective(
        centre + Vec3::new(0.9, 0.6, 1.2).normalize() * extent * 1.3,
        centre,
        50f32.to_radians(),
        radius * 0.05,
    );
    Ok(Placed { data, camera })
}

/// One instance at the origin, and a camera that frames it (for `--instances 1`).
pub fn single(
    data: SceneData,
    asset: &MeshletAsset,
) -> Result<Placed, meshlight_gpu_scene::SceneDataError> {
    let mut placed = field(data, asset, 1)?;
    let mesh = &placed.data.meshes[0];
    let s = mesh.bounding_sphere;
    let centre = placed.data.instances.first().map_or(Vec3::ZERO, |i| {
        Mat4::from_cols_array_2d(&i.world_from_local).transform_point3(Vec3::new(s[0], s[1], s[2]))
    });
    placed.camera = Camera::perspective(
        centre + Vec3::new(0.45, 0.55, 1.0).normalize() * s[3] * 2.6,
        centre,
        40f32.to_radians(),
        s[3] * 0.05,
    );
    Ok(placed)
}

fn mesh_radius(data: &SceneData, mesh: MeshId) -> f32 {
    data.meshes[mesh.0 as usize].bounding_sphere[3].max(1e-6)
}

/// Lights of the default scene: `count` coloured point lights hovering over instances of
/// a [`field`], spread evenly over it, each reaching its neighbours' instances.
pub fn field_lights(placed: &Placed, count: u32) -> Vec<ClusterableObject> {
    let instances = &placed.data.instances;
    if instances.is_empty() || count == 0 {
        return Vec::new();
    }
    let radius = placed
        .data
        .meshes
        .first()
        .map_or(1.0, |m| m.bounding_sphere[3].max(1e-6));
    let mut rng = Rng(0x6c69_6768_7473_0001);
    (0..count)
        .map(|i| {
            let instance = &instances[(i as usize * instances.len()) / count as usize];
            let at = Mat4::from_cols_array_2d(&instance.world_from_local)
                .w_axis
                .truncate();
            let offset = Vec3::new(rng.unit() - 0.5, 0.0, rng.unit() - 0.5) * radius * 2.0;
            let p = at + offset + Vec3::Y * radius * (1.2 + rng.unit());
            let hue = rng.unit() * std::f32::consts::TAU;
            let color = [0.0f32, 2.1, 4.2].map(|phase| 0.55 + 0.45 * (hue + phase).cos());
            ClusterableObject {
                position_range: [p.x, p.y, p.z, radius * 3.5],
                direction_cos_angle: [0.0, -1.0, 0.0, 1.0],
                color_intensity: [color[0], color[1], color[2], radius * radius * 4.0],
                kind: ClusterableKind::PointLight as u32,
                ..ClusterableObject::default()
            }
        })
        .collect()
}
