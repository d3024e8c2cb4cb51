//! A directional light's shadow cascades for a camera: where the camera's view is split
//! between them, and each one's orthographic view, fitted so that shadows hold still
//! while the camera moves.
//!
//! - **Splits.** The practical scheme: each split distance blends the uniform and the
//!   logarithmic split of `near .. distance` by [`CascadeSettings::split_lambda`] (0:
//!   uniform, 1: logarithmic, where each cascade covers the same ratio of distances).
//! - **A fixed size per cascade.** A cascade covers the bounding sphere of its slice of
//!   the camera's frustum, computed in the camera's own space, so its radius (and a
//!   texel's world size) depends only on the projection and the split, never on where
//!   the camera stands or looks: turning the camera does not rescale the shadow map.
//! - **Whole texels.** The sphere's centre is snapped, in the light's frame, to whole
//!   texels, so when the camera moves the map slides by whole texels and a still edge
//!   falls on the same texels (no shimmer).
//! - **Held while the camera moves.** With [`CascadeSettings::hold`] > 0 a cascade's box
//!   is the sphere grown by that fraction of its radius, and its centre is snapped, in
//!   all three axes of the light's frame, to a grid of steps of twice that (in whole
//!   texels): the box keeps its place, and so its view, while the camera moves within a
//!   grid cell, yet always holds the slice's sphere. A renderer that keeps a map while
//!   its view is unchanged then draws a cascade again only when the camera leaves its
//!   cell, at the cost of texels `1 + hold` times larger and casters culled to the box
//!   rather than to the camera's slice (those planes move with the camera).
//! - **Casters outside the slice.** The depth range covers the sphere and reaches
//!   [`CascadeSettings::caster_reach`] further towards the light: a mountain behind the
//!   camera still shades the ground in front of it.
//!
//! The LOD rule that follows (documented in docs/ARCHITECTURE.md, "Views"): a shadow
//! view's cut is chosen by its own projection, orthographic, with a texel's world size
//! as the pixel; it depends only on the cascade an object falls in, never on the
//! camera's cut, so an object's shadow changes level only when it changes cascade.

use glam::{Mat4, Vec3, Vec3Swizzles};
use meshlight_shaders::cpu::layout::View;

use crate::view::{Camera, CameraError};

/// The most cascades a light has.
pub const MAX_CASCADES: u32 = 4;

/// [`CascadeSettings::hold`] by default: texels an eighth larger, for a map drawn again
/// about once for every quarter of its cascade's radius the camera moves.
pub const DEFAULT_HOLD: f32 = 0.125;

/// How a directional light's shadow is split into cascades.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CascadeSettings {
    /// Cascades, 1 to [`MAX_CASCADES`].
    pub count: u32,
    /// Texels along each side of a cascade's map.
    pub resolution: u32,
    /// Distance from the camera (view-space depth) where shadows end.
    pub distance: f32,
    /// 0: uniform splits; 1: logarithmic; between: a blend of the two.
    pub split_lambda: f32,
    /// How far beyond a cascade's sphere, towards the light, casters are kept.
    pub caster_reach: f32,
    /// How far a cascade's box reaches past its slice's sphere, as a fraction of the
    /// sphere's radius, 0 to 1: its view then stays the same while the camera moves
    /// within a grid cell of twice that, so a kept map is not drawn again. 0 fits the
    /// box to the sphere (the sharpest map), and every camera move changes the view.
    pub hold: f32,
}

impl Default for CascadeSettings {
    /// Four 2048² cascades to 100 units, split 0.8 of the way to logarithmic, casters
    /// kept 100 units towards the light, boxes an eighth of a radius larger than their
    /// slices (held while the camera moves a quarter of a radius).
    fn default() -> Self {
        Self {
            count: 4,
            resolution: 2048,
            distance: 100.0,
            split_lambda: 0.8,
            caster_reach: 100.0,
            hold: DEFAULT_HOLD,
        }
    }
}

