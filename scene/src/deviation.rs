//! Measured deviation of a simplified group from the surface it was simplified from.
//!
//! meshoptimizer's reported error is a quadric estimate: distance to the planes of the
//! collapsed neighbourhood, which underestimates the distance to the actual triangles at
//! edge midpoints and across creases. A group's LOD error must bound how far its output
//! lies from the full-detail surface, so the builder measures the real distance on the
//! output triangles and chains it level by level: if every point of the children lies
//! within `e` of LOD 0 and a point of the output lies within `d` of the children, it lies
//! within `e + d` of LOD 0 (triangle inequality).

use glam::Vec3;

use crate::mesh::{Fans, edge_key, triangle_edges};

/// Grid cells allowed per source triangle; more only costs memory without pruning more.
const CELLS_PER_TRIANGLE: usize = 4;

/// Largest distance from sample points of the `simplified` triangles to the surface of
/// the `source` triangles (both indexing `positions`).
///
/// Samples are each triangle's edge midpoints and centroid; its corners are vertices of
/// the source (simplification only removes vertices), so they lie on it.
///
/// Only the maximum is needed, so each sample is first measured against the source
/// triangles around its own triangle's corners, which is where the surface it replaced
/// lies: that is an upper bound of its distance, and when it is no larger than the
/// maximum so far the sample cannot raise it. Only the other samples are searched for
/// exactly, in a grid built the first time one needs it.
pub fn simplified_deviation(positions: &[Vec3], source: &[u32], simplified: &[u32]) -> f32 {
    if simplified.is_empty() || source.is_empty() {
        return 0.0;
    }
    let fans = Fans::new(positions.len(), source);
    let spheres: Vec<(Vec3, f32)> = source
        .chunks_exact(3)
        .map(|t| {
            let [a, b, c] = [t[0], t[1], t[2]].map(|i| positions[i as usize]);
            let centre = (a + b + c) / 3.0;
            let r2 = centre
                .distance_squared(a)
                .max(centre.distance_squared(b))
                .max(centre.distance_squared(c));
            (centre, r2.sqrt())
        })
        .collect();
    let mut grid: Option<TriangleGrid> = None;
    let mut worst = 0.0f32;
    let mut measure = |p: Vec3, corners: &[u32]| {
        // Only whether some triangle lies within `worst` matters here: when none does,
        // the grid search below finds the exact distance on its own. A triangle whose
        // bounding sphere is farther than `worst` cannot, so it is skipped unmeasured.
        let reach = worst.sqrt();
        for &v in corners {
            for &t in fans.of(v) {
                let (centre, radius) = spheres[t as usize];
                let r = radius + reach;
                if centre.distance_squared(p) > r * r {
                    continue;
                }
                let t = 3 * t as usize;
                let [a, b, c] =
                    [source[t], source[t + 1], source[t + 2]].map(|i| positions[i as usize]);
                if closest_on_triangle(p, a, b, c).distance_squared(p) <= worst {
                    return;
                }
            }
        }
        let grid = grid.get_or_insert_with(|| TriangleGrid::new(positions, source));
        worst = worst.max(grid.distance_squared(p, worst));
    };
    // Each edge once: the two triangles sharing it give the same midpoint.
    let mut edges: Vec<u64> = triangle_edges(simplified)
        .map(|(a, b)| edge_key(a, b))
        .collect();
    edges.sort_unstable();
    edges.dedup();
    // Triangles and edges kept unchanged from the source lie on it: their samples are
    // at distance zero and are not measured.
    for t in simplified.chunks_exact(3) {
        if fans.has_triangle(source, t[0], t[1], t[2]) {
            continue;
        }
        let [a, b, c] = [t[0], t[1], t[2]].map(|v| positions[v as usize]);
        measure((a + b + c) / 3.0, t);
    }
    for e in edges {
        let (i, j) = ((e >> 32) as u32, e as u32);
        if fans.has_edge(source, i, j) {
            continue;
        }
        measure(
            (positions[i as usize] + positions[j as usize]) * 0.5,
            &[i, j],
        );
    }
    worst.sqrt()
}

/// Lookups on the source triangles around each vertex.
impl Fans {
    /// Whether some source triangle has the edge `i`–`j`.
    pub(crate) fn has_edge(&self, source: &[u32], i: u32, j: u32) -> bool {
        self.of(i)
            .iter()
            .any(|&t| source[3 * t as usize..3 * t as usize + 3].contains(&j))
    }

