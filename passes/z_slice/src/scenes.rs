//! Seeded random scenes of clusterable objects and the cameras to view them, for the
//! light-clustering stages' tests and benchmarks: every stage is compared with its
//! reference on the same reproducible scenes.

use glam::Vec3;
use meshlight_gpu_scene::{Camera, Projection};
use meshlight_shaders::cpu::layout::{ClusterableKind, ClusterableObject};

/// xorshift64*: seeded, reproducible scenes.
pub struct Rng(pub u64);

impl Rng {
    pub fn next_u64(&mut self) -> u64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        self.0.wrapping_mul(0x2545_f491_4f6c_dd1d)
    }
    pub fn unit(&mut self) -> f32 {
        (self.next_u64() >> 40) as f32 / (1u64 << 24) as f32
    }
    pub fn range(&mut self, lo: f32, hi: f32) -> f32 {
        lo + (hi - lo) * self.unit()
    }
    pub fn below(&mut self, n: u32) -> u32 {
        (self.next_u64() % n as u64) as u32
    }
    pub fn direction(&mut self) -> Vec3 {
        Vec3::new(
            self.range(-1.0, 1.0),
            self.range(-1.0, 1.0),
            self.range(-1.0, 1.0),
        )
        .normalize_or(Vec3::Y)
    }
}

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

pub fn spot(position: Vec3, direction: Vec3, range: f32, half_angle: f32) -> ClusterableObject {
    let mut o = object(ClusterableKind::SpotLight, position, range);
    o.direction_cos_angle = [direction.x, direction.y, direction.z, half_angle.cos()];
    o.sin_angle = half_angle.sin();
    o
}

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
                    let d = rng.direction();
                    spot(position, d, range, rng.range(0.05, 1.5))
                }
                kind => {
                    let mut o = object(kind, position, range);
                    let d = rng.direction();
                    o.direction_cos_angle = [d.x, d.y, d.z, 1.0];
                    o
                }
            }
        })
        .collect()
}

pub fn perspective(position: Vec3, target: Vec3, fov_y: f32) -> Camera {
    Camera::perspective(position, target, fov_y, 0.1)
}

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