/// What is wrong with a cascade setting: the setting, and what to change.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum CascadeError {
    /// A number out of its range.
    #[error("shadow cascades: {setting} = {value} is outside {range}; {hint}")]
    OutOfRange {
        /// The setting.
        setting: &'static str,
        /// What it was.
        value: String,
        /// What it must lie in.
        range: &'static str,
        /// What to change.
        hint: &'static str,
    },
    /// The light has no direction.
    #[error(
        "shadow cascades: the light's direction {0:?} has no length or is not finite; give a unit vector towards the light"
    )]
    LightDirection([f32; 3]),
    /// The camera cannot be split.
    #[error("shadow cascades: {0}")]
    Camera(#[from] CameraError),
    /// Shadows end before the camera's near plane.
    #[error(
        "shadow cascades: shadows end at {distance}, nearer than the camera's near plane at {near}; raise the shadow distance"
    )]
    Distance {
        /// The shadow distance.
        distance: f32,
        /// The camera's near plane.
        near: f32,
    },
}

impl CascadeSettings {
    /// Checks every number, naming the first one out of range.
    pub fn validate(&self) -> Result<(), CascadeError> {
        let out = |setting, value: String, range, hint| {
            Err(CascadeError::OutOfRange {
                setting,
                value,
                range,
                hint,
            })
        };
        if !(1..=MAX_CASCADES).contains(&self.count) {
            return out(
                "count",
                self.count.to_string(),
                "1..=4",
                "give 1 to 4 cascades",
            );
        }
        if !(16..=16384).contains(&self.resolution) || !self.resolution.is_multiple_of(8) {
            return out(
                "resolution",
                self.resolution.to_string(),
                "16..=16384, a multiple of 8",
                "give a map side of 16 to 16384 texels, a multiple of 8 (each cascade's map is cleared alone, in whole 256-byte blocks)",
            );
        }
        if !(self.distance.is_finite() && self.distance > 0.0) {
            return out(
                "distance",
                self.distance.to_string(),
                "(0, ∞)",
                "give a positive, finite shadow distance",
            );
        }
        if !(0.0..=1.0).contains(&self.split_lambda) {
            return out(
                "split_lambda",
                self.split_lambda.to_string(),
                "0..=1",
                "0 splits uniformly, 1 logarithmically",
            );
        }
        if !(self.caster_reach.is_finite() && self.caster_reach >= 0.0) {
            return out(
                "caster_reach",
                self.caster_reach.to_string(),
                "[0, ∞)",
                "give a finite distance, 0 or more",
            );
        }
        if !(0.0..=1.0).contains(&self.hold) {
            return out(
                "hold",
                self.hold.to_string(),
                "0..=1",
                "give a fraction of a cascade's radius: 0 fits the box to its slice, 1 doubles it",
            );
        }
        Ok(())
    }

    /// The view-space depths where the cascades begin and end: `count + 1` of them, from
    /// `near` to [`Self::distance`], increasing.
    pub fn splits(&self, near: f32) -> Vec<f32> {
        let (n, f, count) = (near, self.distance, self.count as f32);
        (0..=self.count)
            .map(|i| {
                let t = i as f32 / count;
                let logarithmic = n * (f / n).powf(t);
                let uniform = n + (f - n) * t;
                let d = self.split_lambda * logarithmic + (1.0 - self.split_lambda) * uniform;
                match i {
                    0 => n,
                    i if i == self.count => f,
                    _ => d,
                }
            })
            .collect()
    }
}

/// One cascade: its slice of the camera's view and the light's view over it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Cascade {
    /// View-space depths of the slice it serves.
    pub near: f32,
    /// Where the slice ends.
    pub far: f32,
    /// World size of one texel of its map.
    pub texel_size: f32,
    /// The light's camera for it: orthographic, looking along the light.
    pub camera: Camera,
    /// Its view for a map of the cascade's resolution.
    pub view: View,
}

