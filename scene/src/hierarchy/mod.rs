//! The culling hierarchy: per mesh, a tree over the DAG's groups, built at bake time and
//! stored in the asset, so that culling walks what is on screen instead of testing
//! every meshlet of every level.
//!
//! # Leaves
//!
//! A leaf holds the meshlets simplified in one group (the group's children), and one
//! more leaf holds the roots. The meshlets of a leaf share their parent: the LOD cut
//! keeps a meshlet when its own error is imperceptible and its parent's is not, so a
//! leaf whose group is imperceptible holds no meshlet of the cut, and that test is the
//! very one `cull_lod` makes per meshlet, once for all of them.
//!
//! # Shape
//!
//! Errors grow with the level, and a view's cut lies in a band of levels that depends on
//! the distance. So the tree is ordered first by error, then by place: under the root a
//! chain from coarse to fine (`root = {roots, c1}`, `c1 = {top level, c2}`, …, the last
//! link the finest level), and under each link the level's groups in a bounding-volume
//! tree of up to [`BRANCHING`] children per node, split at the median of the longest
//! axis of their centres. A distant instance stops near the top of the chain (every
//! finer link is imperceptible); a near one walks down to its levels, and within a level
//! only where the frustum and the LOD tests lead.
//!
//! # What a node bounds, and why its tests are conservative
//!
//! Every node bounds all meshlets below it: `bounds` encloses their culling spheres,
//! `lod_sphere` their own and parent LOD spheres, `min_error` is the smallest own error
//! and `max_parent_error` the largest parent error (infinite with a root below). The
//! projected error `e · s / max(d − r · s, near)` grows with the error and shrinks with
//! the distance `d − r · s` from the camera to the sphere. From any viewpoint the
//! nearest point of `lod_sphere` is no farther than any enclosed sphere's nearest point,
//! and its farthest point no nearer than their centres. So:
//! - outside the frustum, `bounds` holds no meshlet in it;
//! - "too fine": `max_parent_error` projected from the nearest point of `lod_sphere`
//!   imperceptible ⇒ every parent below is imperceptible ⇒ no meshlet below is in the cut;
//! - "too coarse": `min_error` projected from the farthest point perceptible ⇒ every own
//!   error below is perceptible ⇒ none is in the cut.
//!
//! Spheres nest exactly: a radius is rounded up from the f64 distance plus the enclosed
//! radius, and loading checks the same f64 inequality, so a stored sphere really holds
//! what it claims to. What remains is the rounding of the world transform and of the
//! projection on the GPU; the traversal absorbs it with a slack relative to the
//! magnitudes involved (see `meshlight-pass-fill-clusters`'s `hierarchy` module), so a
//! skipped node never holds a meshlet of the cut.
//!
//! # Layout
//!
//! Nodes in breadth-first order (the root first; a node's children contiguous and after
//! it, so following children always moves forward and cannot cycle), and the cluster
//! list in depth-first order, so that any subtree's meshlets are one range: a traversal
//! that runs out of queue space emits a whole subtree at once, conservatively.

use crate::asset::format::{GroupRecord, MeshletRecord, NO_GROUP, NodeRecord};

#[cfg(feature = "build")]
mod builder;
#[cfg(feature = "build")]
pub use builder::{BRANCHING, Hierarchy, build};

/// Most children a stored node may have (the loader refuses more).
pub const MAX_CHILDREN: u32 = 16;

/// Levels of a tree the GPU walk reaches: the root is level 0, and `fill_clusters`'
/// walk tests two levels a round for at most 256 rounds, so a node at this level or
/// deeper is never tested and what lies below it is never drawn. The loader refuses
/// such a tree rather than draw a mesh with parts silently missing; a baked tree
/// branches eight ways and stays far shallower.
pub const MAX_DEPTH: u32 = 512;

/// A LOD sphere (mesh space: centre, radius) and the error measured inside it, as
/// [`crate::MeshletAsset::lod`] returns them.
pub type Lod = ([f32; 4], f32);

/// A meshlet's own LOD sphere and error, and its parent's (`None` for a root).
pub fn meshlet_lod(m: &MeshletRecord, groups: &[GroupRecord]) -> (Lod, Option<Lod>) {
    let own = match groups.get(m.source_group as usize) {
        Some(g) if m.source_group != NO_GROUP => (g.lod_sphere, g.error),
        _ => (m.bounds, 0.0),
    };
    let parent = match groups.get(m.parent_group as usize) {
        Some(g) if m.parent_group != NO_GROUP => Some((g.lod_sphere, g.error)),
        _ => None,
    };
    (own, parent)
}

fn distance64(a: [f32; 4], b: [f32; 4]) -> f64 {
    (0..3)
        .map(|k| {
            let d = a[k] as f64 - b[k] as f64;
            d * d
        })
        .sum::<f64>()
        .sqrt()
}

/// Whether sphere `outer` (centre xyz, radius w) encloses `inner`, in f64 on the stored
/// values: the inequality the builder makes hold and the loader checks.
pub fn encloses(outer: [f32; 4], inner: [f32; 4]) -> bool {
    distance64(outer, inner) + inner[3] as f64 <= outer[3] as f64
}

/// Depth of the tree (1 for a root alone), for summaries.
pub fn depth(nodes: &[NodeRecord]) -> u32 {
    let mut depth = vec![1u32; nodes.len()];
    let mut deepest = u32::from(!nodes.is_empty());
    for i in 0..nodes.len() {
        let d = depth[i] + 1;
        for c in nodes[i].children().filter(|&c| c < nodes.len()) {
            depth[c] = d;
            deepest = deepest.max(d);
        }
    }
    deepest
}

/// Leaves of the tree.
pub fn leaf_count(nodes: &[NodeRecord]) -> usize {
    nodes.iter().filter(|n| n.is_leaf()).count()
}
