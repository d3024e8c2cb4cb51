#define_import_path meshlight::view

// The camera as every pass sees it. Matrices are column-major, right-handed, with a
// reverse-Z projection (depth 1 at the near plane, 0 at the far plane or infinity), so
// larger depth is nearer and float depth bits compare like the depth itself.
//
// Passes bind a `View` as a uniform themselves; the Rust mirror is
// `meshlight_shaders::cpu::layout::View` and a test checks both layouts match.
struct View {
    // World space to view space.
    view: mat4x4<f32>,
    // View space to clip space (reverse-Z).
    projection: mat4x4<f32>,
    // World space to clip space: projection * view.
    view_projection: mat4x4<f32>,
    // View space to world space.
    inverse_view: mat4x4<f32>,
    // Clip space to view space.
    inverse_projection: mat4x4<f32>,
    // Clip space to world space.
    inverse_view_projection: mat4x4<f32>,
    // Last frame's world-to-clip, for occlusion against last frame's depth pyramid.
    previous_view_projection: mat4x4<f32>,
    // World-space planes (xyz = inward unit normal, w = distance) in the order left,
    // right, bottom, top, near, far; a point p is inside when dot(xyz, p) + w >= 0.
    // With an infinite projection the far plane is (0, 0, 0, 1), which keeps everything.
    frustum: array<vec4<f32>, 6>,
    // Camera position in world space.
    camera_position: vec3<f32>,
    // Distance from the camera to the near plane, in view-space units.
    near: f32,
    // Render target size in pixels.
    viewport_size: vec2<f32>,
    // 1 / viewport_size, to turn pixel coordinates into uv without a division.
    inverse_viewport_size: vec2<f32>,
    // Pixels per unit of error at distance 1: 0.5 * projection[1][1] * viewport height.
    lod_scale: f32,
    // Frame counter, for temporal effects and debugging.
    frame_index: u32,
    // 1 when the projection is orthographic: a projected error does not shrink with
    // distance.
    orthographic: u32,
    // Padding to a 16-byte multiple, so the Rust mirror has no implicit padding.
    padding: u32,
}

// True when the sphere (world-space centre, radius) touches the frustum.
// Conservative: spheres just outside a corner may pass, none inside are rejected.
fn sphere_in_frustum(view: View, center: vec3<f32>, radius: f32) -> bool {
    for (var i = 0u; i < 6u; i += 1u) {
        let plane = view.frustum[i];
        if dot(plane.xyz, center) + plane.w < -radius {
            return false;
        }
    }
    return true;
}

// Screen-space size in pixels of a simplification error seen from `distance` (never
// closer than the near plane), the way meshoptimizer's cluster-LOD demo measures it;
// through an orthographic projection the same at every distance. The one formula of
// the LOD cut: `project_error_to_pixels` puts the error on a sphere, the hierarchy walk
// bounds it over a node's spheres.
fn error_to_pixels(view: View, distance: f32, error: f32) -> f32 {
    if view.orthographic != 0u {
        return error * view.lod_scale;
    }
    return error / max(distance, view.near) * view.lod_scale;
}

// `error_to_pixels` with the error on the LOD sphere's nearest point to the camera, so
// it is conservative for the whole group and, because parent spheres enclose their
// children, monotonic along the DAG. `center` is world-space; radius and error are
// already scaled by the instance.
fn project_error_to_pixels(view: View, center: vec3<f32>, radius: f32, error: f32) -> f32 {
    return error_to_pixels(view, length(center - view.camera_position) - radius, error);
}

// Clip space to normalised device coordinates.
fn clip_to_ndc(clip: vec4<f32>) -> vec3<f32> {
    return clip.xyz / clip.w;
}

// NDC xy (y up) to texture uv (y down, 0..1).
fn ndc_to_uv(ndc: vec2<f32>) -> vec2<f32> {
    return ndc * vec2(0.5, -0.5) + vec2(0.5);
}

fn uv_to_ndc(uv: vec2<f32>) -> vec2<f32> {
    return uv * vec2(2.0, -2.0) + vec2(-1.0, 1.0);
}

// Pixel coordinates (pixel centres at +0.5) to uv.
fn pixel_to_uv(view: View, pixel: vec2<f32>) -> vec2<f32> {
    return pixel * view.inverse_viewport_size;
}

// World-space position to pixel coordinates and reverse-Z depth.
fn world_to_screen(view: View, world: vec3<f32>) -> vec3<f32> {
    let ndc = clip_to_ndc(view.view_projection * vec4(world, 1.0));
    return vec3(ndc_to_uv(ndc.xy) * view.viewport_size, ndc.z);
}

// Reconstructs the world-space position of a pixel from its uv and reverse-Z depth.
fn position_from_depth(view: View, uv: vec2<f32>, depth: f32) -> vec3<f32> {
    let world = view.inverse_view_projection * vec4(uv_to_ndc(uv), depth, 1.0);
    return world.xyz / world.w;
}

// View-space depth (positive distance along the view direction) of a reverse-Z depth.
fn view_z_from_depth(view: View, depth: f32) -> f32 {
    let v = view.inverse_projection * vec4(0.0, 0.0, depth, 1.0);
    return -v.z / v.w;
}
