//! The scenes the hierarchy tests walk: fields of instances each test places, and seeded
//! random views over them.

use glam::{Mat4, Quat, Vec3};
use meshlight_gpu_scene::{Camera, Material, Projection, SceneData, data::Limits};
use meshlight_scene::{BuildOptions, Mesh, MeshletAsset, build_asset};
use meshlight_shaders::cpu::layout::View;
use meshlight_shaders::cpu::occlusion::DepthPyramid;
use meshlight_testing::Rng;

/// `mesh` baked with the default options.
pub fn bake(mesh: &Mesh) -> MeshletAsset {
    build_asset(mesh, &BuildOptions::default(), &mut |_| {})
        .unwrap()
        .asset
}

/// Two meshes (the bunny and spot, so hierarchies are rebased in the shared buffers) on
/// a 4 × 3 field, turned and scaled differently (one unevenly), in bunny radii.
pub fn bunny_and_spot() -> SceneData {
    use meshlight_testing::meshes::{bunny, spot};
    field(&[("bunny", bunny()), ("spot", spot())], 12, |i| {
        let (x, z) = ((i % 4) as f32, (i / 4) as f32);
        let mut scale = Vec3::splat(0.7 + 0.1 * (i % 5) as f32);
        if i == 5 {
            scale = Vec3::new(1.5, 0.6, 1.0);
        }
        (scale, i as f32 * 1.3, Vec3::new(x * 3.0, 0.0, z * 3.0))
    })
}

/// Random views of [`bunny_and_spot`]'s field, from within it to 48 bunny radii away
/// (every fourth orthographic), at thresholds of 0.5, 1 and 2 px.
pub const BUNNY_AND_SPOT_VIEWS: Views = Views {
    target: [Vec3::new(-1.0, -0.5, -1.0), Vec3::new(10.0, 1.0, 7.0)],
    lowest: -0.3,
    distance: [0.4, 120.0],
    viewports: &[[320, 240], [640, 360], [1280, 720]],
    fov: [0.5, 1.5],
    thresholds: &[0.5, 1.0, 2.0],
};

/// `count` instances of `meshes` (`(name, asset)`; instance `i` takes `meshes[i % len]`)
/// with one material. `place(i)` gives instance `i`'s scale (each mesh first scaled to
/// the first one's radius), its turn about y, and its position in radii of the first mesh.
pub fn field(
    meshes: &[(&str, &MeshletAsset)],
    count: u32,
    place: impl Fn(u32) -> (Vec3, f32, Vec3),
) -> SceneData {
    let mut data = SceneData::new(Limits::default());
    let material = data
        .add_material(Material {
            base_color: [1.0; 3],
            ..Material::default()
        })
        .unwrap();
    let ids: Vec<_> = meshes
        .iter()
        .map(|(name, asset)| data.add_mesh(name, asset).unwrap())
        .collect();
    let radius = data.meshes[0].bounding_sphere[3];
    for i in 0..count {
        let mesh = i as usize % ids.len();
        let (scale, turn, position) = place(i);
        let transform = Mat4::from_scale_rotation_translation(
            scale * (radius / data.meshes[mesh].bounding_sphere[3]),
            Quat::from_rotation_y(turn),
            position * radius,
        );
        data.add_instance(ids[mesh], transform, material)
            .unwrap()
            .expect("an invertible transform");
    }
    data
}

/// Where seeded random views of a field look from, in radii of its first mesh.
#[derive(Clone, Copy)]
pub struct Views {
    /// The box the target is drawn in.
    pub target: [Vec3; 2],
    /// The eye lies from the target along a direction drawn in x, z ∈ (-1, 1) and
    /// y ∈ (`lowest`, 1).
    pub lowest: f32,
    /// `[nearest, ratio]`: the eye's distance, log-uniform from `nearest` to `nearest × ratio`.
    pub distance: [f32; 2],
    pub viewports: &'static [[u32; 2]],
    /// The vertical field of view's range (radians).
    pub fov: [f32; 2],
    /// The LOD thresholds a view is drawn with (px).
    pub thresholds: &'static [f32],
}

impl Views {
    /// `count` views of `data`'s field drawn from `seed`: `(number, view, threshold)`.
    pub fn seeded(
        self,
        data: &SceneData,
        seed: u64,
        count: u32,
    ) -> impl Iterator<Item = (u32, View, f32)> + use<> {
        let radius = data.meshes[0].bounding_sphere[3];
        let mut rng = Rng(seed);
        (0..count).map(move |v| {
            let (view, threshold) = self.draw(radius, &mut rng, v);
            (v, view, threshold)
        })
    }

    /// View number `v` of a field whose first mesh has this radius, and its threshold.
    fn draw(&self, radius: f32, rng: &mut Rng, v: u32) -> (View, f32) {
        let [low, high] = self.target;
        let target = Vec3::new(
            rng.range(low.x, high.x),
            rng.range(low.y, high.y),
            rng.range(low.z, high.z),
        ) * radius;
        let direction = Vec3::new(
            rng.range(-1.0, 1.0),
            rng.range(self.lowest, 1.0),
            rng.range(-1.0, 1.0),
        )
        .normalize_or(Vec3::Z);
        let [nearest, ratio] = self.distance;
        let distance = radius * nearest * ratio.powf(rng.unit());
        let viewport = self.viewports[rng.below(self.viewports.len() as u32) as usize];
        let fov = rng.range(self.fov[0], self.fov[1]);
        let mut camera =
            Camera::perspective(target + direction * distance, target, fov, radius * 0.02);
        // Every fourth view orthographic (a shadow cascade's kind), spanning what the
        // perspective view spans at the target.
        if v % 4 == 3 {
            camera.projection = Projection::Orthographic {
                height: 2.0 * distance * (0.5 * fov).tan(),
                near: radius * 0.02,
                far: distance * 4.0,
            };
        }
        let threshold = self.thresholds[rng.below(self.thresholds.len() as u32) as usize];
        (camera.view(viewport, v, None), threshold)
    }
}

/// Rectangles of depth, each nearer than a random instance, on an empty image of
/// `viewport`: a pyramid that hides some of a field seen through `view`.
pub fn walls(
    rng: &mut Rng,
    data: &SceneData,
    view: &View,
    viewport: [u32; 2],
    count: u32,
) -> DepthPyramid {
    let [w, h] = viewport;
    let mut depth = vec![0.0f32; (w * h) as usize];
    let eye = Vec3::from(view.camera_position);
    for _ in 0..count {
        let instance = &data.instances[rng.below(data.instances.len() as u32) as usize];
        let at = Vec3::from_slice(&instance.world_from_local[3][..3]);
        let d = view.near / ((at - eye).length() * rng.range(0.3, 0.9));
        let (x0, y0) = (rng.below(w / 2), rng.below(h / 2));
        let (x1, y1) = (
            (x0 + w / 4 + rng.below(w / 2)).min(w),
            (y0 + h / 4 + rng.below(h / 2)).min(h),
        );
        for y in y0..y1 {
            for x in x0..x1 {
                let p = &mut depth[(y * w + x) as usize];
                *p = p.max(d);
            }
        }
    }
    DepthPyramid::from_depth(w, h, &depth)
}
