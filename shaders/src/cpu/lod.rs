//! The LOD test of `meshlight::view` and `meshlight::meshlet` in Rust: the projected error
//! and the cut, operation for operation in f32, for every CPU reference that decides
//! which level of the DAG is drawn (`cull_lod`'s per cluster, `fill_clusters`' bounds per
//! hierarchy node).

use super::layout::View;
use super::matrix::transform_point;

/// `instance_max_scale`: the largest axis scale of `world_from_local` (columns), which
/// brings a mesh-space radius or error to world space.
pub fn instance_max_scale(world_from_local: &[[f32; 4]; 4]) -> f32 {
    let axis = |c: [f32; 4]| c[0] * c[0] + c[1] * c[1] + c[2] * c[2];
    let [x, y, z] = [0, 1, 2].map(|c| axis(world_from_local[c]));
    x.max(y.max(z)).sqrt()
}

/// `error_to_pixels`: pixels an error of `error` world units spans at `distance` from
/// the camera (never nearer than the near plane); through an orthographic projection,
/// at any distance.
pub fn error_to_pixels(view: &View, distance: f32, error: f32) -> f32 {
    if view.orthographic != 0 {
        return error * view.lod_scale;
    }
    error / distance.max(view.near) * view.lod_scale
}

/// `project_error_to_pixels`: [`error_to_pixels`] from the nearest point of the sphere
/// at world-space `center` of `radius`.
pub fn project_error_to_pixels(view: &View, center: [f32; 3], radius: f32, error: f32) -> f32 {
    let d = [
        center[0] - view.camera_position[0],
        center[1] - view.camera_position[1],
        center[2] - view.camera_position[2],
    ];
    let length = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt();
    error_to_pixels(view, length - radius, error)
}

/// `error_perceptible`: whether an error of `pixels` shows at `threshold` (strictly
/// above it; a NaN never shows).
pub fn error_perceptible(pixels: f32, threshold: f32) -> bool {
    pixels > threshold
}

/// `lod_cut`, with the projected errors it compared: (in the cut, own px, parent px;
/// `f32::MAX` when the parent was not projected, for a root or a perceptible own error).
#[allow(clippy::too_many_arguments)]
pub fn lod_cut(
    view: &View,
    world_from_mesh: &[[f32; 4]; 4],
    scale: f32,
    own_sphere: [f32; 4],
    own_error: f32,
    parent_sphere: [f32; 4],
    parent_error: f32,
    threshold: f32,
) -> (bool, f32, f32) {
    let xyz = |s: [f32; 4]| [s[0], s[1], s[2]];
    let own_center = transform_point(world_from_mesh, xyz(own_sphere));
    let own = project_error_to_pixels(view, own_center, own_sphere[3] * scale, own_error * scale);
    if error_perceptible(own, threshold) {
        return (false, own, f32::MAX);
    }
    if parent_error >= f32::MAX {
        return (true, own, f32::MAX);
    }
    let parent_center = transform_point(world_from_mesh, xyz(parent_sphere));
    let parent = project_error_to_pixels(
        view,
        parent_center,
        parent_sphere[3] * scale,
        parent_error * scale,
    );
    (error_perceptible(parent, threshold), own, parent)
}

#[cfg(test)]
mod tests {
    use super::*;

    const IDENTITY: [[f32; 4]; 4] = [
        [1.0, 0.0, 0.0, 0.0],
        [0.0, 1.0, 0.0, 0.0],
        [0.0, 0.0, 1.0, 0.0],
        [0.0, 0.0, 0.0, 1.0],
    ];

    /// A camera at the origin with `lod_scale` 100 and the near plane at 0.1.
    fn view() -> View {
        View {
            near: 0.1,
            lod_scale: 100.0,
            ..View::default()
        }
    }

    fn assert_near(got: f32, want: f32) {
        assert!((got - want).abs() <= want * 1e-6, "{got} != {want}");
    }

    #[test]
    fn an_orthographic_views_errors_project_the_same_at_every_distance() {
        let v = View {
            lod_scale: 100.0,
            near: 0.1,
            orthographic: 1,
            ..View::default()
        };
        for distance in [0.0, 0.5, 10.0, 1e4] {
            assert_near(error_to_pixels(&v, distance, 0.5), 50.0);
        }
    }

    #[test]
    fn an_error_shrinks_with_distance_and_stops_growing_at_the_near_plane() {
        let v = view();
        assert_near(error_to_pixels(&v, 10.0, 0.5), 5.0);
        assert_near(error_to_pixels(&v, 20.0, 0.5), 2.5);
        assert_eq!(
            error_to_pixels(&v, 0.01, 0.5),
            error_to_pixels(&v, 0.1, 0.5)
        );
        // From the sphere's nearest point: centre 12 away, radius 2.
        assert_near(project_error_to_pixels(&v, [0.0, 0.0, 12.0], 2.0, 0.5), 5.0);
    }

    #[test]
    fn the_cut_takes_a_level_whose_error_hides_below_a_parent_that_shows() {
        let v = view();
        // Spheres of radius 1 whose nearest point is 100 units away: 1 unit of error is
        // 1 px.
        let s = [0.0, 0.0, 101.0, 1.0];
        let cut = |scale, own, parent| lod_cut(&v, &IDENTITY, scale, s, own, s, parent, 2.0);
        // Own error 1 px, parent's 10 px: in the cut at a 2 px threshold.
        let (in_cut, own, parent) = cut(1.0, 1.0, 10.0);
        assert!(in_cut, "own {own}, parent {parent}");
        assert_near(own, 1.0);
        assert_near(parent, 10.0);
        // Both hidden: too fine, a coarser level draws instead.
        assert!(!cut(1.0, 1.0, 1.5).0);
        // Own error shows: too coarse, and the parent is not projected.
        let (in_cut, own, parent) = cut(1.0, 3.0, 10.0);
        assert!(!in_cut);
        assert_near(own, 3.0);
        assert_eq!(parent, f32::MAX);
        // A root is drawn whenever its own error hides.
        assert!(cut(1.0, 1.0, f32::MAX).0);
        // The instance's scale grows the error (and the sphere): 1 unit now shows.
        assert!(!cut(4.0, 1.0, 10.0).0);
    }
}
