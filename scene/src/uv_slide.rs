//! How far a texture slides over the surface when a group is simplified.
//!
//! Simplification keeps vertices where they were, but a coarse triangle interpolates its
//! corners' UVs across a region where the full-detail mesh had other vertices with other
//! UVs, so a texel the coarse triangle draws at a point was drawn somewhere else at full
//! detail. That distance, in object units, is the texture's error at the point: the units
//! of the position error, so that one LOD error bounds both.
//!
//! It is measured against the level the group was simplified from, the whole of it: near
//! a group's border a coarse triangle's UVs may reach into a neighbouring group's part of
//! the map (the border is fixed in place and in UV, but a coarse edge is a straight chord
//! across a curved map). A point of the output carrying the UV `u` lies within `d` of a
//! point of the level carrying `u`, on a cluster that lies within its own error `e` of
//! LOD 0, so the texel is within `d + e` of where LOD 0 draws it (triangle inequality):
//! that sum, over the output's samples, bounds the group's slide from LOD 0.
//!
//! The point carrying `u` is looked for on the sample's own chart only: the triangles
//! joined to it through shared vertices, which is a piece of the map with no seam inside
//! ([`uv_charts`]). An atlas packs charts of far-apart parts side by side, so a UV just
//! outside a chart usually lies in another one; the texel shown there is a bleed across
//! the seam, not the other part's surface brought over. Such a sample (a coarse border
//! edge cutting across a curved chart border, or a collapse across a seam) is measured
//! to the point of its chart with the nearest UV, plus that UV gap in object units (see
//! [`texel_size`]): never below what the texture visibly moved, but an estimate, not a
//! bound.

use glam::{Vec2, Vec3};

use crate::deviation::{TriangleRegion, triangle_region};
use crate::mesh::{Fans, edge_key, triangle_edges};

/// How far outside a UV triangle (in barycentric units) a sample still counts as inside:
/// samples on a chart's border edges are exactly on it and round either way.
const INSIDE: f32 = 1e-4;

/// Rings of grid cells searched around a sample for the nearest UV of its chart.
const MAX_RINGS: i32 = 32;

/// Object units per UV unit over the whole mesh: the square root of its surface area
/// over its UV area. It turns a UV difference into how far a texel moved on the surface,
/// and weighs UVs against positions in the simplifier. 0 when the UVs cover no area.
pub fn texel_size(positions: &[Vec3], uvs: &[[f32; 2]], indices: &[u32]) -> f32 {
    if uvs.is_empty() {
        return 0.0;
    }
    let (mut area, mut uv_area) = (0.0f64, 0.0f64);
    for t in indices.chunks_exact(3) {
        let [a, b, c] = [t[0], t[1], t[2]].map(|v| positions[v as usize]);
        area += f64::from((b - a).cross(c - a).length());
        let [a, b, c] = [t[0], t[1], t[2]].map(|v| Vec2::from(uvs[v as usize]));
        uv_area += f64::from((b - a).perp_dot(c - a).abs());
    }
    if uv_area > 0.0 && area.is_finite() && uv_area.is_finite() {
        (area / uv_area).sqrt() as f32
    } else {
        0.0
    }
}

/// Each vertex's chart: the connected piece of `indices` (joined through shared vertex
/// ids, so split wherever a seam gave a position several vertices) it belongs to, named
/// by its lowest vertex id. Unused vertices are their own chart.
pub fn uv_charts(vertex_count: usize, indices: &[u32]) -> Vec<u32> {
    let mut parent: Vec<u32> = (0..vertex_count as u32).collect();
    fn root(parent: &mut [u32], mut v: u32) -> u32 {
        while parent[v as usize] != v {
            let up = parent[parent[v as usize] as usize];
            parent[v as usize] = up;
            v = up;
        }
        v
    }
    for t in indices.chunks_exact(3) {
        for &v in &t[1..] {
            let (a, b) = (root(&mut parent, t[0]), root(&mut parent, v));
            // The lower root names the joined set.
            parent[a.max(b) as usize] = a.min(b);
        }
    }
    (0..vertex_count as u32)
        .map(|v| root(&mut parent, v))
        .collect()
}

