//! The camera and the per-frame `View` every pass binds.

use glam::{Mat4, Vec3, Vec4};
use meshlight_graph::{GraphError, RecordContext, Result};
use meshlight_shaders::cpu::layout::View;

/// The `View` a pass reads from its frame input `input`, during `record`. With
/// `viewport`, the size the pass was set up for (its targets or visibility buffer), the
/// view must have been made for that size: a camera and params that disagree are a
/// record error naming both, not an image squeezed into the wrong grid.
pub fn frame_view(
    ctx: &RecordContext<'_>,
    input: &str,
    viewport: Option<[u32; 2]>,
) -> Result<View> {
    let error = |message: String| GraphError::Record {
        pass: ctx.pass_name().to_string(),
        message,
    };
    let bytes = ctx.frame_bytes(input)?;
    let view: View = bytes
        .get(..size_of::<View>())
        .map(bytemuck::pod_read_unaligned)
        .ok_or_else(|| {
            error(format!(
                "frame input `{input}` must hold a View ({} bytes), got {}",
                size_of::<View>(),
                bytes.len()
            ))
        })?;
    if let Some([width, height]) = viewport
        && view.viewport_size != [width as f32, height as f32]
    {
        return Err(error(format!(
            "the view's viewport {:?} differs from the pass's {width} × {height} (its targets or visibility buffer); make the params match the camera's viewport",
            view.viewport_size
        )));
    }
    Ok(view)
}

/// How the camera projects; both are reverse-Z (depth 1 at the near plane).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Projection {
    /// Infinite far plane; `fov_y` in radians.
    Perspective {
        /// Vertical field of view, radians.
        fov_y: f32,
        /// Distance of the near plane, where depth is 1.
        near: f32,
    },
    /// `height` world units fill the viewport vertically; depth spans near..far.
    Orthographic {
        /// World units the viewport spans vertically.
        height: f32,
        /// Distance of the near plane, where depth is 1.
        near: f32,
        /// Distance of the far plane, where depth is 0.
        far: f32,
    },
    /// A host application's own view-to-clip matrix ([`Camera::from_matrices`]), used as
    /// it is: its aspect is the host's and does not follow the viewport.
    Matrix {
        /// The matrix, reverse-Z (depth 1 at the near plane).
        projection: Mat4,
        /// Distance of the near plane, where depth is 1, read from the matrix.
        near: f32,
    },
}

/// Why a host's matrices cannot be drawn with.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum CameraError {
    /// A matrix holds a NaN or an infinity.
    #[error("the {which} matrix is not finite; pass the matrices the host draws with")]
    NotFinite {
        /// `view` or `projection`.
        which: &'static str,
    },
    /// The view matrix scales, shears or mirrors, so it is not a camera's pose.
    #[error(
        "the view matrix is not a rotation and a translation (its axes are not orthonormal, or it mirrors); pass the camera's world-to-view matrix, e.g. glam's `camera::rh::view::look_at_mat4`, with any scale moved into the instances"
    )]
    NotRigid,
    /// The projection does not map the near plane to depth 1 in front of the camera.
    #[error(
        "the projection maps depth 1 to view-space z = {near_z} and depth 0.5 to z = {mid_z}: meshlight draws reverse-Z, depth 1 at the near plane in front of the camera (negative z, right-handed) and 0 far away, as Bevy does; build it with glam's `camera::rh::proj::directx::perspective_infinite_reverse` (or swap near and far of a standard projection)"
    )]
    NotReverseZ {
        /// View-space z the matrix maps depth 1 to.
        near_z: f32,
        /// View-space z it maps depth 0.5 to.
        mid_z: f32,
    },
}

/// A camera looking from `position` towards `target`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Camera {
    /// Where the camera is, world space.
    pub position: Vec3,
    /// The point it looks at.
    pub target: Vec3,
    /// Which way is up on the screen (`Vec3::Y` unless set).
    pub up: Vec3,
    /// How it projects.
    pub projection: Projection,
}

