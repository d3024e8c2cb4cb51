//! The check that LOD cuts have no cracks, on a packed asset: every group's simplified
//! meshlets must meet the neighbouring groups exactly where its children did.
//!
//! Why this is enough: a cut switches between a group's children and its outputs as a
//! whole. Neighbouring groups of one build iteration share only vertices that were locked,
//! so if each group's outputs use every edge it shares with a neighbour the same number
//! of times in each direction as its children did, any mix of refined and simplified
//! groups closes up. Edges that no neighbour uses (the mesh's own open boundary, folds and
//! seams inside the group) may change. Edges are compared by their grid coordinates, as
//! the GPU decodes them.

use rayon::prelude::*;
use rustc_hash::{FxHashMap, FxHashSet};

use crate::asset::MeshletAsset;

type Vertex = [u32; 3];
type Edge = (Vertex, Vertex);

/// One line per group whose outputs do not meet its neighbours like its children.
pub fn crack_problems(asset: &MeshletAsset) -> Vec<String> {
    let groups = asset.groups();
    let meshlets = asset.meshlets();
    let mut outputs: Vec<Vec<u32>> = vec![Vec::new(); groups.len()];
    for (i, m) in meshlets.iter().enumerate() {
        if let Some(o) = outputs.get_mut(m.source_group as usize) {
            o.push(i as u32);
        }
    }
    let mut by_level: FxHashMap<u32, Vec<usize>> = FxHashMap::default();
    for (g, group) in groups.iter().enumerate() {
        by_level.entry(group.level).or_default().push(g);
    }
    let mut levels: Vec<u32> = by_level.keys().copied().collect();
    levels.sort_unstable();
    let mut problems = Vec::new();
    for level in levels {
        let at_level = &by_level[&level];
        // Groups are independent once the level's shared edges are known: in parallel.
        let before: Vec<FxHashMap<Edge, i32>> = at_level
            .par_iter()
            .map(|&g| directed_uses(asset, asset.group_children(&groups[g])))
            .collect();
        // Which groups of this iteration use each edge: shared ones are the borders.
        let mut users: FxHashMap<Edge, (usize, bool)> = FxHashMap::default();
        for (k, uses) in before.iter().enumerate() {
            for e in uses.keys() {
                let u = users.entry(*e).or_insert((k, false));
                if u.0 != k {
                    u.1 = true;
                }
            }
        }
        let cracked: Vec<(usize, usize)> = at_level
            .par_iter()
            .enumerate()
            .map(|(k, &g)| {
                let after = directed_uses(asset, &outputs[g]);
                let keys: FxHashSet<&Edge> = before[k].keys().chain(after.keys()).collect();
                let cracked = keys
                    .into_iter()
                    .filter(|e| users.get(*e).is_some_and(|u| u.1))
                    .filter(|e| net(&before[k], e) != net(&after, e))
                    .count();
                (g, cracked)
            })
            .collect();
        for (g, cracked) in cracked {
            if cracked > 0 {
                problems.push(format!(
                    "group {g}: its simplified meshlets use {cracked} edges shared with \
                     neighbouring groups differently from its children: a crack in some LOD cut"
                ));
            }
        }
    }
    problems
}

fn net(uses: &FxHashMap<Edge, i32>, e: &Edge) -> i32 {
    uses.get(e).copied().unwrap_or(0)
}

/// Net directed uses (+1 one way, -1 the other) of every edge of `meshlets`' triangles,
/// keyed by its two grid points in order; an edge used both ways nets to zero but is
/// kept, so that "used" and "net" are both known.
fn directed_uses(asset: &MeshletAsset, meshlets: &[u32]) -> FxHashMap<Edge, i32> {
    let mut net: FxHashMap<Edge, i32> = FxHashMap::default();
    for &m in meshlets {
        let (grid, triangles) = asset.decode_topology(m as usize);
        for t in &triangles {
            for k in 0..3 {
                let (a, b) = (grid[t[k] as usize], grid[t[(k + 1) % 3] as usize]);
                if a == b {
                    continue;
                }
                let (key, s) = if a < b { ((a, b), 1) } else { ((b, a), -1) };
                *net.entry(key).or_default() += s;
            }
        }
    }
    net
}