/// The cascades of a light shining towards `-toward_light` for `camera` drawn to a
/// `viewport`: `settings.count` of them, nearest first.
pub fn cascades(
    camera: &Camera,
    viewport: [u32; 2],
    toward_light: Vec3,
    settings: &CascadeSettings,
    frame_index: u32,
) -> Result<Vec<Cascade>, CascadeError> {
    settings.validate()?;
    let light = toward_light.normalize_or_zero();
    if light == Vec3::ZERO || !light.is_finite() {
        return Err(CascadeError::LightDirection(toward_light.to_array()));
    }
    let near = camera_near(camera, viewport);
    if settings.distance <= near {
        return Err(CascadeError::Distance {
            distance: settings.distance,
            near,
        });
    }
    let world_from_view = camera.view_matrix().inverse();
    let view_from_clip = camera.projection_matrix(viewport).inverse();
    // The light's frame: rows are its axes; it looks along -light.
    let up = if light.y.abs() < 0.99 {
        Vec3::Y
    } else {
        Vec3::Z
    };
    let light_from_world = glam::camera::rh::view::look_to_mat4(Vec3::ZERO, -light, up);
    let world_from_light = light_from_world.inverse();
    let res = settings.resolution;
    let splits = settings.splits(near);
    splits
        .windows(2)
        .map(|pair| {
            let (slice_near, slice_far) = (pair[0], pair[1]);
            let (centre, radius) = slice_sphere(&view_from_clip, slice_near, slice_far);
            // The box's half side: the sphere's radius, grown by `hold`.
            let half = radius * (1.0 + settings.hold);
            let texel_size = 2.0 * half / res as f32;
            let in_light =
                light_from_world.transform_point3(world_from_view.transform_point3(centre));
            let snapped = if settings.hold > 0.0 {
                // Whole steps of the grid (whole texels, at most `hold × radius` from
                // the sphere's centre along each axis, so the box holds the sphere).
                let texels = (2.0 * settings.hold * radius / texel_size).floor().max(1.0);
                let step = texels * texel_size;
                (in_light / step).round() * step
            } else {
                Vec3::new(
                    (in_light.x / texel_size).floor() * texel_size,
                    (in_light.y / texel_size).floor() * texel_size,
                    in_light.z,
                )
            };
            // The eye: on the light's side of the box, just past the casters' reach
            // (the near plane, a hundredth of the way in, keeps the projection
            // invertible).
            let margin = 0.01 * (half + settings.caster_reach);
            let back = half + settings.caster_reach + margin;
            let eye = world_from_light.transform_point3(snapped + Vec3::Z * back);
            let view = glam::camera::rh::view::look_to_mat4(eye, -light, up);
            // Reverse-Z: the near plane at depth 1, the box's far side at 0.
            let projection = glam::camera::rh::proj::directx::orthographic(
                -half,
                half,
                -half,
                half,
                back + half,
                margin,
            );
            let light_camera = Camera::from_matrices(view, projection)?;
            let mut view = light_camera.view([res, res], frame_index, None);
            // Held, the casters are culled to the box alone: the slice's planes move
            // with the camera.
            if settings.hold == 0.0 {
                view.frustum = caster_planes(
                    camera,
                    viewport,
                    light,
                    (slice_near, slice_far),
                    3.0 * texel_size,
                    &view.frustum,
                );
            }
            Ok(Cascade {
                near: slice_near,
                far: slice_far,
                texel_size,
                view,
                camera: light_camera,
            })
        })
        .collect()
}

