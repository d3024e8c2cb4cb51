//! Seeded random scenes of clusterable objects and the cameras to view them, for the
//! light-clustering stages' tests and benchmarks: every stage is compared with its
//! reference on the same reproducible scenes.

use glam::Vec3;
use meshlight_gpu_scene::{Camera, Projection};
use meshlight_shaders::cpu::layout::{ClusterableKind, ClusterableObject};

pub use meshlight_shaders::cpu::rng::Rng;

/// A direction drawn uniformly from the cube's corners' span, normalised (+Y when it
/// comes out zero).
pub fn direction(rng: &mut Rng) -> Vec3 {
    Vec3::new(
        rng.range(-1.0, 1.0),
        rng.range(-1.0, 1.0),
        rng.range(-1.0, 1.0),
    )
    .normalize_or(Vec3::Y)
}

/// An object of `kind` at `position` reaching `range`, pointing down: the base the test
/// scenes vary.
pub fn object(kind: ClusterableKind, position: Vec3, range: f32) -> ClusterableObject {
    ClusterableObject {
        position_range: [position.x, position.y, position.z, range],
        direction_cos_angle: [0.0, -1.0, 0.0, 1.0],
        color_intensity: [1.0; 4],
        kind: kind as u32,
        sin_angle: 0.0,
        payload: 0,
        padding: 0,
    }
}

/// A spot light with the given direction and half-angle.
pub fn spot(position: Vec3, direction: Vec3, range: f32, half_angle: f32) -> ClusterableObject {
    let mut o = object(ClusterableKind::SpotLight, position, range);
    o.direction_cos_angle = [direction.x, direction.y, direction.z, half_angle.cos()];
    o.sin_angle = half_angle.sin();
    o
}

/// Every object kind, in `ClusterableKind` order, so scenes cycle through all of them.
pub const KINDS: [ClusterableKind; 4] = [
    ClusterableKind::PointLight,
    ClusterableKind::SpotLight,
    ClusterableKind::Probe,
    ClusterableKind::Decal,
];

/// `n` objects of every kind around `centre`, ranges spread over three decades.
pub fn random_objects(
    rng: &mut Rng,
    n: usize,
    centre: Vec3,
    spread: f32,
) -> Vec<ClusterableObject> {
    (0..n)
        .map(|i| {
            let position = centre
                + Vec3::new(
                    rng.range(-spread, spread),
                    rng.range(-spread, spread),
                    rng.range(-spread, spread),
                );
            let range = 0.05 * 1000f32.powf(rng.unit());
            match KINDS[i % 4] {
                ClusterableKind::SpotLight => {
                    let d = direction(rng);
                    spot(position, d, range, rng.range(0.05, 1.5))
                }
                kind => {
                    let mut o = object(kind, position, range);
                    let d = direction(rng);
                    o.direction_cos_angle = [d.x, d.y, d.z, 1.0];
                    o
                }
            }
        })
        .collect()
}

/// A camera 5 to 60 units from a random target on the ground near the origin, looking
/// at it: orthographic (10 to 80 units tall) or perspective (0.5 to 1.5 rad), with the
/// target the scene's objects gather around.
pub fn random_camera(rng: &mut Rng, ortho: bool) -> (Camera, Vec3) {
    let target = Vec3::new(rng.range(-5.0, 5.0), 0.0, rng.range(-5.0, 5.0));
    let eye = target + direction(rng) * rng.range(5.0, 60.0);
    let camera = if ortho {
        orthographic(eye, target, rng.range(10.0, 80.0))
    } else {
        perspective(eye, target, rng.range(0.5, 1.5))
    };
    (camera, target)
}

/// A perspective camera with the tests' near plane (0.1).
pub fn perspective(position: Vec3, target: Vec3, fov_y: f32) -> Camera {
    Camera::perspective(position, target, fov_y, 0.1)
}

/// An orthographic camera `height` units tall, with the tests' depth range.
pub fn orthographic(position: Vec3, target: Vec3, height: f32) -> Camera {
    Camera {
        position,
        target,
        up: Vec3::Y,
        projection: Projection::Orthographic {
            height,
            near: 0.1,
            far: 200.0,
        },
    }
}