/// Largest slide from LOD 0 of the `simplified` triangles' texture (indexing the
/// `positions`, `uvs` and per-vertex `charts` of `level`), in object units: each
/// sample's distance to the nearest point of `level` carrying its UV plus that point's
/// cluster error (see the module's doc).
///
/// Samples are each triangle's edge midpoints and centroid, as for the position
/// deviation; corners are vertices of the level with their own UVs, where nothing slid.
/// Triangles and edges the simplification kept (those of `source`) are not measured:
/// they are part of the level, within its errors already.
pub fn simplified_uv_slide(level: &UvSurface<'_>, source: &[u32], simplified: &[u32]) -> f32 {
    // A map of no area (every UV on one line, or all zero, as some exporters write)
    // shows no texture that could slide.
    if level.uvs.is_empty() || level.texel == 0.0 || simplified.is_empty() {
        return 0.0;
    }
    let (positions, uvs) = (level.positions, level.uvs);
    let fans = Fans::new(positions.len(), source);
    let mut worst = 0.0f32;
    let mut measure = |corners: &[u32]| {
        let n = corners.len() as f32;
        let p = corners.iter().map(|&v| positions[v as usize]).sum::<Vec3>() / n;
        let uv = corners
            .iter()
            .map(|&v| Vec2::from(uvs[v as usize]))
            .sum::<Vec2>()
            / n;
        worst = worst.max(level.slide(p, uv, level.chart(corners[0])));
    };
    for t in simplified.chunks_exact(3) {
        if !fans.has_triangle(source, t[0], t[1], t[2]) {
            measure(t);
        }
    }
    let mut edges: Vec<u64> = triangle_edges(simplified)
        .map(|(a, b)| edge_key(a, b))
        .collect();
    edges.sort_unstable();
    edges.dedup();
    for e in edges {
        let (i, j) = ((e >> 32) as u32, e as u32);
        if !fans.has_edge(source, i, j) {
            measure(&[i, j]);
        }
    }
    worst
}

/// A set of triangles looked up by UV: a uniform grid over their UV bounds whose cells
/// hold every triangle whose UV bounding box overlaps them, and each triangle's error
/// against LOD 0.
pub struct UvSurface<'a> {
    positions: &'a [Vec3],
    uvs: &'a [[f32; 2]],
    /// Each vertex's chart ([`uv_charts`]).
    charts: &'a [u32],
    /// Object units per UV unit ([`texel_size`]).
    texel: f32,
    triangles: Vec<[u32; 3]>,
    /// Each triangle's error against LOD 0 (0 for LOD 0 itself).
    errors: Vec<f32>,
    origin: Vec2,
    /// Cells per UV unit, per axis.
    scale: Vec2,
    dims: [i32; 2],
    /// Cell `i`'s triangles are `items[start[i]..start[i + 1]]`.
    start: Vec<u32>,
    items: Vec<u32>,
}

