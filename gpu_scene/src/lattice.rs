//! The virtual-geometry benchmark's scene: `n`³ copies of one mesh in a cube, 2.5 mesh
//! radii apart, and a camera outside one corner that frames the whole cube. Here, below
//! both, so that the benchmark and the tests that reproduce its counts place the same
//! instances and look at them the same way.

use crate::view::Camera;
use glam::{Mat4, Vec3};

/// A cube of `n`³ placements of a mesh of bounding radius `radius`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Lattice {
    /// Copies along each axis.
    pub n: u32,
    /// The mesh's bounding radius: the spacing and the camera's near plane follow it.
    pub radius: f32,
}

impl Lattice {
    /// Distance between neighbouring copies.
    pub fn spacing(&self) -> f32 {
        self.radius * 2.5
    }

    /// The placements, x fastest, then y, then z.
    pub fn transforms(&self) -> impl Iterator<Item = Mat4> {
        let (n, spacing) = (self.n, self.spacing());
        (0..n * n * n).map(move |i| {
            let cell = Vec3::new((i % n) as f32, (i / n % n) as f32, (i / (n * n)) as f32);
            Mat4::from_translation(cell * spacing)
        })
    }

    /// A 50° camera outside one corner, far enough to see every copy.
    pub fn camera(&self) -> Camera {
        let spacing = self.spacing();
        let centre = Vec3::splat((self.n as f32 - 1.0) * 0.5 * spacing);
        let extent = self.n as f32 * spacing;
        Camera::perspective(
            centre + Vec3::new(0.9, 0.6, 1.2).normalize() * extent * 1.3,
            centre,
            50f32.to_radians(),
            self.radius * 0.05,
        )
    }
}
