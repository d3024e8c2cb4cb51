//! The CPU reference of `fill_clusters`, and the f32 mirrors of the shared WGSL it uses.
//!
//! The instance test is the WGSL's operation for operation (matrix times vector as a sum
//! of columns in order, dot products left to right), so an instance decides the same way
//! here and on the GPU except when its sphere touches a plane to within rounding.

use meshlight_gpu_scene::SceneData;
use meshlight_shaders::cpu::layout::{Cluster, Instance, View};
use meshlight_shaders::cpu::matrix::mat_vec;

/// What `fill_clusters` produces for a scene and a view.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct FillResult {
    /// Every requested cluster: the visible instances in instance order, each instance's
    /// meshlets in meshlet order. The GPU writes the same clusters, each instance's as one
    /// contiguous run, but the runs in the order its atomics granted them; past the
    /// capacity it writes only what fits.
    pub clusters: Vec<Cluster>,
    /// Instances whose bounding sphere touches the frustum, in instance order.
    pub visible_instances: Vec<u32>,
    /// `cluster_count[1]`: clusters requested.
    pub requested: u32,
    /// `cluster_count[0]`: `min(requested, capacity)`.
    pub written: u32,
}

fn dot3(a: [f32; 3], b: [f32; 3]) -> f32 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// `instance_max_scale`: the largest axis scale of the instance's transform.
pub fn instance_max_scale(instance: &Instance) -> f32 {
    let m = &instance.world_from_local;
    let axis = |c: usize| {
        let v = [m[c][0], m[c][1], m[c][2]];
        dot3(v, v)
    };
    let (x, y, z) = (axis(0), axis(1), axis(2));
    x.max(y.max(z)).sqrt()
}

/// `instance_transform_sphere`: a mesh-space sphere in world space.
pub fn instance_transform_sphere(instance: &Instance, sphere: [f32; 4]) -> [f32; 4] {
    let c = mat_vec(
        &instance.world_from_local,
        [sphere[0], sphere[1], sphere[2], 1.0],
    );
    [c[0], c[1], c[2], sphere[3] * instance_max_scale(instance)]
}

/// The smallest of `dot(plane.xyz, centre) + plane.w + radius` over the frustum planes:
/// `sphere_in_frustum` keeps the sphere when it is not negative. Its size tells how close
/// a decision is to flipping under rounding.
pub fn frustum_margin(view: &View, center: [f32; 3], radius: f32) -> f32 {
    view.frustum
        .iter()
        .map(|p| dot3([p[0], p[1], p[2]], center) + p[3] + radius)
        .fold(f32::INFINITY, f32::min)
}

/// `sphere_in_frustum`, exactly as the WGSL compares (a NaN distance keeps the sphere).
#[allow(clippy::neg_cmp_op_on_partial_ord)]
pub fn sphere_in_frustum(view: &View, center: [f32; 3], radius: f32) -> bool {
    view.frustum
        .iter()
        .all(|p| !(dot3([p[0], p[1], p[2]], center) + p[3] < -radius))
}

/// The instance's mesh bounding sphere in world space.
pub fn instance_sphere(scene: &SceneData, instance: &Instance) -> [f32; 4] {
    let mesh = &scene.meshes[instance.mesh as usize];
    instance_transform_sphere(instance, mesh.bounding_sphere)
}

/// The reference: which instances are visible and the clusters they request.
pub fn cpu_fill(scene: &SceneData, view: &View, capacity: u32) -> FillResult {
    let mut result = FillResult::default();
    for (index, instance) in scene.instances.iter().enumerate() {
        let s = instance_sphere(scene, instance);
        if instance.meshlet_count == 0 || !sphere_in_frustum(view, [s[0], s[1], s[2]], s[3]) {
            continue;
        }
        result.visible_instances.push(index as u32);
        result
            .clusters
            .extend((0..instance.meshlet_count).map(|k| Cluster {
                instance: index as u32,
                meshlet: instance.first_meshlet + k,
            }));
    }
    result.requested = result.clusters.len() as u32;
    result.written = result.requested.min(capacity);
    result
}
