//! LOD 0's open edges as baked, and the load check that LOD 0 still has them.
//!
//! Why: the GPU joins LOD 0's meshlets by their grid points, so a meshlet whose border
//! vertices moved (a damaged `grid_min`, a flipped payload bit) opens a crack at full
//! detail that no other check sees: the crack check ([`crate::watertight`]) compares a
//! group's outputs with its children, and LOD 0 is nobody's output. Whether a mesh is
//! meant to be open (a scan's holes, a teapot's rim) is known only to the bake, so the
//! bake records LOD 0's boundary chain ([`OpenEdgeRecord`]: every edge whose net
//! directed use is not zero) and a load compares it with what the meshlets decode to.
//!
//! How the load check stays cheap: the boundary of LOD 0 is the sum of its meshlets'
//! boundaries, whose fingerprints the one decoding pass over the meshlets already takes
//! ([`crate::asset::scan`]), so the check adds only the fingerprint of the recorded
//! edges, a few per thousand triangles on a scanned mesh and none on a closed one.
//! Only when they differ are LOD 0's edges hashed, to say where.

use rayon::prelude::*;
use rustc_hash::FxHashMap;

use crate::asset::MeshletAsset;
use crate::asset::format::OpenEdgeRecord;
use crate::asset::scan::MeshletScan;
use crate::chain_fingerprint::{ChainKeys, edge};

type Vertex = [u32; 3];

/// The boundary chain of the triangles of `meshlets` meshlets, `triangles(i)` giving
/// meshlet `i`'s as grid points, in the recorded form: one record per edge with a net
/// use, oriented so that it is positive, sorted by [`OpenEdgeRecord::key`]. Each
/// meshlet's own shared edges cancel before anything is gathered across meshlets, so
/// only their borders meet in the final sort. Sorted runs rather than hash tables: a
/// meshlet's few hundred edges sort faster than they hash.
pub fn boundary_chain<F, I>(meshlets: usize, triangles: F) -> Vec<OpenEdgeRecord>
where
    F: Fn(usize) -> I + Sync,
    I: Iterator<Item = [Vertex; 3]>,
{
    let mut borders: Vec<((Vertex, Vertex), i32)> = (0..meshlets)
        .into_par_iter()
        .flat_map_iter(|i| {
            let mut edges: Vec<((Vertex, Vertex), i32)> = Vec::new();
            for t in triangles(i) {
                for k in 0..3 {
                    let (a, b) = (t[k], t[(k + 1) % 3]);
                    if a != b {
                        edges.push(if a < b { ((a, b), 1) } else { ((b, a), -1) });
                    }
                }
            }
            net_runs(edges)
        })
        .collect();
    borders.par_sort_unstable_by_key(|&(e, _)| e);
    net_runs(borders)
        .into_iter()
        .map(|((a, b), n)| {
            let (from, to) = if n > 0 { (a, b) } else { (b, a) };
            OpenEdgeRecord {
                from,
                to,
                uses: n.unsigned_abs(),
            }
        })
        .collect()
}

/// The net use of each edge of `edges` (keyed by its points in ascending order, + from
/// the first to the second), zeros left out, in ascending order of the key.
fn net_runs(mut edges: Vec<((Vertex, Vertex), i32)>) -> Vec<((Vertex, Vertex), i32)> {
    edges.sort_unstable_by_key(|&(e, _)| e);
    edges
        .chunk_by(|x, y| x.0 == y.0)
        .map(|run| (run[0].0, run.iter().map(|&(_, n)| n).sum::<i32>()))
        .filter(|&(_, n)| n != 0)
        .collect()
}

/// LOD 0's boundary chain as the asset's meshlets decode it (grid points, corners as
/// the GPU reads them).
pub fn decoded_lod0_chain(asset: &MeshletAsset) -> Vec<OpenEdgeRecord> {
    let lod0: Vec<usize> = (0..asset.meshlets().len())
        .filter(|&i| asset.meshlets()[i].level() == 0)
        .collect();
    boundary_chain(lod0.len(), |i| {
        let (grid, triangles) = asset.decode_topology(lod0[i]);
        let last = grid.len().saturating_sub(1);
        triangles
            .into_iter()
            .map(move |t| t.map(|k| grid[(k as usize).min(last)]))
    })
}

/// The fingerprint of a recorded chain under `keys`: what the LOD-0 meshlets'
/// boundaries sum to when they still have it.
pub fn fingerprint(records: &[OpenEdgeRecord], keys: &ChainKeys) -> u64 {
    records.iter().fold(0u64, |sum, r| {
        let value = edge(keys.point(r.from), keys.point(r.to));
        sum.wrapping_add(value.wrapping_mul(u64::from(r.uses)))
    })
}

