//! The viewer's camera: flown (WASD/QE, mouse look) or orbiting a target, turned into
//! the renderer's [`Camera`] each frame.

use glam::Vec3;
use meshlight::gpu_scene::Camera;

/// Fly or orbit; both look with yaw and pitch, so switching keeps the view.
#[derive(Clone, Debug)]
pub struct CameraRig {
    pub position: Vec3,
    /// Radians around +Y, 0 looking down -Z.
    pub yaw: f32,
    /// Radians above the horizon.
    pub pitch: f32,
    /// Metres per second when flying (scroll changes it).
    pub speed: f32,
    /// Orbit mode: the camera circles `pivot` at `distance`.
    pub orbit: bool,
    pub pivot: Vec3,
    pub distance: f32,
    /// The lens of the scene's camera (field of view, near plane).
    lens: Camera,
    start: (Vec3, Vec3),
    /// The camera exactly as placed, until the rig moves: a fixed camera renders the
    /// same view matrix as `meshlight render` with that camera.
    placed: Option<Camera>,
}

impl CameraRig {
    /// A rig at `camera`'s place, looking where it looks.
    pub fn new(camera: Camera) -> Self {
        let mut rig = Self {
            position: camera.position,
            yaw: 0.0,
            pitch: 0.0,
            speed: 1.0,
            orbit: false,
            pivot: camera.target,
            distance: 1.0,
            lens: camera,
            start: (camera.position, camera.target),
            placed: None,
        };
        rig.look_at(camera.position, camera.target);
        rig
    }

    /// Puts the camera at `position` looking at `target` (which becomes the orbit's
    /// pivot); flying speed follows the distance.
    pub fn look_at(&mut self, position: Vec3, target: Vec3) {
        let d = target - position;
        self.position = position;
        self.pivot = target;
        self.distance = d.length().max(1e-3);
        let dir = d / self.distance;
        self.yaw = dir.x.atan2(-dir.z);
        self.pitch = dir.y.clamp(-1.0, 1.0).asin();
        self.speed = (self.distance * 0.5).max(0.1);
        let mut placed = self.lens;
        placed.position = position;
        placed.target = target;
        self.placed = Some(placed);
    }

    /// Back to where the rig started (R).
    pub fn reset(&mut self) {
        let (p, t) = self.start;
        self.orbit = false;
        self.look_at(p, t);
    }

    pub fn forward(&self) -> Vec3 {
        let (sy, cy) = self.yaw.sin_cos();
        let (sp, cp) = self.pitch.sin_cos();
        Vec3::new(sy * cp, sp, -cy * cp)
    }

    /// Mouse look by pixels moved.
    pub fn rotate(&mut self, dx: f32, dy: f32) {
        const RADIANS_PER_PIXEL: f32 = 0.004;
        self.placed = None;
        self.yaw += dx * RADIANS_PER_PIXEL;
        self.pitch = (self.pitch - dy * RADIANS_PER_PIXEL).clamp(-1.55, 1.55);
        if self.orbit {
            self.position = self.pivot - self.forward() * self.distance;
        }
    }

    /// Moves by `local` (x right, y up, z forward) for `seconds`; in orbit mode forward
    /// is toward the pivot and sideways circles it.
    pub fn travel(&mut self, local: Vec3, seconds: f32) {
        if local == Vec3::ZERO {
            return;
        }
        self.placed = None;
        let forward = self.forward();
        let right = forward.cross(Vec3::Y).normalize_or_zero();
        if self.orbit {
            self.distance = (self.distance * (1.0 - local.z * seconds)).max(1e-3);
            self.rotate(local.x * seconds * 400.0, -local.y * seconds * 400.0);
            self.position = self.pivot - self.forward() * self.distance;
        } else {
            let step = (right * local.x + Vec3::Y * local.y + forward * local.z) * self.speed;
            self.position += step * seconds;
        }
    }

    /// Enters or leaves orbit mode; entering orbits the point the camera looks at, at
    /// the distance it had.
    pub fn toggle_orbit(&mut self) {
        self.orbit = !self.orbit;
        self.placed = None;
        if self.orbit {
            self.pivot = self.position + self.forward() * self.distance;
        }
    }

    /// Scroll: faster or slower flight.
    pub fn scale_speed(&mut self, notches: f32) {
        self.speed = (self.speed * 1.2f32.powf(notches)).clamp(1e-3, 1e5);
    }

    /// The renderer's camera for the rig's place.
    pub fn camera(&self) -> Camera {
        if let Some(c) = self.placed {
            return c;
        }
        let mut c = self.lens;
        c.position = self.position;
        c.target = self.position + self.forward() * self.distance;
        c
    }
}