    /// Whether some source triangle has the corners `a`, `b` and `c`.
    pub(crate) fn has_triangle(&self, source: &[u32], a: u32, b: u32, c: u32) -> bool {
        self.of(a).iter().any(|&t| {
            let s = &source[3 * t as usize..3 * t as usize + 3];
            s.contains(&b) && s.contains(&c)
        })
    }
}

/// A uniform grid over a small triangle set (one group), answering nearest-distance
/// queries. Cells hold every triangle whose bounding box overlaps them.
struct TriangleGrid {
    triangles: Vec<[Vec3; 3]>,
    origin: Vec3,
    cell: f32,
    dims: [i32; 3],
    /// Cell `i`'s triangles are `items[start[i]..start[i + 1]]`.
    start: Vec<u32>,
    items: Vec<u32>,
}

impl TriangleGrid {
    fn new(positions: &[Vec3], indices: &[u32]) -> Self {
        let triangles: Vec<[Vec3; 3]> = indices
            .chunks_exact(3)
            .map(|t| [t[0], t[1], t[2]].map(|v| positions[v as usize]))
            .collect();
        let (mut lo, mut hi) = (Vec3::splat(f32::MAX), Vec3::splat(f32::MIN));
        let mut extent_sum = 0.0f32;
        for [a, b, c] in &triangles {
            let (tlo, thi) = (a.min(*b).min(*c), a.max(*b).max(*c));
            lo = lo.min(tlo);
            hi = hi.max(thi);
            extent_sum += (thi - tlo).max_element();
        }
        let size = (hi - lo).max(Vec3::splat(f32::MIN_POSITIVE));
        // About one triangle across a cell; coarser when that would be too many cells
        // (a group is a surface patch, so cells ~ triangles for a well-shaped one).
        let mut cell = (extent_sum / triangles.len() as f32).max(size.max_element() * 1e-4);
        let limit = triangles.len() * CELLS_PER_TRIANGLE + 64;
        let dims = loop {
            let d = (size / cell).ceil().max(Vec3::ONE);
            let d = [d.x as i32, d.y as i32, d.z as i32];
            if d.iter().map(|&n| n as usize).product::<usize>() <= limit {
                break d;
            }
            cell *= 1.25;
        };
        let inv = 1.0 / cell;
        let cell_of = |p: Vec3| -> [i32; 3] {
            let r = ((p - lo) * inv).floor();
            let r = [r.x as i32, r.y as i32, r.z as i32];
            std::array::from_fn(|k| r[k].clamp(0, dims[k] - 1))
        };
        let index = |x: i32, y: i32, z: i32| ((z * dims[1] + y) * dims[0] + x) as usize;
        let ranges: Vec<([i32; 3], [i32; 3])> = triangles
            .iter()
            .map(|[a, b, c]| (cell_of(a.min(*b).min(*c)), cell_of(a.max(*b).max(*c))))
            .collect();
        let cells = dims.iter().map(|&n| n as usize).product::<usize>();
        let mut start = vec![0u32; cells + 1];
        for (l, h) in &ranges {
            for z in l[2]..=h[2] {
                for y in l[1]..=h[1] {
                    for x in l[0]..=h[0] {
                        start[index(x, y, z) + 1] += 1;
                    }
                }
            }
        }
        for i in 0..cells {
            start[i + 1] += start[i];
        }
        let mut fill = start.clone();
        let mut items = vec![0u32; start[cells] as usize];
        for (t, (l, h)) in ranges.iter().enumerate() {
            for z in l[2]..=h[2] {
                for y in l[1]..=h[1] {
                    for x in l[0]..=h[0] {
                        let f = &mut fill[index(x, y, z)];
                        items[*f as usize] = t as u32;
                        *f += 1;
                    }
                }
            }
        }
        Self {
            triangles,
            origin: lo,
            cell,
            dims,
            start,
            items,
        }
    }

