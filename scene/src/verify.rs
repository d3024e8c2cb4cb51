//! The DAG invariants, checked on a packed asset: what `meshlight inspect` verifies and
//! what the tests hold every built mesh to.

use glam::Vec3;

use crate::asset::MeshletAsset;
use crate::bounds::contains;

/// Per-level counts of an asset.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct LevelStats {
    pub meshlets: usize,
    pub triangles: usize,
    pub vertices: usize,
}

/// Triangles, meshlets and vertices per level.
pub fn level_stats(asset: &MeshletAsset) -> Vec<LevelStats> {
    let mut stats = vec![LevelStats::default(); asset.header().level_count.max(1) as usize];
    for m in asset.meshlets() {
        let Some(s) = stats.get_mut(m.level() as usize) else {
            continue;
        };
        s.meshlets += 1;
        s.triangles += m.triangle_count() as usize;
        s.vertices += m.vertex_count() as usize;
    }
    stats
}

/// The level count the halving of triangles per level predicts: log2(LOD-0 meshlets)
/// steps from the leaves to a single root, plus the leaf level.
pub fn expected_levels(lod0_meshlets: u32) -> f32 {
    (lod0_meshlets.max(1) as f32).log2() + 1.0
}

/// Checks every invariant and returns one line per violation (empty = valid).
pub fn verify(asset: &MeshletAsset) -> Vec<String> {
    let mut problems = Vec::new();
    let h = asset.header();
    let meshlets = asset.meshlets();
    let sphere = |s: [f32; 4]| (Vec3::new(s[0], s[1], s[2]), s[3]);
    let mut parents = vec![0u32; meshlets.len()];
    for (gi, g) in asset.groups().iter().enumerate() {
        for &c in asset.group_children(g) {
            let child = &meshlets[c as usize];
            parents[c as usize] += 1;
            if child.lod_error > g.error {
                problems.push(format!(
                    "group {gi}: error {} below child meshlet {c}'s {}",
                    g.error, child.lod_error
                ));
            }
            if !contains(sphere(g.lod_sphere), sphere(child.lod_sphere)) {
                problems.push(format!(
                    "group {gi}: LOD sphere does not contain child meshlet {c}'s"
                ));
            }
            if child.parent_error != g.error || child.parent_sphere != g.lod_sphere {
                problems.push(format!(
                    "meshlet {c}: parent LOD bounds differ from its group {gi}'s"
                ));
            }
        }
    }
    let mut roots = 0;
    for (i, m) in meshlets.iter().enumerate() {
        let is_root = m.parent_error == f32::MAX;
        roots += is_root as usize;
        match (is_root, parents[i]) {
            (true, 0) | (false, 1) => {}
            (true, n) => problems.push(format!("root meshlet {i} is a child of {n} groups")),
            (false, n) => problems.push(format!("meshlet {i} is a child of {n} groups, not one")),
        }
        if m.lod_error > m.parent_error {
            problems.push(format!(
                "meshlet {i}: own error {} above its parent's {}",
                m.lod_error, m.parent_error
            ));
        }
        if m.level() == 0 && m.lod_error != 0.0 {
            problems.push(format!("LOD-0 meshlet {i} has error {}", m.lod_error));
        }
    }
    if !(1..=3).contains(&roots) {
        problems.push(format!(
            "{roots} root meshlets; the DAG should end in 1 to 3"
        ));
    }
    if roots as u32 != h.root_count {
        problems.push(format!("header says {} roots, found {roots}", h.root_count));
    }
    let expected = expected_levels(h.lod0_meshlets);
    let levels = h.level_count as f32;
    if (levels - expected).abs() > (expected * 0.5).max(2.0) {
        problems.push(format!(
            "{} levels for {} LOD-0 meshlets; about {:.1} expected",
            h.level_count, h.lod0_meshlets, expected
        ));
    }
    problems
}
