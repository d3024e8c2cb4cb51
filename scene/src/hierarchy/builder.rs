//! Building the culling hierarchy of one mesh at bake time (see [`super`] for its shape
//! and what its nodes bound); loading and drawing only read the stored nodes.

use rayon::prelude::*;

use super::{distance64, meshlet_lod};
use crate::asset::format::{GroupRecord, MeshletRecord, NO_GROUP, NodeRecord, ROOT_PARENT_ERROR};

/// Children per node of a level's bounding-volume tree.
pub const BRANCHING: usize = 8;

/// A mesh's culling hierarchy: the nodes (root first) and the cluster list the leaves
/// take their meshlets from (asset-local meshlet ids, each meshlet once).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Hierarchy {
    /// The node records, in breadth-first order, as the asset stores them.
    pub nodes: Vec<NodeRecord>,
    /// The cluster list, in depth-first order, as the asset stores it.
    pub clusters: Vec<u32>,
}

/// What a subtree bounds.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Bounds {
    bounds: [f32; 4],
    lod_sphere: [f32; 4],
    min_error: f32,
    max_parent_error: f32,
}

/// A node before it is laid out: a leaf has meshlets, an internal node children.
struct Tree {
    b: Bounds,
    children: Vec<Tree>,
    meshlets: Vec<u32>,
    /// Its range of the cluster list, assigned depth-first.
    first_cluster: u32,
    cluster_count: u32,
}

/// The smallest f32 at least `x`.
fn round_up(x: f64) -> f32 {
    let r = x as f32;
    if (r as f64) < x { r.next_up() } else { r }
}

/// A sphere enclosing `spheres` (not empty): centred on their bounding box, its radius
/// rounded up so that [`super::encloses`] holds for each.
fn enclose(spheres: &[[f32; 4]]) -> [f32; 4] {
    let mut lo = [f64::INFINITY; 3];
    let mut hi = [f64::NEG_INFINITY; 3];
    for s in spheres {
        for k in 0..3 {
            lo[k] = lo[k].min(s[k] as f64 - s[3] as f64);
            hi[k] = hi[k].max(s[k] as f64 + s[3] as f64);
        }
    }
    let c = [0, 1, 2].map(|k| ((lo[k] + hi[k]) * 0.5) as f32);
    let centre = [c[0], c[1], c[2], 0.0];
    let radius = spheres
        .iter()
        .map(|s| distance64(centre, *s) + s[3] as f64)
        .fold(0.0f64, f64::max);
    [c[0], c[1], c[2], round_up(radius)]
}

fn leaf(meshlet_ids: Vec<u32>, meshlets: &[MeshletRecord], groups: &[GroupRecord]) -> Tree {
    let mut culling = Vec::with_capacity(meshlet_ids.len());
    let mut lod = Vec::with_capacity(2 * meshlet_ids.len());
    let (mut min_error, mut max_parent_error) = (f32::INFINITY, 0.0f32);
    for &id in &meshlet_ids {
        let m = &meshlets[id as usize];
        culling.push(m.bounds);
        let ((own_sphere, own_error), parent) = meshlet_lod(m, groups);
        lod.push(own_sphere);
        min_error = min_error.min(own_error);
        match parent {
            Some((sphere, error)) => {
                lod.push(sphere);
                max_parent_error = max_parent_error.max(error);
            }
            None => max_parent_error = ROOT_PARENT_ERROR,
        }
    }
    Tree {
        b: Bounds {
            bounds: enclose(&culling),
            lod_sphere: enclose(&lod),
            min_error,
            max_parent_error,
        },
        children: Vec::new(),
        meshlets: meshlet_ids,
        first_cluster: 0,
        cluster_count: 0,
    }
}

fn node(children: Vec<Tree>) -> Tree {
    let culling: Vec<[f32; 4]> = children.iter().map(|c| c.b.bounds).collect();
    let lod: Vec<[f32; 4]> = children.iter().map(|c| c.b.lod_sphere).collect();
    let b = Bounds {
        bounds: enclose(&culling),
        lod_sphere: enclose(&lod),
        min_error: children
            .iter()
            .map(|c| c.b.min_error)
            .fold(f32::INFINITY, f32::min),
        max_parent_error: children
            .iter()
            .map(|c| c.b.max_parent_error)
            .fold(0.0, f32::max),
    };
    Tree {
        b,
        children,
        meshlets: Vec::new(),
        first_cluster: 0,
        cluster_count: 0,
    }
}

/// `items` (not empty) in `parts` runs of about equal size, split recursively at the
/// median of the longest axis of their culling spheres' centres.
fn split(mut items: Vec<Tree>, parts: usize) -> Vec<Vec<Tree>> {
    if parts <= 1 || items.len() <= 1 {
        return vec![items];
    }
    let mut lo = [f32::INFINITY; 3];
    let mut hi = [f32::NEG_INFINITY; 3];
    for t in &items {
        for k in 0..3 {
            lo[k] = lo[k].min(t.b.bounds[k]);
            hi[k] = hi[k].max(t.b.bounds[k]);
        }
    }
    let axis = (0..3)
        .max_by(|&a, &b| (hi[a] - lo[a]).total_cmp(&(hi[b] - lo[b])).then(b.cmp(&a)))
        .unwrap_or(0);
    // Stable: equal centres keep their (deterministic) order.
    items.sort_by(|a, b| a.b.bounds[axis].total_cmp(&b.b.bounds[axis]));
    let left_parts = parts / 2;
    let mid = (items.len() * left_parts)
        .div_ceil(parts)
        .clamp(1, items.len() - 1);
    let right = items.split_off(mid);
    let mut out = split(items, left_parts);
    out.extend(split(right, parts - left_parts));
    out
}