    /// Squared distance from `p` to the nearest triangle, or any value ≤ `known` when the
    /// nearest is no farther than `known` (the caller only needs the maximum over points,
    /// so the search stops as soon as a triangle that close is found).
    fn distance_squared(&self, p: Vec3, known: f32) -> f32 {
        let rel = ((p - self.origin) / self.cell).floor();
        let c = [rel.x as i32, rel.y as i32, rel.z as i32];
        let c: [i32; 3] = std::array::from_fn(|k| c[k].clamp(0, self.dims[k] - 1));
        let max_ring = (0..3)
            .map(|k| c[k].max(self.dims[k] - 1 - c[k]))
            .max()
            .unwrap_or(0);
        let mut best = f32::INFINITY;
        for ring in 0..=max_ring {
            // Every cell of this ring is at least (ring - 1) cells from the clamped
            // point's cell, and p is no closer to the grid than its clamp onto it.
            let floor = (ring - 1).max(0) as f32 * self.cell;
            if best <= floor * floor {
                break;
            }
            let lo: [i32; 3] = std::array::from_fn(|k| (c[k] - ring).max(0));
            let hi: [i32; 3] = std::array::from_fn(|k| (c[k] + ring).min(self.dims[k] - 1));
            for z in lo[2]..=hi[2] {
                for y in lo[1]..=hi[1] {
                    // Only the cells on this ring's shell: all of a row on a face of the
                    // cube, its two ends elsewhere, taken directly (iterating the whole
                    // cube, or every row, and skipping the inside cost most of the
                    // search's time).
                    let face = (z - c[2]).abs() == ring || (y - c[1]).abs() == ring;
                    let ends = [c[0] - ring, c[0] + ring];
                    // An end past the grid is not there; at ring 0 the ends are one.
                    let end = |k: usize| {
                        let x = ends[k];
                        (!face && (0..self.dims[0]).contains(&x) && (k == 0 || ring > 0))
                            .then_some(x)
                    };
                    let row = if face { lo[0]..hi[0] + 1 } else { 0..0 };
                    let xs = row.chain(end(0)).chain(end(1));
                    for x in xs {
                        let box_lo =
                            self.origin + Vec3::new(x as f32, y as f32, z as f32) * self.cell;
                        let gap = (box_lo - p).max(p - (box_lo + self.cell)).max(Vec3::ZERO);
                        if gap.length_squared() >= best {
                            continue;
                        }
                        let i = ((z * self.dims[1] + y) * self.dims[0] + x) as usize;
                        let range = self.start[i] as usize..self.start[i + 1] as usize;
                        for &t in &self.items[range] {
                            let [a, b, cc] = self.triangles[t as usize];
                            let d = closest_on_triangle(p, a, b, cc).distance_squared(p);
                            // A NaN from a degenerate triangle is skipped: a larger
                            // distance only makes the bound more conservative.
                            if d < best {
                                best = d;
                                if best <= known {
                                    return best;
                                }
                            }
                        }
                    }
                }
            }
        }
        best
    }
}

/// Which part of a triangle abc holds the point nearest to some p: a corner, a point
/// `t` of the way along an edge, or the inside (with the barycentric areas `va`, `vb`,
/// `vc`, to be divided by their sum). Found by the Voronoi regions of the corners and
/// edges (Ericson, Real-Time Collision Detection, 5.1.5), for points of any dimension:
/// the surface deviation asks it in object space, the texture slide in UV space.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum TriangleRegion {
    /// Corner a.
    A,
    /// Corner b.
    B,
    /// Corner c.
    C,
    /// `a + (b - a) · t`.
    Ab(f32),
    /// `a + (c - a) · t`.
    Ac(f32),
    /// `b + (c - b) · t`.
    Bc(f32),
    /// The inside, at barycentric weights proportional to `va`, `vb`, `vc`.
    Inside {
        /// Weight of a (before division by the sum).
        va: f32,
        /// Weight of b.
        vb: f32,
        /// Weight of c.
        vc: f32,
    },
}

/// A point [`triangle_region`] measures: differences and dot products.
pub trait TrianglePoint: Copy + std::ops::Sub<Output = Self> {
    /// The dot product.
    fn dot(self, other: Self) -> f32;
}

impl TrianglePoint for Vec3 {
    fn dot(self, other: Self) -> f32 {
        Vec3::dot(self, other)
    }
}

impl TrianglePoint for glam::Vec2 {
    fn dot(self, other: Self) -> f32 {
        glam::Vec2::dot(self, other)
    }
}

