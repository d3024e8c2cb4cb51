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
