//! Geometry of LOD cuts: watertight at every error threshold, and each level within its
//! stored error of the full-detail surface.

mod common;

use std::collections::HashMap;

use glam::Vec3;
use meshlight_scene::deviation::closest_on_triangle;
use meshlight_scene::{BuildOptions, Built, build_asset, load::load_mesh, procedural_mesh};

fn build(mesh: &meshlight_scene::Mesh) -> Built {
    build_asset(mesh, &BuildOptions::default(), &mut |_| {}).unwrap()
}

/// Thresholds between every pair of consecutive distinct errors, plus both ends, so
/// that every distinct cut of the DAG is visited.
fn thresholds(built: &Built) -> Vec<f32> {
    let mut errors: Vec<f32> = built
        .asset
        .meshlets()
        .iter()
        .map(|m| built.asset.lod(m).1)
        .collect();
    errors.sort_by(f32::total_cmp);
    errors.dedup();
    let mut t: Vec<f32> = errors.windows(2).map(|w| (w[0] + w[1]) * 0.5).collect();
    t.push(0.0);
    t.push(errors.last().copied().unwrap_or(0.0) * 2.0 + 1.0);
    t
}

#[test]
fn every_cut_of_the_closed_procedural_mesh_is_watertight() {
    let built = build(&procedural_mesh(48));
    let asset = &built.asset;
    let decoded: Vec<_> = (0..asset.meshlets().len())
        .map(|i| asset.decode_meshlet(i))
        .collect();
    let cuts = thresholds(&built);
    assert!(cuts.len() > 10);
    let mut levels_seen = std::collections::BTreeSet::new();
    let mut worst_folds = 0;
    for &t in &cuts {
        let mut folds = 0usize;
        let mut edges: HashMap<([u32; 3], [u32; 3]), i32> = HashMap::new();
        let mut triangles = 0;
        for (m, d) in asset.meshlets().iter().zip(&decoded) {
            // The runtime rule: own error acceptable, parent's not.
            if !(asset.lod(m).1 <= t && t < asset.parent_lod(m).1) {
                continue;
            }
            levels_seen.insert(m.level());
            for tri in &d.triangles {
                triangles += 1;
                for k in 0..3 {
                    let a = d.grid[tri[k] as usize];
                    let b = d.grid[tri[(k + 1) % 3] as usize];
                    assert_ne!(a, b, "a triangle collapsed to an edge after quantisation");
                    // Directed: +1 one way, -1 the other, so a closed, consistently
                    // wound surface sums to zero and each undirected edge is seen twice.
                    let (key, s) = if a < b { ((a, b), 1) } else { ((b, a), -1) };
                    *edges.entry(key).or_default() += s * 16 + 1;
                }
            }
        }
        assert!(triangles > 0, "the cut at {t} is empty");
        for (edge, v) in &edges {
            // Each use adds 16 in one direction or -16 in the other, plus 1: a crack
            // leaves an edge unbalanced. Two uses (16 - 16 + 2 = 2) is a manifold edge;
            // four or more balanced uses is a fold, where simplification closed the
            // surface onto itself (allowed in small numbers, see FOLDS_PER_64_TRIANGLES).
            let uses = v.rem_euclid(16);
            assert!(
                *v == uses && uses >= 2 && uses % 2 == 0,
                "cut at error {t}: edge {edge:?} is a crack (code {v})"
            );
            folds += (uses > 2) as usize;
        }
        worst_folds = worst_folds.max(folds * 1000 / edges.len());
    }
    println!("most fold edges in one cut: {worst_folds} per thousand edges");
    assert!(
        worst_folds <= 10,
        "{worst_folds} per thousand edges of a cut are folds"
    );
    assert!(
        levels_seen.len() as u32 == asset.header().level_count,
        "the cuts visited every level"
    );
}

/// Uniform grid over the LOD-0 triangles for "is any triangle within r of p".
struct Surface<'a> {
    positions: &'a [Vec3],
    triangles: Vec<[u32; 3]>,
    cells: HashMap<[i32; 3], Vec<u32>>,
    cell: f32,
}