/// The region of triangle abc nearest to `p` (see [`TriangleRegion`]).
pub fn triangle_region<P: TrianglePoint>(p: P, a: P, b: P, c: P) -> TriangleRegion {
    let (ab, ac, ap) = (b - a, c - a, p - a);
    let (d1, d2) = (ab.dot(ap), ac.dot(ap));
    if d1 <= 0.0 && d2 <= 0.0 {
        return TriangleRegion::A;
    }
    let bp = p - b;
    let (d3, d4) = (ab.dot(bp), ac.dot(bp));
    if d3 >= 0.0 && d4 <= d3 {
        return TriangleRegion::B;
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        return TriangleRegion::Ab(d1 / (d1 - d3));
    }
    let cp = p - c;
    let (d5, d6) = (ab.dot(cp), ac.dot(cp));
    if d6 >= 0.0 && d5 <= d6 {
        return TriangleRegion::C;
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        return TriangleRegion::Ac(d2 / (d2 - d6));
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && d4 - d3 >= 0.0 && d5 - d6 >= 0.0 {
        return TriangleRegion::Bc((d4 - d3) / ((d4 - d3) + (d5 - d6)));
    }
    TriangleRegion::Inside { va, vb, vc }
}

/// Closest point on triangle abc to p.
pub fn closest_on_triangle(p: Vec3, a: Vec3, b: Vec3, c: Vec3) -> Vec3 {
    match triangle_region(p, a, b, c) {
        TriangleRegion::A => a,
        TriangleRegion::B => b,
        TriangleRegion::C => c,
        TriangleRegion::Ab(t) => a + (b - a) * t,
        TriangleRegion::Ac(t) => a + (c - a) * t,
        TriangleRegion::Bc(t) => b + (c - b) * t,
        TriangleRegion::Inside { va, vb, vc } => {
            let denom = 1.0 / (va + vb + vc);
            a + (b - a) * (vb * denom) + (c - a) * (vc * denom)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Brute force over every triangle, for comparison with the grid.
    fn brute(positions: &[Vec3], source: &[u32], simplified: &[u32]) -> f32 {
        let mut worst = 0.0f32;
        for t in simplified.chunks_exact(3) {
            let [a, b, c] = [t[0], t[1], t[2]].map(|v| positions[v as usize]);
            for p in [
                (a + b) * 0.5,
                (b + c) * 0.5,
                (c + a) * 0.5,
                (a + b + c) / 3.0,
            ] {
                let d = source
                    .chunks_exact(3)
                    .map(|s| {
                        let [x, y, z] = [s[0], s[1], s[2]].map(|v| positions[v as usize]);
                        closest_on_triangle(p, x, y, z).distance(p)
                    })
                    .fold(f32::INFINITY, f32::min);
                worst = worst.max(d);
            }
        }
        worst
    }

    #[test]
    fn grid_agrees_with_brute_force_on_a_bumpy_patch() {
        // A bumpy height field, and a coarse version of it that skips every other vertex.
        let n = 24;
        let height = |x: usize, y: usize| ((x as f32 * 0.7).sin() * (y as f32 * 0.5).cos()) * 0.8;
        let positions: Vec<Vec3> = (0..=n)
            .flat_map(|y| (0..=n).map(move |x| Vec3::new(x as f32, y as f32, height(x, y))))
            .collect();
        let id = |x: usize, y: usize| (y * (n + 1) + x) as u32;
        let quads = |step: usize| {
            let mut out = Vec::new();
            for y in (0..n).step_by(step) {
                for x in (0..n).step_by(step) {
                    let (a, b, c, d) = (
                        id(x, y),
                        id(x + step, y),
                        id(x + step, y + step),
                        id(x, y + step),
                    );
                    out.extend([a, b, c, a, c, d]);
                }
            }
            out
        };
        let (fine, coarse) = (quads(1), quads(2));
        let grid = simplified_deviation(&positions, &fine, &coarse);
        let exact = brute(&positions, &fine, &coarse);
        assert!(exact > 0.05, "the coarse patch deviates ({exact})");
        assert_eq!(grid, exact);
        // Only float rounding of the sample points (centroids) off their own triangle.
        assert!(simplified_deviation(&positions, &fine, &fine) < 1e-5);
    }

    #[test]
    fn points_off_the_source_are_measured() {
        let positions = [
            Vec3::ZERO,
            Vec3::X,
            Vec3::Y,
            Vec3::new(0.0, 0.0, 2.0),
            Vec3::new(1.0, 0.0, 2.0),
            Vec3::new(0.0, 1.0, 2.0),
        ];
        let d = simplified_deviation(&positions, &[0, 1, 2], &[3, 4, 5]);
        assert!((d - 2.0).abs() < 1e-6, "{d}");
    }
}
