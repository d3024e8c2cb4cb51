//! The built-in default mesh: a bumpy (3,5) torus knot, so that `meshlight` runs with no
//! files. A tube swept along a closed curve, with both parameters wrapping, is closed
//! and manifold by construction, which the crack-free cut test relies on; the bumps
//! give the simplifier real curvature to work against.

use std::f32::consts::TAU;

use glam::Vec3;

use crate::mesh::Mesh;

/// Tube segments of the default mesh: 16 × 256² = 1,048,576 triangles.
pub const DEFAULT_SEGMENTS: u32 = 256;

/// Triangles of [`procedural_mesh`] for a segment count.
pub fn procedural_triangle_count(segments: u32) -> usize {
    let (along, around) = grid(segments);
    2 * along as usize * around as usize
}

fn grid(segments: u32) -> (u32, u32) {
    let around = segments.max(3);
    (around * 8, around)
}

/// A deterministic closed, manifold torus knot with `16 × segments²` triangles
/// (segments ≥ 3). Same segments, same bytes, on every machine: only `sin`/`cos` of
/// `f32`, evaluated in a fixed order.
pub fn procedural_mesh(segments: u32) -> Mesh {
    knot_mesh(segments, Knot::DEFAULT)
}

/// The shape of a bumpy torus knot: the default mesh's, or one of a family of others
/// (a generated world places a different one on each tile).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Knot {
    /// Turns around the axis of symmetry (coprime with `q` for one closed tube).
    pub p: u32,
    /// Turns through the torus's hole.
    pub q: u32,
    /// Shifts the bumps along the tube and around it: knots differing only in it have
    /// their bumps in other places.
    pub phase: f32,
}

impl Knot {
    /// The default mesh's: a (3,5) knot.
    pub const DEFAULT: Knot = Knot {
        p: 3,
        q: 5,
        phase: 0.0,
    };
}

/// A bumpy `knot` with `16 × segments²` triangles, closed and manifold as
/// [`procedural_mesh`] is (which is `knot_mesh(segments, Knot::DEFAULT)`).
pub fn knot_mesh(segments: u32, knot: Knot) -> Mesh {
    let (along, around) = grid(segments);
    let (p, q) = (knot.p as f32, knot.q as f32);
    let phase = knot.phase;
    let curve = |t: f32| {
        let r = 2.0 + (q * t).cos();
        Vec3::new(r * (p * t).cos(), r * (p * t).sin(), -(q * t).sin())
    };
    let mut positions = Vec::with_capacity((along * around) as usize);
    for i in 0..along {
        let t = TAU * i as f32 / along as f32;
        let c = curve(t);
        // Central difference over a tiny step: the tangent of a closed curve is periodic,
        // so the frame below wraps with it.
        let h = 1e-3;
        let tangent = (curve(t + h) - curve(t - h)).normalize();
        // Rotation-minimising frames would twist by a non-integer angle over one loop and
        // leave a seam; a frame from the tangent and a fixed axis is periodic.
        let side = tangent.cross(Vec3::Z).normalize();
        let up = side.cross(tangent);
        for j in 0..around {
            let s = TAU * j as f32 / around as f32;
            let bumps = 0.06 * (7.0 * t + phase).sin() * (3.0 * s).sin()
                + 0.03 * (41.0 * t + 2.0 * s + phase).sin()
                + 0.015 * (97.0 * t).cos() * (9.0 * s + phase).cos();
            let radius = 0.45 * (1.0 + bumps);
            positions.push(c + radius * (side * s.cos() + up * s.sin()));
        }
    }
    let mut indices = Vec::with_capacity(procedural_triangle_count(segments) * 3);
    for i in 0..along {
        let i1 = (i + 1) % along;
        for j in 0..around {
            let j1 = (j + 1) % around;
            let v = |a: u32, b: u32| a * around + b;
            indices.extend_from_slice(&[v(i, j), v(i1, j), v(i1, j1)]);
            indices.extend_from_slice(&[v(i, j), v(i1, j1), v(i, j1)]);
        }
    }
    let mut mesh = Mesh {
        source: match knot == Knot::DEFAULT {
            true => format!("procedural torus knot ({segments} segments)"),
            false => format!(
                "procedural ({}, {}) torus knot, phase {} ({segments} segments)",
                knot.p, knot.q, knot.phase
            ),
        },
        positions,
        normals: Vec::new(),
        uvs: Vec::new(),
        colors: Vec::new(),
        indices,
        materials: Vec::new(),
    };
    mesh.generate_normals();
    mesh
}
