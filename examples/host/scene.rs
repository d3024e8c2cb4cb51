//! What the host draws and what it asks meshlight to draw: one mesh, the camera's
//! matrices, and two triangles of the host's own, one in front of the mesh and one
//! behind it, so the frame shows both sides of the depth composite. The host example and
//! its test share this module.

use glam::{Mat4, Vec3};
use meshlight::gpu_scene::data::Limits;
use meshlight::gpu_scene::{Material, SceneData};
use meshlight_virtual_geometry::scenes;

/// The host's triangles: the one nearer the camera than the mesh, and the one behind it.
pub const NEAR_COLOUR: [f32; 3] = [1.0, 0.0, 0.0];
/// See [`NEAR_COLOUR`].
pub const FAR_COLOUR: [f32; 3] = [0.0, 1.0, 0.0];

/// The scene meshlight draws, the camera both draw with, and the host's vertices.
pub struct HostScene {
    /// One copy of the procedural mesh, for meshlight.
    pub data: SceneData,
    /// World to view, right-handed, looking down -Z.
    pub view: Mat4,
    /// The host's projection: reverse-Z, infinite far plane.
    pub projection: Mat4,
    /// Two triangles: position and colour per vertex.
    pub vertices: Vec<[f32; 6]>,
}

/// The scene for a `width × height` window; `limits` are the device's (the scene's
/// buffers are bound whole, so they are sized for it).
pub fn host_scene(
    width: u32,
    height: u32,
    limits: &wgpu::Limits,
) -> Result<HostScene, Box<dyn std::error::Error>> {
    // A small procedural mesh (16 × 32² triangles), baked once and cached.
    let asset = scenes::load_asset(std::path::Path::new("procedural"), 32)?;
    let mut data = SceneData::new(Limits::for_device(limits));
    let mesh = data.add_mesh("knot", &asset)?;
    let material = data.add_material(Material {
        base_color: [0.86, 0.70, 0.30],
        ..Material::default()
    })?;
    data.add_instance(mesh, Mat4::IDENTITY, material)?;
    let s = data.meshes[0].bounding_sphere;
    let (centre, radius) = (Vec3::new(s[0], s[1], s[2]), s[3]);
    let eye = centre + Vec3::new(0.0, 0.3, 1.0).normalize() * radius * 2.8;
    let view = glam::camera::rh::view::look_at_mat4(eye, centre, Vec3::Y);
    let aspect = width as f32 / height.max(1) as f32;
    let projection = glam::camera::rh::proj::directx::perspective_infinite_reverse(
        45f32.to_radians(),
        aspect,
        radius * 0.05,
    );
    // In the camera's frame: right, up, and towards the mesh.
    let pose = view.inverse();
    let (right, up) = (pose.x_axis.truncate(), pose.y_axis.truncate());
    let ahead = (centre - eye).normalize();
    let distance = (centre - eye).length();
    // Halfway to the mesh, over the left of the view: nearer than anything meshlight draws.
    let near = eye + ahead * distance * 0.5 - right * radius * 0.3;
    // Past the mesh's far side: behind everything meshlight draws.
    let far = centre + ahead * radius * 1.5;
    let triangle = |at: Vec3, size: f32, colour: [f32; 3]| {
        [
            at - right * size - up * size,
            at + right * size - up * size,
            at + up * size,
        ]
        .map(|p| [p.x, p.y, p.z, colour[0], colour[1], colour[2]])
    };
    let mut vertices = triangle(near, radius * 0.2, NEAR_COLOUR).to_vec();
    vertices.extend(triangle(far, radius * 1.4, FAR_COLOUR));
    Ok(HostScene {
        data,
        view,
        projection,
        vertices,
    })
}
