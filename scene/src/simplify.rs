//! Simplifying one group of clusters to about half its triangles without moving its
//! border, so that neighbouring groups still meet exactly at every level.

use glam::Vec3;
use meshopt::{SimplifyOptions, SimplifyVertex};

use crate::deviation::simplified_deviation;
use crate::mesh::{edge_key, triangle_edges};

/// A group counts as simplified when it lost at least this share of its triangles;
/// otherwise its clusters are retried at the next level with other neighbours.
const STUCK_RATIO: f32 = 0.85;
/// Weight of each normal component against position error. With `ErrorClamped` the
/// attribute error cannot exceed the position error scale, so the weight only steers
/// which collapses happen first.
const NORMAL_WEIGHT: f32 = 0.5;

/// One simplified group in the group's own (global) vertex ids.
pub struct Simplified {
    pub indices: Vec<u32>,
    /// Object-space error of this simplification alone, as meshoptimizer estimates it.
    pub error: f32,
    /// Measured distance from the output's triangles to the input's (see
    /// [`simplified_deviation`]).
    pub deviation: f32,
}

/// How hard a group is pushed; the DAG builder raises it when a whole level is stuck.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Effort {
    /// Keep topology: no piece vanishes, no edge folds onto a third triangle.
    Normal,
    /// Let small disconnected pieces vanish.
    Prune,
    /// Last resort near the root, for a group that is everything left of the mesh:
    /// pruning, and folds are accepted rather than ending with many roots.
    Whole,
}

/// Simplifies `indices` (global vertex ids) to about half. `locked(v)` says whether a
/// global vertex lies on the group border. Returns `None` when the group is stuck.
///
/// Works on a compact copy of the group's vertices: meshoptimizer's cost is per vertex
/// of the buffer it is given, and a group is a tiny part of the mesh.
pub fn simplify_group(
    positions: &[Vec3],
    normals: &[Vec3],
    indices: &[u32],
    locked: impl Fn(u32) -> bool,
    effort: Effort,
) -> Option<Simplified> {
    let crate::meshlets::Localised { globals, local } = crate::meshlets::localise(indices);
    let pos: Vec<Vec3> = globals.iter().map(|&g| positions[g as usize]).collect();
    let attrs: Vec<Vec3> = globals.iter().map(|&g| normals[g as usize]).collect();
    let locks: Vec<SimplifyVertex> = globals
        .iter()
        .map(|&g| {
            if locked(g) {
                SimplifyVertex::Lock
            } else {
                SimplifyVertex::None
            }
        })
        .collect();
    let adapter = meshopt::VertexDataAdapter::new(bytemuck::cast_slice(&pos), 12, 0)
        .expect("Vec3 is 12 bytes");
    let triangles = indices.len() / 3;
    let mut options = SimplifyOptions::ErrorAbsolute | SimplifyOptions::ErrorClamped;
    if effort != Effort::Normal {
        options |= SimplifyOptions::Prune;
    }
    // Welded ids for the manifold check: seams must not count as separate edges.
    let weld = crate::mesh::position_remap(&pos);
    // The input's own folds, counted only when the output has any (most have none).
    let mut folds_before: Option<usize> = None;
    // Half first; if that folds the surface onto itself (near the root of thin shapes,
    // where opposite sides of a tube meet), a milder target that still counts as progress.
    for target in [triangles / 2, triangles * 3 / 4] {
        let target = target.max(1) * 3;
        let mut error = 0.0f32;
        let out = meshopt::simplify_with_attributes_and_locks(
            &local,
            &adapter,
            bytemuck::cast_slice(&attrs),
            &[NORMAL_WEIGHT; 3],
            12,
            &locks,
            target,
            f32::MAX,
            options,
            Some(&mut error),
        );
        if out.is_empty() || out.len() / 3 > (triangles as f32 * STUCK_RATIO) as usize {
            return None;
        }
        let folds = overused_edges(&out, &weld);
        if effort != Effort::Whole
            && folds > 0
            && folds > *folds_before.get_or_insert_with(|| overused_edges(&local, &weld))
        {
            continue;
        }
        return Some(Simplified {
            deviation: simplified_deviation(&pos, &local, &out),
            indices: out.iter().map(|&l| globals[l as usize]).collect(),
            error,
        });
    }
    None
}

/// Edges (between welded vertices) used by more than two triangles: a fold or a
/// non-manifold junction, which a watertight cut cannot contain.
fn overused_edges(indices: &[u32], weld: &[u32]) -> usize {
    let mut edges: Vec<u64> = triangle_edges(indices)
        .map(|(a, b)| edge_key(weld[a as usize], weld[b as usize]))
        .collect();
    edges.sort_unstable();
    edges
        .chunk_by(|a, b| a == b)
        .filter(|run| run.len() > 2)
        .count()
}
