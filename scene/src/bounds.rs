//! Bounding spheres: a cluster's own sphere for culling, and LOD spheres that must
//! enclose their children's so that projected error never grows toward the leaves.

use glam::Vec3;

/// A sphere plus the simplification error measured inside it, the pair the runtime
/// projects to pixels to choose a cut.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LodBounds {
    /// Centre of the sphere, in mesh space.
    pub center: Vec3,
    /// Radius of the sphere: the error is projected from its nearest point.
    pub radius: f32,
    /// Object-space error; `f32::INFINITY` for "no parent" (a root).
    pub error: f32,
}

impl LodBounds {
    /// The parent of a root: an infinite error, so that a root is drawn whenever
    /// nothing finer is.
    pub const ROOT_PARENT: LodBounds = LodBounds {
        center: Vec3::ZERO,
        radius: 0.0,
        error: f32::INFINITY,
    };
}

/// A sphere enclosing `points`: Ritter's two-pass estimate, then the exact farthest
/// distance from that centre, so containment of every point holds exactly.
pub fn sphere_of_points(points: impl Iterator<Item = Vec3> + Clone) -> (Vec3, f32) {
    let Some(first) = points.clone().next() else {
        return (Vec3::ZERO, 0.0);
    };
    let far = |from: Vec3| {
        points
            .clone()
            .fold((from, -1.0f32), |(best, d), p| {
                let dp = p.distance_squared(from);
                if dp > d { (p, dp) } else { (best, d) }
            })
            .0
    };
    let a = far(first);
    let b = far(a);
    let mut center = (a + b) * 0.5;
    let mut radius = a.distance(b) * 0.5;
    for p in points.clone() {
        let d = p.distance(center);
        if d > radius {
            let grow = (d - radius) * 0.5;
            radius += grow;
            center += (p - center) * (grow / d);
        }
    }
    let exact = points.map(|p| p.distance(center)).fold(0.0f32, f32::max);
    (center, exact)
}

/// The smallest sphere enclosing two spheres, padded by a relative epsilon so that
/// float rounding can never make a child stick out of its parent.
pub fn merge_spheres(a: (Vec3, f32), b: (Vec3, f32)) -> (Vec3, f32) {
    let (ca, ra) = a;
    let (cb, rb) = b;
    let d = ca.distance(cb);
    let (center, radius) = if d + rb <= ra {
        (ca, ra)
    } else if d + ra <= rb {
        (cb, rb)
    } else {
        let radius = (d + ra + rb) * 0.5;
        (ca + (cb - ca) * ((radius - ra) / d), radius)
    };
    (center, radius + pad(center, radius))
}

/// Slack for float rounding, relative to the magnitude of the numbers involved.
pub fn pad(center: Vec3, radius: f32) -> f32 {
    (center.abs().max_element() + radius) * 4.0 * f32::EPSILON
}

/// Whether `outer` contains `inner`, allowing float rounding.
pub fn contains(outer: (Vec3, f32), inner: (Vec3, f32)) -> bool {
    outer.0.distance(inner.0) + inner.1 <= outer.1 + pad(outer.0, outer.1)
}