impl<'a> UvSurface<'a> {
    /// The grid over the triangles `indices` (three vertex ids each), all of error 0.
    pub fn new(
        positions: &'a [Vec3],
        uvs: &'a [[f32; 2]],
        charts: &'a [u32],
        indices: &[u32],
        texel: f32,
    ) -> Self {
        let triangles: Vec<[u32; 3]> = match uvs.is_empty() {
            true => Vec::new(),
            false => indices
                .chunks_exact(3)
                .map(|t| [t[0], t[1], t[2]])
                .collect(),
        };
        let uv = |v: u32| Vec2::from(uvs[v as usize]);
        let (mut lo, mut hi) = (Vec2::ZERO, Vec2::ZERO);
        if let Some(&[v, ..]) = triangles.first() {
            (lo, hi) = (uv(v), uv(v));
        }
        for t in &triangles {
            for &v in t {
                lo = lo.min(uv(v));
                hi = hi.max(uv(v));
            }
        }
        // About one cell per triangle, square in UV.
        let extent = (hi - lo).max(Vec2::splat(1e-6));
        let side = (extent.x * extent.y / triangles.len().max(1) as f32).sqrt();
        let dims = (extent / side.max(f32::MIN_POSITIVE))
            .ceil()
            .clamp(Vec2::ONE, Vec2::splat(2048.0));
        let scale = dims / extent;
        let dims = [dims.x as i32, dims.y as i32];
        let cell_of = |p: Vec2| {
            let c = ((p - lo) * scale).floor();
            [
                (c.x as i32).clamp(0, dims[0] - 1),
                (c.y as i32).clamp(0, dims[1] - 1),
            ]
        };
        let cells = (dims[0] * dims[1]) as usize;
        let ranges: Vec<([i32; 2], [i32; 2])> = triangles
            .iter()
            .map(|t| {
                let [a, b, c] = t.map(uv);
                (cell_of(a.min(b).min(c)), cell_of(a.max(b).max(c)))
            })
            .collect();
        let for_cells = |(l, h): ([i32; 2], [i32; 2]), f: &mut dyn FnMut(usize)| {
            for y in l[1]..=h[1] {
                for x in l[0]..=h[0] {
                    f((y * dims[0] + x) as usize);
                }
            }
        };
        let mut start = vec![0u32; cells + 1];
        for &r in &ranges {
            for_cells(r, &mut |i| start[i + 1] += 1);
        }
        for i in 0..cells {
            start[i + 1] += start[i];
        }
        let mut fill = start.clone();
        let mut items = vec![0u32; start[cells] as usize];
        for (t, &r) in ranges.iter().enumerate() {
            for_cells(r, &mut |i| {
                items[fill[i] as usize] = t as u32;
                fill[i] += 1;
            });
        }
        Self {
            positions,
            uvs,
            charts,
            texel,
            errors: vec![0.0; triangles.len()],
            triangles,
            origin: lo,
            scale,
            dims,
            start,
            items,
        }
    }

    /// The same surface with each triangle's error against LOD 0 (one per triangle, in
    /// the order of `indices`).
    pub fn with_errors(mut self, errors: Vec<f32>) -> Self {
        debug_assert_eq!(errors.len(), self.triangles.len());
        self.errors = errors;
        self
    }

    /// A vertex's chart.
    pub fn chart(&self, v: u32) -> u32 {
        self.charts[v as usize]
    }

    /// How far from LOD 0's the texel at `uv` drawn at `p` is (see the module's doc): the
    /// nearest point of a triangle of `chart` carrying `uv`, plus that triangle's error,
    /// or, where none carries it, the point of the chart with the nearest UV plus the gap
    /// in object units and its triangle's error.
    pub fn slide(&self, p: Vec3, uv: Vec2, chart: u32) -> f32 {
        if self.triangles.is_empty() {
            return 0.0;
        }
        let c = ((uv - self.origin) * self.scale).floor();
        let mut best = f32::INFINITY;
        if c.x >= 0.0 && c.y >= 0.0 && c.x < self.dims[0] as f32 && c.y < self.dims[1] as f32 {
            for &t in self.cell([c.x as i32, c.y as i32]) {
                let tri = self.triangles[t as usize];
                if self.charts[tri[0] as usize] != chart {
                    continue;
                }
                let [a, b, c] = tri.map(|v| Vec2::from(self.uvs[v as usize]));
                if let Some(w) = inside(uv, a, b, c) {
                    best = best.min(self.point(t, w).distance(p) + self.errors[t as usize]);
                }
            }
        }
        if best.is_finite() {
            return best;
        }
        // No triangle carries this UV: the nearest UV instead, its gap counted. Rings of
        // cells around the sample's, until no nearer cell can beat the best so far.
        let home = [
            (c.x.clamp(0.0, (self.dims[0] - 1) as f32)) as i32,
            (c.y.clamp(0.0, (self.dims[1] - 1) as f32)) as i32,
        ];
        let cell_side = (1.0 / self.scale).min_element();
        // How far outside the grid the sample is, in UV, which every ring adds to.
        let outside = (self.origin - uv)
            .max(
                uv - (self.origin
                    + Vec2::new(self.dims[0] as f32, self.dims[1] as f32) / self.scale),
            )
            .max(Vec2::ZERO)
            .length();
        // A sample whose chart has no triangle within this many rings is charged the
        // gap to the last ring: a lower estimate, which bounds the search's cost.
        let rings = self.dims[0].max(self.dims[1]).min(MAX_RINGS);
        let mut nearest_gap = outside;
        for r in 0..=rings {
            nearest_gap = outside.max((r - 1).max(0) as f32 * cell_side);
            if nearest_gap * self.texel >= best {
                break;
            }
            for y in home[1] - r..=home[1] + r {
                for x in home[0] - r..=home[0] + r {
                    let on_ring = (y - home[1]).abs() == r || (x - home[0]).abs() == r;
                    if !on_ring || x < 0 || y < 0 || x >= self.dims[0] || y >= self.dims[1] {
                        continue;
                    }
                    for &t in self.cell([x, y]) {
                        let tri = self.triangles[t as usize];
                        if self.charts[tri[0] as usize] != chart {
                            continue;
                        }
                        let [a, b, c] = tri.map(|v| Vec2::from(self.uvs[v as usize]));
                        let w = closest_barycentric(uv, a, b, c);
                        let gap = (a * w[0] + b * w[1] + c * w[2]).distance(uv);
                        let slide = self.point(t, w).distance(p)
                            + gap * self.texel
                            + self.errors[t as usize];
                        best = best.min(slide);
                    }
                }
            }
        }
        if best.is_finite() {
            best
        } else {
            nearest_gap * self.texel
        }
    }