impl Camera {
    /// A host application's camera: its world-to-view matrix (right-handed, looking
    /// down -Z, a rotation and a translation) and its view-to-clip projection (reverse-Z:
    /// depth 1 at the near plane, 0 far away, as Bevy's and glam's
    /// `camera::rh::proj::directx::perspective_infinite_reverse`). A frame seen through it lines up with what the
    /// host draws with the same matrices, so the two composite by depth. Matrices
    /// meshlight cannot draw with are refused, saying what to pass instead.
    pub fn from_matrices(view: Mat4, projection: Mat4) -> Result<Self, CameraError> {
        for (which, m) in [("view", view), ("projection", projection)] {
            if !m.is_finite() {
                return Err(CameraError::NotFinite { which });
            }
        }
        let axes = [
            view.x_axis.truncate(),
            view.y_axis.truncate(),
            view.z_axis.truncate(),
        ];
        let orthonormal = (0..3).all(|i| {
            (0..3).all(|j| {
                let want = if i == j { 1.0 } else { 0.0 };
                (axes[i].dot(axes[j]) - want).abs() < 1e-3
            })
        });
        let rows_last = view.row(3);
        if !orthonormal || glam::Mat3::from_mat4(view).determinant() <= 0.0 || rows_last != Vec4::W
        {
            return Err(CameraError::NotRigid);
        }
        let inverse = projection.inverse();
        let view_z = |depth: f32| {
            let p = inverse * Vec4::new(0.0, 0.0, depth, 1.0);
            p.z / p.w
        };
        let (near_z, mid_z) = (view_z(1.0), view_z(0.5));
        if !(near_z.is_finite() && mid_z.is_finite() && near_z < 0.0 && near_z > mid_z) {
            return Err(CameraError::NotReverseZ { near_z, mid_z });
        }
        let pose = view.inverse();
        let position = pose.w_axis.truncate();
        let forward = -pose.z_axis.truncate();
        Ok(Self {
            position,
            target: position + forward,
            up: pose.y_axis.truncate(),
            projection: Projection::Matrix {
                projection,
                near: -near_z,
            },
        })
    }

    /// A perspective camera with the default up, the form every scene and tool starts from.
    pub fn perspective(position: Vec3, target: Vec3, fov_y: f32, near: f32) -> Self {
        Self {
            position,
            target,
            up: Vec3::Y,
            projection: Projection::Perspective { fov_y, near },
        }
    }

    /// World to view space, right-handed.
    pub fn view_matrix(&self) -> Mat4 {
        glam::camera::rh::view::look_at_mat4(self.position, self.target, self.up)
    }

    /// View to clip space for a viewport of `viewport` pixels: reverse-Z, infinite far
    /// plane for a perspective camera.
    pub fn projection_matrix(&self, viewport: [u32; 2]) -> Mat4 {
        let aspect = viewport[0].max(1) as f32 / viewport[1].max(1) as f32;
        match self.projection {
            Projection::Perspective { fov_y, near } => {
                glam::camera::rh::proj::directx::perspective_infinite_reverse(fov_y, aspect, near)
            }
            Projection::Orthographic { height, near, far } => {
                let (h, w) = (height * 0.5, height * 0.5 * aspect);
                // Swapping near and far maps the near plane to depth 1.
                glam::camera::rh::proj::directx::orthographic(-w, w, -h, h, far, near)
            }
            Projection::Matrix { projection, .. } => projection,
        }
    }

    fn near(&self) -> f32 {
        match self.projection {
            Projection::Perspective { near, .. }
            | Projection::Orthographic { near, .. }
            | Projection::Matrix { near, .. } => near,
        }
    }

    /// The view of this camera for a viewport of `viewport` pixels. `previous` is last
    /// frame's world-to-clip (this frame's when there is none).
    pub fn view(&self, viewport: [u32; 2], frame_index: u32, previous: Option<Mat4>) -> View {
        let view = self.view_matrix();
        let projection = self.projection_matrix(viewport);
        let view_projection = projection * view;
        let size = [viewport[0].max(1) as f32, viewport[1].max(1) as f32];
        View {
            view: view.to_cols_array_2d(),
            projection: projection.to_cols_array_2d(),
            view_projection: view_projection.to_cols_array_2d(),
            inverse_view: view.inverse().to_cols_array_2d(),
            inverse_projection: projection.inverse().to_cols_array_2d(),
            inverse_view_projection: view_projection.inverse().to_cols_array_2d(),
            previous_view_projection: previous.unwrap_or(view_projection).to_cols_array_2d(),
            frustum: frustum_planes(view_projection),
            camera_position: self.position.to_array(),
            near: self.near(),
            viewport_size: size,
            inverse_viewport_size: [1.0 / size[0], 1.0 / size[1]],
            lod_scale: 0.5 * projection.y_axis.y * size[1],
            frame_index,
            // An affine projection (w = 1 everywhere) is orthographic.
            orthographic: u32::from(projection.w_axis.w != 0.0),
            padding: 0,
        }
    }
}

