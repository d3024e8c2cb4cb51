//! Deterministic topological order, and the full path of a cycle when there is one.

use crate::compile::versions::Edge;
use crate::error::GraphError;
use petgraph::Direction;
use petgraph::graph::{DiGraph, NodeIndex};
use std::cmp::Reverse;
use std::collections::BinaryHeap;

/// The dependency DAG over pass indices.
pub fn build_dag(pass_count: usize, edges: &[Edge]) -> DiGraph<usize, usize> {
    let mut g = DiGraph::with_capacity(pass_count, edges.len());
    for p in 0..pass_count {
        g.add_node(p);
    }
    for (i, e) in edges.iter().enumerate() {
        g.add_edge(NodeIndex::new(e.from), NodeIndex::new(e.to), i);
    }
    g
}

/// Kahn's algorithm with the lowest declaration index first, so equal inputs give equal
/// orders and independent passes keep the order the user wrote.
pub fn topological_order(
    dag: &DiGraph<usize, usize>,
    names: &[String],
) -> Result<Vec<usize>, GraphError> {
    let n = dag.node_count();
    let mut indegree: Vec<usize> = (0..n)
        .map(|i| {
            dag.neighbors_directed(NodeIndex::new(i), Direction::Incoming)
                .count()
        })
        .collect();
    let mut ready: BinaryHeap<Reverse<usize>> =
        (0..n).filter(|&i| indegree[i] == 0).map(Reverse).collect();
    let mut order = Vec::with_capacity(n);
    while let Some(Reverse(p)) = ready.pop() {
        order.push(p);
        for next in dag.neighbors_directed(NodeIndex::new(p), Direction::Outgoing) {
            let d = &mut indegree[next.index()];
            *d -= 1;
            if *d == 0 {
                ready.push(Reverse(next.index()));
            }
        }
    }
    if order.len() == n {
        return Ok(order);
    }
    let remaining: Vec<bool> = indegree.iter().map(|&d| d > 0).collect();
    Err(GraphError::Cycle {
        path: find_cycle(dag, &remaining)
            .into_iter()
            .map(|p| names[p].clone())
            .collect(),
    })
}

/// `order` with each readback pass moved as late as its edges allow: just before the
/// first pass that must follow it (the next writer of what it copies), or to the end.
///
/// Why: a copy cannot be recorded inside a compute pass, so a readback between two
/// compute passes splits the frame's one compute pass in two, and each split costs a
/// few microseconds on the GPU. A readback's copy has no consumer in the frame, so
/// nothing is gained by running it early; sunk to the end, the frame's readbacks follow
/// one another after the last compute work. The order stays topological: a readback
/// only moves past passes that do not depend on it. Readbacks that meet at one place
/// keep their order.
pub fn sink_readbacks(
    dag: &DiGraph<usize, usize>,
    order: Vec<usize>,
    is_readback: &[bool],
) -> Vec<usize> {
    let position: Vec<usize> = {
        let mut at = vec![usize::MAX; is_readback.len()];
        for (i, &p) in order.iter().enumerate() {
            at[p] = i;
        }
        at
    };
    // Each readback's place: the position of its first successor in the order, so
    // that it is recorded right before that pass (its place, then its old position,
    // breaks ties).
    let mut keyed: Vec<(usize, usize, usize)> = order
        .iter()
        .enumerate()
        .map(|(i, &p)| {
            if !is_readback[p] {
                return (i, 1, p);
            }
            let first_after = dag
                .neighbors_directed(NodeIndex::new(p), Direction::Outgoing)
                .map(|q| position[q.index()])
                .filter(|&at| at != usize::MAX)
                .min()
                .unwrap_or(order.len());
            (first_after, 0, i)
        })
        .collect();
    keyed.sort_unstable();
    keyed
        .into_iter()
        .map(|(_, kind, x)| if kind == 0 { order[x] } else { x })
        .collect()
}

/// Every node left after Kahn's algorithm lies on or behind a cycle; walking predecessors
/// that are also left must revisit a node, and the walk between the visits is the cycle.
fn find_cycle(dag: &DiGraph<usize, usize>, remaining: &[bool]) -> Vec<usize> {
    let start = remaining.iter().position(|&r| r).unwrap_or(0);
    let mut seen_at = vec![usize::MAX; remaining.len()];
    let mut walk = Vec::new();
    let mut node = start;
    while seen_at[node] == usize::MAX {
        seen_at[node] = walk.len();
        walk.push(node);
        let mut preds: Vec<usize> = dag
            .neighbors_directed(NodeIndex::new(node), Direction::Incoming)
            .map(|n| n.index())
            .filter(|&i| remaining[i])
            .collect();
        preds.sort_unstable();
        match preds.first() {
            Some(&p) => node = p,
            None => return walk,
        }
    }
    let mut cycle: Vec<usize> = walk[seen_at[node]..].to_vec();
    cycle.reverse();
    // Start at the lowest index so the message is stable.
    let lowest = cycle
        .iter()
        .enumerate()
        .min_by_key(|(_, p)| **p)
        .map(|(i, _)| i)
        .unwrap_or(0);
    cycle.rotate_left(lowest);
    cycle
}