/// The planes a caster of a cascade is culled against: the cascade box's four sides
/// (casters outside them draw off the map) and, in slots 4 and 5, two planes of the
/// camera's slice `near..far`. A caster matters only where its shadow can fall on the
/// slice, so only inside the slice swept towards the light, and each of the slice's
/// planes (the camera's four sides and the slice's two ends, moved out by `margin` for
/// the filter's reach) whose inward normal does not face away from the light bounds
/// that sweep (moving towards the light never brings a point back inside it). The
/// slice's ends are taken first, then the sides most across the light; where fewer
/// than two bound the sweep, the box's near and far planes stay. Nothing reads slot 4
/// as the near plane (`cull_lod` measures the near plane from the view matrix and
/// `near`). The projection, and so the LOD and the texel snapping, stays the box's.
fn caster_planes(
    camera: &Camera,
    viewport: [u32; 2],
    toward_light: Vec3,
    (near, far): (f32, f32),
    margin: f32,
    box_planes: &[[f32; 4]; 6],
) -> [[f32; 4]; 6] {
    let world_from_view = camera.view_matrix().inverse();
    let eye = world_from_view.w_axis.truncate();
    let forward = -world_from_view.z_axis.truncate().normalize();
    let sides =
        crate::view::frustum_planes(camera.projection_matrix(viewport) * camera.view_matrix());
    let ends = [
        forward.extend(-forward.dot(eye + forward * near)),
        (-forward).extend(forward.dot(eye + forward * far)),
    ];
    let bounding = |p: &glam::Vec4| p.truncate().dot(toward_light) >= 0.0;
    let mut lateral: Vec<glam::Vec4> = sides[..4]
        .iter()
        .map(|p| glam::Vec4::from_array(*p))
        .filter(bounding)
        .collect();
    lateral.sort_by(|a, b| {
        (a.truncate().dot(toward_light)).total_cmp(&b.truncate().dot(toward_light))
    });
    let mut chosen = ends
        .into_iter()
        .filter(bounding)
        .chain(lateral)
        .map(|p| (p + glam::Vec4::W * margin).to_array());
    let mut out = *box_planes;
    for slot in [4, 5] {
        if let Some(p) = chosen.next() {
            out[slot] = p;
        }
    }
    out
}

/// The near plane's distance of `camera` (view-space depth where clip depth is 1).
fn camera_near(camera: &Camera, viewport: [u32; 2]) -> f32 {
    let view_from_clip = camera.projection_matrix(viewport).inverse();
    -view_from_clip.project_point3(Vec3::new(0.0, 0.0, 1.0)).z
}

