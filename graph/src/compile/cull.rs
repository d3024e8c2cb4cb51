//! Culling: a pass runs only if what it writes reaches something visible outside the frame
//! (an imported, history or exported resource) or it declares a side effect.

use crate::compile::versions::{Edge, EdgeKind};
use crate::node::PassNode;
use crate::resource::ResourceInfo;

/// Returns, per pass, whether it is kept.
pub fn live_passes(
    resources: &[ResourceInfo],
    passes: &[PassNode],
    side_effects: &[bool],
    edges: &[Edge],
) -> Vec<bool> {
    let mut live = vec![false; passes.len()];
    let mut stack: Vec<usize> = Vec::new();
    for (p, node) in passes.iter().enumerate() {
        let visible = node
            .bound_slots()
            .any(|(s, h)| s.writes() && resources[h.id.index()].is_visible_outside());
        if visible || side_effects[p] {
            live[p] = true;
            stack.push(p);
        }
    }
    // Data flows only along read-after-write edges; ordering edges pull in nothing.
    while let Some(p) = stack.pop() {
        for e in edges
            .iter()
            .filter(|e| e.to == p && e.kind == EdgeKind::ReadAfterWrite)
        {
            if !live[e.from] {
                live[e.from] = true;
                stack.push(e.from);
            }
        }
    }
    live
}
