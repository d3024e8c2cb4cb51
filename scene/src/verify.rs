//! The DAG checks on a packed asset, in two kinds: [`verify`] finds structural
//! violations (the asset would draw wrongly: bounds, error monotonicity, parent links,
//! LOD 0 open where the bake left it closed, cracks in LOD cuts, triangle records),
//! which make `meshlight inspect` fail; [`quality`] finds a valid DAG that is merely poor
//! (too deep, too many roots, levels that do not halve), which it reports as warnings.

use glam::Vec3;

use crate::asset::MeshletAsset;
use crate::asset::format::NO_GROUP;
use crate::asset::scan::scan_meshlets;
use crate::bounds::contains;
use crate::chain_fingerprint::ChainKeys;

/// Per-level counts of an asset.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct LevelStats {
    /// Meshlets of the level.
    pub meshlets: usize,
    /// Triangles of the level: each level should hold about half the one before.
    pub triangles: usize,
    /// Vertex records of the level (a vertex counts once per meshlet using it).
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

/// Most levels a good DAG has: ⌈log2(LOD-0 meshlets)⌉ + 2.
pub fn level_limit(lod0_meshlets: u32) -> u32 {
    (lod0_meshlets.max(1) as f32).log2().ceil() as u32 + 2
}

/// Most triangles a level may hold relative to the level before (the last step to the
/// root aside, which may be small).
pub const MAX_LEVEL_RATIO: f64 = 0.55;
/// Most triangles all levels together may hold relative to LOD 0.
pub const MAX_TOTAL_RATIO: f64 = 2.1;
/// Most root meshlets of a good DAG.
pub const MAX_ROOTS: u32 = 3;

/// How good a valid DAG is, and what is poor about it.
#[derive(Debug, Clone, PartialEq)]
pub struct Quality {
    /// One line per finding, each saying what is poor and what to try.
    pub warnings: Vec<String>,
    /// Largest triangles(level) / triangles(level - 1), the last level aside.
    pub worst_ratio: f64,
    /// Most levels a good DAG of this size has ([`level_limit`]).
    pub level_limit: u32,
    /// All levels' triangles over LOD 0's.
    pub total_ratio: f64,
}

/// The quality targets: levels that halve, a shallow DAG, one root.
pub fn quality(asset: &MeshletAsset) -> Quality {
    let h = asset.header();
    let stats = level_stats(asset);
    let limit = level_limit(h.lod0_meshlets);
    let mut warnings = Vec::new();
    let try_this = "try the other `--grouping`, or check the mesh for non-manifold edges and \
                    disconnected slivers";
    let mut worst_ratio = 0.0f64;
    let last = stats.len().saturating_sub(1);
    for level in 1..last {
        let ratio = stats[level].triangles as f64 / stats[level - 1].triangles.max(1) as f64;
        worst_ratio = worst_ratio.max(ratio);
        if ratio > MAX_LEVEL_RATIO {
            warnings.push(format!(
                "level {level} holds {:.2}x the triangles of level {} (a good DAG halves, at most \
                 {MAX_LEVEL_RATIO}x): simplification got stuck there; {try_this}",
                ratio,
                level - 1
            ));
        }
    }
    if h.level_count > limit {
        warnings.push(format!(
            "{} levels for {} LOD-0 meshlets, more than the {limit} that halving gives: the DAG \
             is deep and LOD selection walks more levels; {try_this}",
            h.level_count, h.lod0_meshlets
        ));
    }
    if h.root_count > MAX_ROOTS {
        warnings.push(format!(
            "{} root meshlets (a good DAG ends in 1 to {MAX_ROOTS}): the coarsest view draws \
             more than it needs; {try_this}",
            h.root_count
        ));
    }
    let total_ratio = h.total_triangles as f64 / h.lod0_triangles.max(1) as f64;
    if total_ratio > MAX_TOTAL_RATIO {
        warnings.push(format!(
            "all levels hold {total_ratio:.2}x the LOD-0 triangles (at most {MAX_TOTAL_RATIO}x \
             when levels halve): the asset is larger than it needs to be; {try_this}"
        ));
    }
    Quality {
        warnings,
        worst_ratio,
        level_limit: limit,
        total_ratio,
    }
}

/// Checks every structural invariant and returns one line per violation (empty = valid).
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
            let (child_sphere, child_error) = asset.lod(child);
            if child_error > g.error {
                problems.push(format!(
                    "group {gi}: error {} below child meshlet {c}'s {child_error}",
                    g.error
                ));
            }
            if !contains(sphere(g.lod_sphere), sphere(child_sphere)) {
                problems.push(format!(
                    "group {gi}: LOD sphere does not contain child meshlet {c}'s"
                ));
            }
            if child.parent_group != gi as u32 {
                problems.push(format!(
                    "meshlet {c}: parent group {:#x}, but group {gi} lists it as a child",
                    child.parent_group
                ));
            }
        }
    }
    let mut roots = 0;
    for (i, m) in meshlets.iter().enumerate() {
        let is_root = m.parent_group == NO_GROUP;
        roots += is_root as usize;
        match (is_root, parents[i]) {
            (true, 0) | (false, 1) => {}
            (true, n) => problems.push(format!("root meshlet {i} is a child of {n} groups")),
            (false, n) => problems.push(format!("meshlet {i} is a child of {n} groups, not one")),
        }
    }
    // One decoding pass gives the per-meshlet checks and the crack check's fingerprints.
    let keys = ChainKeys::random();
    let scans = scan_meshlets(asset, &keys);
    for (i, (m, scan)) in meshlets.iter().zip(&scans).enumerate() {
        if let Some(t) = scan.first_out_of_range {
            problems.push(format!(
                "meshlet {i}: triangle {t} refers past its {} vertices (decoded clamped)",
                m.vertex_count()
            ));
        }
        // The culling sphere holds every decoded vertex: what the renderer culls by.
        let centre = Vec3::new(m.bounds[0], m.bounds[1], m.bounds[2]);
        if scan.farthest > m.bounds[3] * (1.0 + 1e-5) + 1e-6 * centre.abs().max_element() {
            problems.push(format!(
                "meshlet {i}: a vertex lies {} from the centre of its culling sphere of \
                 radius {}",
                scan.farthest, m.bounds[3]
            ));
        }
    }
    if roots == 0 {
        problems.push("no root meshlet; the coarsest level must have one".to_owned());
    }
    // Cracks compare neighbouring pages: checked on a whole asset (by `bake` and
    // `inspect`), not on the resident part of one opened for streaming.
    if asset.page_file().is_none() {
        problems.extend(crate::open_edges::lod0_problem(asset, &scans, &keys));
        problems.extend(crate::watertight::crack_problems_scanned(asset, &scans));
    }
    if roots as u32 != h.root_count {
        problems.push(format!("header says {} roots, found {roots}", h.root_count));
    }
    problems
}