/// A bounding-volume tree over `items` (not empty), up to [`BRANCHING`] children each.
fn spatial(mut items: Vec<Tree>) -> Tree {
    if items.len() == 1 {
        return items.pop().expect("one item");
    }
    if items.len() <= BRANCHING {
        return node(items);
    }
    node(split(items, BRANCHING).into_iter().map(spatial).collect())
}

/// Cluster ranges, depth-first; returns the list.
fn assign_clusters(t: &mut Tree, list: &mut Vec<u32>) {
    t.first_cluster = list.len() as u32;
    if t.children.is_empty() {
        list.extend_from_slice(&t.meshlets);
    } else {
        for c in &mut t.children {
            assign_clusters(c, list);
        }
    }
    t.cluster_count = list.len() as u32 - t.first_cluster;
}

/// Builds the hierarchy of one mesh from its packed records: `children` is the asset's
/// children section, which `groups` index. Deterministic; the levels' trees are built in
/// parallel.
pub fn build(meshlets: &[MeshletRecord], groups: &[GroupRecord], children: &[u32]) -> Hierarchy {
    let roots: Vec<u32> = (0..meshlets.len() as u32)
        .filter(|&i| meshlets[i as usize].parent_group == NO_GROUP)
        .collect();
    let top = groups.iter().map(|g| g.level).max().map_or(0, |l| l + 1);
    let mut by_level: Vec<Vec<u32>> = vec![Vec::new(); top as usize];
    for (i, g) in groups.iter().enumerate() {
        by_level[g.level as usize].push(i as u32);
    }
    // Coarse to fine: the roots, then the levels from the top down.
    let mut links: Vec<Tree> = Vec::new();
    if !roots.is_empty() {
        links.push(leaf(roots, meshlets, groups));
    }
    let levels: Vec<Tree> = by_level
        .into_par_iter()
        .rev()
        .filter(|ids| !ids.is_empty())
        .map(|ids| {
            let leaves: Vec<Tree> = ids
                .iter()
                .map(|&g| {
                    let g = &groups[g as usize];
                    let range = g.first_child as usize..(g.first_child + g.child_count) as usize;
                    leaf(children[range].to_vec(), meshlets, groups)
                })
                .collect();
            spatial(leaves)
        })
        .collect();
    links.extend(levels);
    let Some(mut root) = links.pop() else {
        return Hierarchy::default();
    };
    while let Some(coarser) = links.pop() {
        root = node(vec![coarser, root]);
    }
    let mut clusters = Vec::with_capacity(meshlets.len());
    assign_clusters(&mut root, &mut clusters);
    // Breadth-first: each node's children appended together, after it.
    let mut order: Vec<&Tree> = vec![&root];
    let mut nodes = Vec::new();
    let mut i = 0;
    while i < order.len() {
        let t = order[i];
        let first_child = if t.children.is_empty() {
            0
        } else {
            order.len() as u32
        };
        order.extend(t.children.iter());
        nodes.push(NodeRecord {
            bounds: t.b.bounds,
            lod_sphere: t.b.lod_sphere,
            min_error: t.b.min_error,
            max_parent_error: t.b.max_parent_error,
            first_child,
            child_count: t.children.len() as u32,
            first_cluster: t.first_cluster,
            cluster_count: t.cluster_count,
            reserved: [0; 2],
        });
        i += 1;
    }
    Hierarchy { nodes, clusters }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::hierarchy::encloses;

    #[test]
    fn enclosing_spheres_hold_what_they_enclose_exactly() {
        let spheres = [
            [1.0e3, -2.5, 0.1, 0.3],
            [1.0e3 + 1.0, -2.0, 0.4, 1e-7],
            [999.9, -3.0, 0.2, 0.0],
        ];
        let s = enclose(&spheres);
        for inner in spheres {
            assert!(encloses(s, inner), "{s:?} {inner:?}");
        }
        // One ulp smaller no longer holds them all: the radius is tight.
        let smaller = [s[0], s[1], s[2], s[3].next_down()];
        assert!(spheres.iter().any(|&inner| !encloses(smaller, inner)));
    }

    #[test]
    fn splits_cover_every_item_in_nonempty_runs() {
        for n in [2usize, 9, 17, 64, 100] {
            let items: Vec<Tree> = (0..n)
                .map(|i| {
                    let b = Bounds {
                        bounds: [(i * 7 % 13) as f32, (i % 5) as f32, 0.0, 1.0],
                        lod_sphere: [0.0, 0.0, 0.0, 1.0],
                        min_error: 0.0,
                        max_parent_error: 1.0,
                    };
                    Tree {
                        b,
                        children: Vec::new(),
                        meshlets: vec![i as u32],
                        first_cluster: 0,
                        cluster_count: 0,
                    }
                })
                .collect();
            let parts = split(items, BRANCHING);
            assert_eq!(parts.len(), BRANCHING.min(n));
            assert!(parts.iter().all(|p| !p.is_empty()));
            let mut all: Vec<u32> = parts.iter().flatten().map(|t| t.meshlets[0]).collect();
            all.sort();
            assert_eq!(all, (0..n as u32).collect::<Vec<_>>());
        }
    }
}