/// World-space planes (inward unit normal, distance) of a reverse-Z world-to-clip
/// matrix: left, right, bottom, top, near, far. The far plane of an infinite projection
/// has no normal and becomes (0, 0, 0, 1), which keeps every point.
pub fn frustum_planes(view_projection: Mat4) -> [[f32; 4]; 6] {
    let m = view_projection.transpose();
    let (r0, r1, r2, r3) = (m.x_axis, m.y_axis, m.z_axis, m.w_axis);
    // Inside: -w <= x <= w, -w <= y <= w, 0 <= z <= w.
    [r3 + r0, r3 - r0, r3 + r1, r3 - r1, r3 - r2, r2].map(|p: Vec4| {
        let len = p.truncate().length();
        if len > 1e-12 {
            (p / len).to_array()
        } else {
            [0.0, 0.0, 0.0, 1.0]
        }
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_orthographic_cameras_view_measures_errors_in_pixels_per_world_unit() {
        let mut camera = Camera::perspective(Vec3::new(0.0, 0.0, 10.0), Vec3::ZERO, 1.0, 0.1);
        assert_eq!(camera.view([640, 480], 0, None).orthographic, 0);
        camera.projection = Projection::Orthographic {
            height: 8.0,
            near: 0.1,
            far: 50.0,
        };
        let view = camera.view([640, 480], 0, None);
        assert_eq!(view.orthographic, 1);
        // 480 pixels span 8 world units.
        assert!((view.lod_scale - 60.0).abs() < 1e-4, "{}", view.lod_scale);
    }

    #[test]
    fn a_hosts_matrices_give_the_same_view_and_bad_ones_say_what_to_pass() {
        let eye = Vec3::new(3.0, 2.0, 7.0);
        use glam::camera::rh::{proj::directx, view::look_at_mat4};
        let view = look_at_mat4(eye, Vec3::new(0.0, 0.5, 0.0), Vec3::Y);
        let projection = directx::perspective_infinite_reverse(0.8, 16.0 / 9.0, 0.25);
        let camera = Camera::from_matrices(view, projection).unwrap();
        assert!(camera.view_matrix().abs_diff_eq(view, 1e-5), "{camera:?}");
        assert_eq!(camera.projection_matrix([1920, 1080]), projection);
        assert!((camera.near() - 0.25).abs() < 1e-5);
        assert!((camera.position - eye).length() < 1e-5);
        // A standard-Z projection maps depth 1 to the far side.
        let standard = directx::perspective(0.8, 16.0 / 9.0, 0.25, 100.0);
        assert!(matches!(
            Camera::from_matrices(view, standard),
            Err(CameraError::NotReverseZ { .. })
        ));
        let scaled = view * Mat4::from_scale(Vec3::splat(2.0));
        assert_eq!(
            Camera::from_matrices(scaled, projection),
            Err(CameraError::NotRigid)
        );
        let mirrored = Mat4::from_scale(Vec3::new(-1.0, 1.0, 1.0)) * view;
        assert_eq!(
            Camera::from_matrices(mirrored, projection),
            Err(CameraError::NotRigid)
        );
        let mut broken = projection;
        broken.x_axis.x = f32::NAN;
        assert_eq!(
            Camera::from_matrices(view, broken),
            Err(CameraError::NotFinite {
                which: "projection"
            })
        );
        let message = Camera::from_matrices(view, standard)
            .unwrap_err()
            .to_string();
        assert!(
            message.contains("perspective_infinite_reverse"),
            "{message}"
        );
    }

    #[test]
    fn planes_keep_what_the_projection_shows_and_reject_the_rest() {
        let camera = Camera::perspective(Vec3::new(0.0, 1.0, 5.0), Vec3::ZERO, 1.0, 0.1);
        let view = camera.view([1280, 720], 0, None);
        let inside = |p: Vec3| {
            view.frustum
                .iter()
                .all(|pl| Vec3::from_slice(&pl[..3]).dot(p) + pl[3] >= 0.0)
        };
        assert!(inside(Vec3::ZERO));
        assert!(inside(Vec3::new(0.0, 0.0, -1000.0)), "no far plane");
        assert!(!inside(Vec3::new(0.0, 1.0, 6.0)), "behind the camera");
        assert!(!inside(Vec3::new(100.0, 0.0, 0.0)), "far to the right");
        assert_eq!(view.frustum[5], [0.0, 0.0, 0.0, 1.0]);
        // The projected centre lands mid-screen at depth in (0, 1].
        let clip = Mat4::from_cols_array_2d(&view.view_projection) * camera.target.extend(1.0);
        assert!((clip.x / clip.w).abs() < 1e-6 && clip.z / clip.w > 0.0 && clip.z / clip.w <= 1.0);
    }
}