/// The bounding sphere, in view space, of the camera frustum's slice between view-space
/// depths `near` and `far`: centred on the view axis where the corners allow, so it
/// depends only on the projection.
fn slice_sphere(view_from_clip: &Mat4, near: f32, far: f32) -> (Vec3, f32) {
    // A corner at view-space depth `d` along the ray through NDC (x, y).
    let corner = |x: f32, y: f32, d: f32| {
        let a = view_from_clip.project_point3(Vec3::new(x, y, 1.0));
        let b = view_from_clip.project_point3(Vec3::new(x, y, 0.5));
        let t = (-d - a.z) / (b.z - a.z);
        a + (b - a) * t
    };
    let corners: Vec<Vec3> = [near, far]
        .into_iter()
        .flat_map(|d| {
            [(-1.0, -1.0), (1.0, -1.0), (-1.0, 1.0), (1.0, 1.0)].map(|(x, y)| corner(x, y, d))
        })
        .collect();
    // The smallest sphere centred on the axis through the slice's middle line: its
    // centre's depth balances the near and far corners' distances.
    let axis = |d: f32| corner(0.0, 0.0, d).xy();
    let (near_half, far_half) = (
        corners[..4]
            .iter()
            .map(|c| (c.xy() - axis(near)).length_squared())
            .fold(0.0f32, f32::max),
        corners[4..]
            .iter()
            .map(|c| (c.xy() - axis(far)).length_squared())
            .fold(0.0f32, f32::max),
    );
    // |z - near|² + near_half = |z - far|² + far_half, along depth.
    let depth = ((far * far - near * near) + (far_half - near_half)) / (2.0 * (far - near));
    let depth = depth.clamp(near, far);
    let centre = corner(0.0, 0.0, depth);
    let radius = corners
        .iter()
        .map(|c| (*c - centre).length())
        .fold(0.0f32, f32::max);
    (centre, radius)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::view::Projection;

    fn camera(position: Vec3, target: Vec3) -> Camera {
        Camera::perspective(position, target, 1.0, 0.1)
    }

    fn texel_of(c: &Cascade, world: Vec3, res: u32) -> glam::Vec2 {
        let vp = Mat4::from_cols_array_2d(&c.view.view_projection);
        let ndc = vp.project_point3(world);
        (ndc.xy() * 0.5 + 0.5) * res as f32
    }

    #[test]
    fn splits_run_from_the_near_plane_to_the_distance_and_blend_the_two_schemes() {
        let s = CascadeSettings {
            count: 4,
            distance: 100.0,
            split_lambda: 0.0,
            ..CascadeSettings::default()
        };
        let uniform = s.splits(1.0);
        assert_eq!(uniform.len(), 5);
        assert_eq!((uniform[0], uniform[4]), (1.0, 100.0));
        assert!((uniform[2] - 50.5).abs() < 1e-4, "{uniform:?}");
        let log = CascadeSettings {
            split_lambda: 1.0,
            ..s
        }
        .splits(1.0);
        // Each cascade covers the same ratio: 100^(1/4).
        assert!((log[1] - 100f32.powf(0.25)).abs() < 1e-4, "{log:?}");
        let blend = CascadeSettings {
            split_lambda: 0.5,
            ..s
        }
        .splits(1.0);
        assert!((blend[1] - 0.5 * (uniform[1] + log[1])).abs() < 1e-4);
        assert!(blend.windows(2).all(|w| w[0] < w[1]), "{blend:?}");
    }

    #[test]
    fn each_cascade_covers_its_slice_of_the_camera_frustum() {
        for hold in [0.0, DEFAULT_HOLD, 1.0] {
            let settings = CascadeSettings {
                hold,
                ..CascadeSettings::default()
            };
            for (eye, target) in [
                (Vec3::new(3.0, 5.0, 9.0), Vec3::new(-4.0, 0.0, -30.0)),
                (Vec3::new(-13.7, 2.2, 41.3), Vec3::new(20.0, -3.0, 0.5)),
                (Vec3::new(0.3, 0.7, -0.2), Vec3::new(0.0, 0.5, -1.0)),
            ] {
                covers_its_slice(&settings, &camera(eye, target));
            }
        }
    }

    /// Every cascade of `cam`: texels no larger than its slice's (grown by the hold)
    /// need, every corner and the middle of its slice inside its box.
    fn covers_its_slice(settings: &CascadeSettings, cam: &Camera) {
        let settings = *settings;
        let viewport = [1920, 1080];
        let cascades = cascades(cam, viewport, Vec3::new(-0.5, 0.8, 0.35), &settings, 0).unwrap();
        assert_eq!(cascades.len(), 4);
        let world_from_view = cam.view_matrix().inverse();
        let view_from_clip = cam.projection_matrix(viewport).inverse();
        for c in &cascades {
            // No larger than the sphere around the slice's corners from their centroid.
            let corners: Vec<Vec3> = [c.near, c.far]
                .into_iter()
                .flat_map(|d| {
                    [(-1.0, -1.0), (1.0, -1.0), (-1.0, 1.0), (1.0, 1.0)].map(|(x, y)| {
                        let a = view_from_clip.project_point3(Vec3::new(x, y, 1.0));
                        let b = view_from_clip.project_point3(Vec3::new(x, y, 0.5));
                        a + (b - a) * ((-d - a.z) / (b.z - a.z))
                    })
                })
                .collect();
            let centroid = corners.iter().sum::<Vec3>() / 8.0;
            let loose = corners
                .iter()
                .map(|p| (*p - centroid).length())
                .fold(0.0, f32::max);
            assert!(
                c.texel_size
                    <= 2.0 * loose * (1.0 + settings.hold) / settings.resolution as f32
                        * (1.0 + 1e-5),
                "cascade {}..{}: a texel of {} for a slice of radius {loose}",
                c.near,
                c.far,
                c.texel_size
            );
            let vp = Mat4::from_cols_array_2d(&c.view.view_projection);
            for d in [c.near, 0.5 * (c.near + c.far), c.far] {
                for (x, y) in [
                    (-1.0, -1.0),
                    (1.0, -1.0),
                    (-1.0, 1.0),
                    (1.0, 1.0),
                    (0.0, 0.0),
                ] {
                    let a = view_from_clip.project_point3(Vec3::new(x, y, 1.0));
                    let b = view_from_clip.project_point3(Vec3::new(x, y, 0.5));
                    let p = a + (b - a) * ((-d - a.z) / (b.z - a.z));
                    let ndc = vp.project_point3(world_from_view.transform_point3(p));
                    assert!(
                        ndc.x.abs() <= 1.0 + 1e-4 && ndc.y.abs() <= 1.0 + 1e-4,
                        "depth {d}: {ndc}"
                    );
                    assert!((0.0..=1.0).contains(&ndc.z), "depth {d}: {ndc}");
                }
            }
        }
    }

    #[test]
    fn moving_the_camera_slides_the_maps_by_whole_texels_and_turning_it_keeps_their_size() {
        let settings = CascadeSettings {
            resolution: 1024,
            ..CascadeSettings::default()
        };
        let light = Vec3::new(-0.5, 0.8, 0.35);
        let point = Vec3::new(2.5, 0.3, -7.25);
        let first = cascades(
            &camera(Vec3::new(0.0, 2.0, 5.0), Vec3::ZERO),
            [1280, 720],
            light,
            &settings,
            0,
        )
        .unwrap();
        let mut rng = meshlight_shaders::cpu::rng::Rng(7);
        for _ in 0..20 {
            let shift = Vec3::new(
                rng.range(-3.0, 3.0),
                rng.range(-1.0, 1.0),
                rng.range(-3.0, 3.0),
            );
            let target = Vec3::new(rng.range(-5.0, 5.0), 0.0, rng.range(-5.0, 5.0));
            let moved = cascades(
                &camera(Vec3::new(0.0, 2.0, 5.0) + shift, target),
                [1280, 720],
                light,
                &settings,
                0,
            )
            .unwrap();
            for (a, b) in first.iter().zip(&moved) {
                assert_eq!(a.texel_size, b.texel_size, "a cascade's texel changed size");
                let slide = texel_of(b, point, 1024) - texel_of(a, point, 1024);
                let off = (slide - slide.round()).abs().max_element();
                assert!(off < 2e-2, "the map slid by {slide}, not whole texels");
            }
        }
    }

    /// Along a camera path of small steps, moving and turning: a held cascade's view
    /// changes only now and then (when the camera leaves its grid cell), a fitted one's
    /// at almost every step, and every box still holds its slice.
    #[test]
    fn held_cascades_keep_their_views_while_the_camera_moves_within_a_cell() {
        let light = Vec3::new(-0.5, 0.8, 0.35);
        let changes = |hold: f32| {
            let settings = CascadeSettings {
                hold,
                ..CascadeSettings::default()
            };
            let mut changed = [0u32; 4];
            let mut last: Option<Vec<Cascade>> = None;
            for i in 0..200 {
                let t = i as f32;
                let eye = Vec3::new(0.05 * t, 2.0, 5.0 - 0.08 * t);
                let turn = 0.002 * t;
                let cam = camera(eye, eye + Vec3::new(turn.sin(), -0.1, -turn.cos()));
                let list = cascades(&cam, [1280, 720], light, &settings, i).unwrap();
                if i % 20 == 0 {
                    covers_its_slice(&settings, &cam);
                }
                if let Some(before) = &last {
                    for (k, (a, b)) in before.iter().zip(&list).enumerate() {
                        let (mut a, mut b) = (a.view, b.view);
                        a.frame_index = 0;
                        b.frame_index = 0;
                        changed[k] += u32::from(bytemuck::bytes_of(&a) != bytemuck::bytes_of(&b));
                    }
                }
                last = Some(list);
            }
            changed
        };
        let fitted = changes(0.0);
        let held = changes(DEFAULT_HOLD);
        assert!(
            fitted.iter().all(|&n| n >= 190),
            "fitted: {fitted:?} of 199 steps"
        );
        assert!(held.iter().all(|&n| n <= 40), "held: {held:?} of 199 steps");
        assert!(
            held[3] <= held[0],
            "the far cascade changed more often: {held:?}"
        );
    }

    #[test]
    fn bad_settings_name_what_to_change() {
        let cam = camera(Vec3::new(0.0, 2.0, 5.0), Vec3::ZERO);
        let bad = |settings: CascadeSettings| {
            cascades(&cam, [64, 64], Vec3::Y, &settings, 0)
                .unwrap_err()
                .to_string()
        };
        let d = CascadeSettings::default();
        assert!(bad(CascadeSettings { count: 5, ..d }).contains("count = 5"));
        assert!(bad(CascadeSettings { resolution: 8, ..d }).contains("resolution = 8"));
        assert!(
            bad(CascadeSettings {
                distance: f32::NAN,
                ..d
            })
            .contains("distance")
        );
        assert!(
            bad(CascadeSettings {
                distance: 0.05,
                ..d
            })
            .contains("raise the shadow distance")
        );
        assert!(
            bad(CascadeSettings {
                split_lambda: 2.0,
                ..d
            })
            .contains("split_lambda")
        );
        for hold in [-0.1, 1.5, f32::NAN] {
            assert!(bad(CascadeSettings { hold, ..d }).contains("hold"));
        }
        let e = cascades(&cam, [64, 64], Vec3::ZERO, &d, 0)
            .unwrap_err()
            .to_string();
        assert!(e.contains("towards the light"), "{e}");
        // An orthographic camera splits too.
        let mut ortho = cam;
        ortho.projection = Projection::Orthographic {
            height: 10.0,
            near: 0.1,
            far: 200.0,
        };
        assert_eq!(cascades(&ortho, [64, 64], Vec3::Y, &d, 0).unwrap().len(), 4);
    }

    /// Every caster whose shadow can fall on a cascade's slice (a point of the slice
    /// moved towards the light, inside the map) is inside the cull planes, and the
    /// planes cut away much of the box the camera never sees.
    #[test]
    fn the_cull_planes_keep_every_caster_of_the_slice_and_cut_the_rest() {
        let mut rng = 7u64;
        let mut unit = move || {
            rng = rng
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (rng >> 40) as f32 / (1u64 << 24) as f32
        };
        let inside = |planes: &[[f32; 4]; 6], p: Vec3, slack: f32| {
            planes
                .iter()
                .all(|q| Vec3::new(q[0], q[1], q[2]).dot(p) + q[3] >= -slack)
        };
        // Boxes fitted to their slices: held ones are culled to the box alone.
        let settings = CascadeSettings {
            count: 3,
            resolution: 512,
            distance: 60.0,
            hold: 0.0,
            ..CascadeSettings::default()
        };
        let mut cut = 0;
        let mut boxed = 0;
        for case in 0..6 {
            let eye = Vec3::new(unit() * 20.0 - 10.0, 1.0 + unit() * 8.0, unit() * 20.0);
            let look = Vec3::new(unit() * 10.0 - 5.0, 0.0, -10.0 - unit() * 10.0);
            let cam = camera(eye, look);
            let light = Vec3::new(unit() - 0.5, 0.3 + unit(), unit() - 0.5).normalize();
            let viewport = [640, 360];
            let list = cascades(&cam, viewport, light, &settings, 0).unwrap();
            let inverse = (cam.projection_matrix(viewport) * cam.view_matrix()).inverse();
            let forward = (cam.target - cam.position).normalize();
            for c in &list {
                let b = Mat4::from_cols_array_2d(&c.view.view_projection);
                let box_planes = crate::view::frustum_planes(b);
                for _ in 0..400 {
                    // A receiver in the slice: a ray through the screen, at a depth in it.
                    let ndc = glam::Vec2::new(unit() * 2.0 - 1.0, unit() * 2.0 - 1.0);
                    let far = inverse.project_point3(ndc.extend(0.5));
                    let dir = (far - cam.position).normalize();
                    let depth = c.near + unit() * (c.far - c.near);
                    let receiver = cam.position + dir * (depth / dir.dot(forward));
                    let caster = receiver + light * unit() * settings.caster_reach;
                    if inside(&box_planes, caster, 0.0) {
                        assert!(
                            inside(&c.view.frustum, caster, 1e-3),
                            "case {case}: a caster of the slice is culled"
                        );
                    }
                    // Any point of the box: how many the planes cut.
                    let p = b.inverse().project_point3(Vec3::new(
                        unit() * 2.0 - 1.0,
                        unit() * 2.0 - 1.0,
                        unit(),
                    ));
                    if inside(&box_planes, p, 0.0) {
                        boxed += 1;
                        cut += usize::from(!inside(&c.view.frustum, p, 0.0));
                    }
                }
            }
        }
        assert!(
            cut * 8 > boxed,
            "the planes cut only {cut} of {boxed} points of the boxes"
        );
    }
}