/// A problem line when LOD 0's meshlets, as scanned with `keys`, no longer have the
/// open edges the bake recorded; `None` when they do.
pub fn lod0_problem(
    asset: &MeshletAsset,
    scans: &[MeshletScan],
    keys: &ChainKeys,
) -> Option<String> {
    let recorded = asset.open_edges();
    let decoded = asset
        .meshlets()
        .iter()
        .zip(scans)
        .filter(|(m, _)| m.level() == 0)
        .fold(0u64, |sum, (_, s)| sum.wrapping_add(s.boundary));
    if decoded == fingerprint(recorded, keys) {
        return None;
    }
    // Where: the exact chains, compared edge by edge.
    let now = decoded_lod0_chain(asset);
    let key_uses = |r: &OpenEdgeRecord| {
        let (k, u) = (r.key(), r.uses as i64);
        (k, if r.from == k.0 { u } else { -u })
    };
    let mut diff: FxHashMap<(Vertex, Vertex), i64> = FxHashMap::default();
    for r in &now {
        let (k, u) = key_uses(r);
        *diff.entry(k).or_default() += u;
    }
    for r in recorded {
        let (k, u) = key_uses(r);
        *diff.entry(k).or_default() -= u;
    }
    let mut differ: Vec<(Vertex, Vertex)> = diff
        .into_iter()
        .filter(|&(_, n)| n != 0)
        .map(|(k, _)| k)
        .collect();
    differ.sort_unstable();
    let Some(&(a, b)) = differ.first() else {
        // Equal chains whose fingerprints differ cannot happen; say so rather than pass.
        return Some(
            "LOD 0's open edges match the recorded ones edge by edge but not by fingerprint \
             (an internal error; please report)"
                .to_owned(),
        );
    };
    let meshlet = (0..asset.meshlets().len())
        .filter(|&i| asset.meshlets()[i].level() == 0)
        .find(|&i| {
            let grid = asset.decode_grid(i);
            grid.contains(&a) && grid.contains(&b)
        });
    let at = match meshlet {
        Some(m) => format!(", e.g. grid points {a:?}–{b:?} of LOD-0 meshlet {m}"),
        None => format!(", e.g. grid points {a:?}–{b:?}"),
    };
    Some(format!(
        "LOD 0 is open along {} edges where the bake recorded {} open edges ({} differ{at}): \
         its meshlets no longer meet where they were baked to (a damaged grid origin or \
         payload); bake the source again",
        now.len(),
        recorded.len(),
        differ.len()
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn chain_of(meshlets: &[Vec<[Vertex; 3]>]) -> Vec<OpenEdgeRecord> {
        boundary_chain(meshlets.len(), |i| meshlets[i].iter().copied())
    }

    fn tri(a: u32, b: u32, c: u32) -> [Vertex; 3] {
        [[a, 0, 0], [b, 0, 0], [c, 0, 0]]
    }

    #[test]
    fn a_closed_surface_has_no_open_edges_and_an_open_one_its_rim() {
        // A tetrahedron split over two meshlets: every edge cancels across them.
        let closed = [
            vec![tri(0, 1, 2), tri(0, 3, 1)],
            vec![tri(0, 2, 3), tri(1, 3, 2)],
        ];
        assert!(chain_of(&closed).is_empty());
        // Without its last face (1, 3, 2): that face's three edges, reversed.
        let open = [vec![tri(0, 1, 2), tri(0, 3, 1)], vec![tri(0, 2, 3)]];
        let chain = chain_of(&open);
        let edges: Vec<(u32, u32, u32)> =
            chain.iter().map(|r| (r.from[0], r.to[0], r.uses)).collect();
        assert_eq!(edges, [(1, 2, 1), (3, 1, 1), (2, 3, 1)]);
        let keys = ChainKeys::fixed(7);
        let faces = fingerprint(&chain, &keys);
        let decoded = [tri(0, 1, 2), tri(0, 3, 1), tri(0, 2, 3)]
            .iter()
            .fold(0u64, |s, t| {
                let p = t.map(|v| keys.point(v));
                s.wrapping_add(crate::chain_fingerprint::triangle(p[0], p[1], p[2]))
            });
        assert_eq!(faces, decoded);
    }

    #[test]
    fn a_doubled_edge_is_recorded_with_its_count() {
        // Two fans on the same rim edge 0→1: the edge is used twice the same way.
        let fans = [vec![tri(0, 1, 2)], vec![tri(0, 1, 3)]];
        let chain = chain_of(&fans);
        let doubled = chain.iter().find(|r| r.key() == ([0, 0, 0], [1, 0, 0]));
        assert_eq!(doubled.map(|r| (r.from[0], r.uses)), Some((0, 2)));
    }
}
