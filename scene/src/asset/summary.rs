//! The figures `meshlight bake` and `meshlight inspect` both report about an asset:
//! per-level counts and errors, the roots, the culling hierarchy and where the bytes go.
//! Gathered here as values, so that a tool formats them as it likes and a test checks
//! the numbers rather than a table's wording.

use crate::asset::MeshletAsset;
use crate::asset::SizeBreakdown;
use crate::asset::format::{AssetHeader, NO_GROUP};
use crate::verify::level_stats;

/// One level of the DAG: LOD 0 first.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LevelSummary {
    /// Meshlets of the level.
    pub meshlets: usize,
    /// Triangles of the level's meshlets.
    pub triangles: usize,
    /// The largest simplification error of a meshlet of the level (0 at LOD 0), the
    /// error a view must tolerate to draw the level.
    pub max_error: f32,
}

/// The culling hierarchy's shape, to judge how much of it a view walks.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct HierarchySummary {
    /// Nodes in all.
    pub nodes: usize,
    /// Leaves: one per group, one for the roots.
    pub leaves: usize,
    /// Nodes on the longest path from the root to a leaf.
    pub depth: u32,
}

/// What a summary of an asset shows, computed once from a loaded asset.
#[derive(Debug, Clone, PartialEq)]
pub struct AssetSummary {
    /// The header as stored: counts, bounds, quantisation, checksum.
    pub header: AssetHeader,
    /// Size of the file in bytes.
    pub bytes: usize,
    /// The largest distance a position moves by quantisation to the grid.
    pub max_position_error: f32,
    /// Per level, LOD 0 first.
    pub levels: Vec<LevelSummary>,
    /// Meshlets without a parent group: what a distant view draws.
    pub root_meshlets: usize,
    /// Triangles of the root meshlets.
    pub root_triangles: u32,
    /// The culling hierarchy's shape.
    pub hierarchy: HierarchySummary,
    /// Bytes per part of the file.
    pub size: SizeBreakdown,
    /// Edges along which LOD 0 is open, as the bake recorded them (0: a closed mesh).
    pub open_edges: usize,
}

impl AssetSummary {
    /// The summary of `asset`. Loading has validated its structure, so nothing here can
    /// fail; a DAG that breaks its invariants still has a summary (`verify` says what
    /// is wrong with it).
    pub fn of(asset: &MeshletAsset) -> Self {
        let mut levels: Vec<LevelSummary> = level_stats(asset)
            .iter()
            .map(|st| LevelSummary {
                meshlets: st.meshlets,
                triangles: st.triangles,
                max_error: 0.0,
            })
            .collect();
        for m in asset.meshlets() {
            if let Some(level) = levels.get_mut(m.level() as usize) {
                level.max_error = level.max_error.max(asset.lod(m).1);
            }
        }
        let roots = asset
            .meshlets()
            .iter()
            .filter(|m| m.parent_group == NO_GROUP);
        let nodes = asset.nodes();
        Self {
            header: *asset.header(),
            bytes: asset.bytes().len(),
            max_position_error: asset.quantization().max_error(),
            levels,
            root_meshlets: roots.clone().count(),
            root_triangles: roots.map(|m| m.triangle_count()).sum(),
            hierarchy: HierarchySummary {
                nodes: nodes.len(),
                leaves: crate::hierarchy::leaf_count(nodes),
                depth: crate::hierarchy::depth(nodes),
            },
            size: asset.size_breakdown(),
            open_edges: asset.open_edges().len(),
        }
    }

    /// The checksum as one number, as tools print it.
    pub fn checksum(&self) -> u64 {
        self.header.checksum[0] as u64 | ((self.header.checksum[1] as u64) << 32)
    }
}