    /// The triangles listed in a grid cell.
    fn cell(&self, [x, y]: [i32; 2]) -> &[u32] {
        let i = (y * self.dims[0] + x) as usize;
        &self.items[self.start[i] as usize..self.start[i + 1] as usize]
    }

    /// The point of triangle `t` at barycentric weights `w`.
    fn point(&self, t: u32, w: [f32; 3]) -> Vec3 {
        let [a, b, c] = self.triangles[t as usize].map(|v| self.positions[v as usize]);
        a * w[0] + b * w[1] + c * w[2]
    }
}

/// The barycentric weights of `p` in the UV triangle `a b c` when it lies inside (within
/// [`INSIDE`]), clamped onto the triangle; `None` outside or for a triangle of no UV area.
pub fn inside(p: Vec2, a: Vec2, b: Vec2, c: Vec2) -> Option<[f32; 3]> {
    let (ab, ac, ap) = (b - a, c - a, p - a);
    let det = ab.perp_dot(ac);
    if det.abs() <= f32::MIN_POSITIVE {
        return None;
    }
    let v = ap.perp_dot(ac) / det;
    let w = ab.perp_dot(ap) / det;
    let u = 1.0 - v - w;
    if u < -INSIDE || v < -INSIDE || w < -INSIDE {
        return None;
    }
    let [u, v, w] = [u, v, w].map(|x| x.max(0.0));
    let sum = u + v + w;
    Some([u / sum, v / sum, w / sum])
}