impl<'a> Surface<'a> {
    fn new(positions: &'a [Vec3], indices: &[u32], cell: f32) -> Self {
        let triangles: Vec<[u32; 3]> = indices
            .chunks_exact(3)
            .map(|t| [t[0], t[1], t[2]])
            .collect();
        let mut cells: HashMap<[i32; 3], Vec<u32>> = HashMap::new();
        for (i, t) in triangles.iter().enumerate() {
            let [a, b, c] = t.map(|v| positions[v as usize]);
            let (lo, hi) = (
                (a.min(b).min(c) / cell).floor(),
                (a.max(b).max(c) / cell).floor(),
            );
            for x in lo.x as i32..=hi.x as i32 {
                for y in lo.y as i32..=hi.y as i32 {
                    for z in lo.z as i32..=hi.z as i32 {
                        cells.entry([x, y, z]).or_default().push(i as u32);
                    }
                }
            }
        }
        Self {
            positions,
            triangles,
            cells,
            cell,
        }
    }

    /// Distance from p to the surface, searched in growing shells and cut off once it
    /// exceeds `limit` (then returns the best found, which is > limit, or infinity).
    fn distance(&self, p: Vec3, limit: f32) -> f32 {
        let c = (p / self.cell).floor();
        let c = [c.x as i32, c.y as i32, c.z as i32];
        let mut best = f32::INFINITY;
        let max_ring = (limit / self.cell).ceil() as i32 + 1;
        for ring in 0..=max_ring {
            // Everything in shell `ring` is at least (ring - 1) cells away.
            if best <= (ring - 1).max(0) as f32 * self.cell {
                break;
            }
            for x in -ring..=ring {
                for y in -ring..=ring {
                    for z in -ring..=ring {
                        if x.abs().max(y.abs()).max(z.abs()) != ring {
                            continue;
                        }
                        let Some(list) = self.cells.get(&[c[0] + x, c[1] + y, c[2] + z]) else {
                            continue;
                        };
                        for &t in list {
                            let [a, b, cc] =
                                self.triangles[t as usize].map(|v| self.positions[v as usize]);
                            best = best.min(closest_on_triangle(p, a, b, cc).distance(p));
                        }
                    }
                }
            }
        }
        best
    }
}

/// The stored error bounds the distance exactly (no allowance): the builder measures
/// each group's deviation from its children at these same sample points and adds the
/// children's errors. The only slack is for float rounding of the distance arithmetic
/// and of that sum, relative to the mesh's extent (see [`ROUNDING`]).
const QUALITY_SLACK: f32 = 1.0;
/// Float rounding allowance, as a share of the mesh's largest extent.
const ROUNDING: f32 = 1e-6;

/// For every simplified meshlet, points sampled on its triangles (corners, edge
/// midpoints, centroid) lie within its stored LOD error (with [`QUALITY_SLACK`]) of the
/// LOD-0 surface. Returns the worst ratio of distance to stored error.
fn check_lod_quality(name: &str, built: &Built) -> f32 {
    let mesh = &built.mesh;
    let (min, max) = mesh.bounds();
    let avg_edge = ((max - min).length_squared() / mesh.triangle_count() as f32).sqrt();
    let surface = Surface::new(&mesh.positions, &mesh.indices, avg_edge * 2.0);
    let mut worst = vec![0.0f32; built.dag.level_count as usize];
    for cluster in built.dag.clusters.iter().filter(|c| c.level > 0) {
        let bound = cluster.lod.error;
        for t in cluster.indices.chunks_exact(3) {
            let [a, b, c] = [t[0], t[1], t[2]].map(|v| mesh.positions[v as usize]);
            for p in [
                a,
                b,
                c,
                (a + b) * 0.5,
                (b + c) * 0.5,
                (c + a) * 0.5,
                (a + b + c) / 3.0,
            ] {
                let d = surface.distance(p, bound);
                let ratio = if bound > 0.0 {
                    d / bound
                } else if d <= 1e-6 {
                    0.0
                } else {
                    f32::INFINITY
                };
                let w = &mut worst[cluster.level as usize];
                *w = w.max(ratio);
                assert!(
                    d <= QUALITY_SLACK * bound + ROUNDING * (max - min).max_element(),
                    "{name}: level {} point {p} is {d} from LOD 0, stored error {bound}",
                    cluster.level
                );
            }
        }
    }
    println!("{name}: worst distance / stored error per level: {worst:.3?}");
    worst.into_iter().fold(0.0, f32::max)
}

#[test]
fn simplified_levels_stay_within_their_stored_error() {
    check_lod_quality("procedural", &build(&procedural_mesh(32)));
    // Faceted: every group goes through the welded mode, whose error is measured too.
    check_lod_quality("faceted", &build(&common::faceted(&procedural_mesh(24))));
    {
        let dir = common::shared_meshes();
        for name in common::SHARED_MESHES {
            check_lod_quality(name, &build(&load_mesh(&dir.join(name)).unwrap()));
        }
    }
}