/// The barycentric weights of the point of the UV triangle `a b c` nearest to `p`
/// ([`triangle_region`], which the surface deviation shares). A triangle of no UV area
/// gives its nearest corner or edge point.
pub fn closest_barycentric(p: Vec2, a: Vec2, b: Vec2, c: Vec2) -> [f32; 3] {
    match triangle_region(p, a, b, c) {
        TriangleRegion::A => [1.0, 0.0, 0.0],
        TriangleRegion::B => [0.0, 1.0, 0.0],
        TriangleRegion::C => [0.0, 0.0, 1.0],
        TriangleRegion::Ab(t) => [1.0 - t, t, 0.0],
        TriangleRegion::Ac(t) => [1.0 - t, 0.0, t],
        TriangleRegion::Bc(t) => [0.0, 1.0 - t, t],
        TriangleRegion::Inside { va, vb, vc } => {
            let sum = va + vb + vc;
            if sum.abs() <= f32::MIN_POSITIVE {
                // No area: the nearest corner.
                let d = [a, b, c].map(|q| q.distance_squared(p));
                let i = (0..3).min_by(|&i, &j| d[i].total_cmp(&d[j])).unwrap_or(0);
                let mut w = [0.0; 3];
                w[i] = 1.0;
                return w;
            }
            let (v, w) = (vb / sum, vc / sum);
            [1.0 - v - w, v, w]
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn charts_are_the_pieces_joined_by_shared_vertices() {
        // Two triangles sharing an edge, a third sharing only positions (other ids), a
        // vertex no triangle uses.
        let charts = uv_charts(10, &[5, 1, 2, 2, 1, 3, 4, 6, 7]);
        assert_eq!(charts, vec![0, 1, 1, 1, 4, 1, 4, 4, 8, 9]);
    }

    #[test]
    fn the_nearest_point_of_a_triangle_is_found_in_every_region() {
        let [a, b, c] = [Vec2::ZERO, Vec2::X, Vec2::Y];
        let at = |p: Vec2| {
            let w = closest_barycentric(p, a, b, c);
            a * w[0] + b * w[1] + c * w[2]
        };
        assert_eq!(at(Vec2::new(-1.0, -1.0)), a);
        assert_eq!(at(Vec2::new(2.0, -0.5)), b);
        assert_eq!(at(Vec2::new(-0.5, 2.0)), c);
        assert!(at(Vec2::new(0.5, -1.0)).distance(Vec2::new(0.5, 0.0)) < 1e-6);
        assert!(at(Vec2::new(-1.0, 0.5)).distance(Vec2::new(0.0, 0.5)) < 1e-6);
        assert!(at(Vec2::new(1.0, 1.0)).distance(Vec2::new(0.5, 0.5)) < 1e-6);
        assert!(at(Vec2::new(0.25, 0.25)).distance(Vec2::new(0.25, 0.25)) < 1e-6);
        // No area: the nearest corner or edge point, never NaN.
        let w = closest_barycentric(Vec2::new(0.5, 1.0), a, b, b);
        assert!(w.iter().all(|x| x.is_finite()));
    }

    #[test]
    fn a_warped_map_slides_where_a_linear_one_does_not() {
        // A flat 3 × 3 grid of points, simplified to its two corner triangles: the
        // positions do not move, so only the texture can.
        let positions: Vec<Vec3> = (0..9)
            .map(|i| Vec3::new((i % 3) as f32, (i / 3) as f32, 0.0))
            .collect();
        let source: Vec<u32> = [
            [0, 1, 4],
            [0, 4, 3],
            [1, 2, 5],
            [1, 5, 4],
            [3, 4, 7],
            [3, 7, 6],
            [4, 5, 8],
            [4, 8, 7],
        ]
        .concat();
        let simplified = [0, 2, 8, 0, 8, 6];
        let charts = uv_charts(9, &source);
        assert_eq!(charts, vec![0; 9]);
        let linear: Vec<[f32; 2]> = positions.iter().map(|p| [p.x / 2.0, p.y / 2.0]).collect();
        let texel = texel_size(&positions, &linear, &source);
        assert!((texel - 2.0).abs() < 1e-5, "{texel}");
        let level = UvSurface::new(&positions, &linear, &charts, &source, texel);
        let slide = simplified_uv_slide(&level, &source, &simplified);
        assert!(slide < 1e-5, "a linear map slides {slide}");
        // The centre's texel moved off the centre by a quarter of the map.
        let mut warped = linear.clone();
        warped[4] = [0.75, 0.75];
        let level = UvSurface::new(&positions, &warped, &charts, &source, texel);
        let slide = simplified_uv_slide(&level, &source, &simplified);
        assert!(slide > 0.2, "a warped map slides only {slide}");
        // All UVs zero, as some exporters write: no area, no texture to slide, and no
        // search through the grid for each sample.
        let zero = vec![[0.0f32; 2]; 9];
        assert_eq!(texel_size(&positions, &zero, &source), 0.0);
        let level = UvSurface::new(&positions, &zero, &charts, &source, 0.0);
        assert_eq!(simplified_uv_slide(&level, &source, &simplified), 0.0);
    }
}
