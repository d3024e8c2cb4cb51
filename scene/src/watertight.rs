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
//!
//! How it is checked cheaply enough to run on every load: the edges whose net use differs
//! between a group's children and its outputs are the edges of the difference of their
//! boundaries, so a group whose outputs have its children's boundary cannot crack. That
//! is compared first, for every group at once, by boundary fingerprints
//! ([`crate::chain_fingerprint`]) taken in the one decoding pass over the meshlets
//! ([`crate::asset::scan`]). Only the groups whose boundary changed (none on a closed
//! mesh; on an open one, those whose simplification moved the mesh's own boundary) are
//! looked at edge by edge: their changed edges from the boundaries of their meshlets, and
//! for each, the other groups of the level whose meshlets' grid boxes hold both its
//! points. That gives what [`exhaustive_crack_problems`], which hashes every edge of every
//! group, gives.

use std::collections::BTreeMap;

use rayon::prelude::*;
use rustc_hash::{FxHashMap, FxHashSet};

use crate::asset::MeshletAsset;
use crate::asset::scan::{MeshletScan, scan_meshlets};
use crate::chain_fingerprint::ChainKeys;

type Vertex = [u32; 3];
type Edge = (Vertex, Vertex);

/// One line per group whose outputs do not meet its neighbours like its children.
pub fn crack_problems(asset: &MeshletAsset) -> Vec<String> {
    crack_problems_scanned(asset, &scan_meshlets(asset, &ChainKeys::random()))
}

/// [`crack_problems`] from a scan of the asset's meshlets (one per meshlet, in order),
/// which the other DAG checks share.
pub fn crack_problems_scanned(asset: &MeshletAsset, scans: &[MeshletScan]) -> Vec<String> {
    let changed = changed_boundaries(asset, scans);
    if changed.is_empty() {
        return Vec::new();
    }
    let groups = asset.groups();
    let mut outputs: FxHashMap<usize, Vec<u32>> =
        changed.iter().map(|&g| (g, Vec::new())).collect();
    for (i, m) in asset.meshlets().iter().enumerate() {
        if let Some(o) = outputs.get_mut(&(m.source_group as usize)) {
            o.push(i as u32);
        }
    }
    let level = Level::index(asset);
    let mut cracked: Vec<(u32, usize, usize)> = changed
        .par_iter()
        .map(|&g| {
            let n = SCRATCH
                .with_borrow_mut(|scratch| cracked_edges(asset, g, &outputs[&g], &level, scratch));
            (groups[g].level, g, n)
        })
        .collect();
    // In the exhaustive check's order: by level, then by group.
    cracked.sort_unstable();
    cracked
        .into_iter()
        .filter(|&(_, _, n)| n > 0)
        .map(|(_, g, n)| crack_message(g, n))
        .collect()
}

fn crack_message(group: usize, cracked: usize) -> String {
    format!(
        "group {group}: its simplified meshlets use {cracked} edges shared with neighbouring \
         groups differently from its children: a crack in some LOD cut"
    )
}

/// The groups whose outputs' boundary differs from their children's, by fingerprint.
fn changed_boundaries(asset: &MeshletAsset, scans: &[MeshletScan]) -> Vec<usize> {
    let groups = asset.groups();
    let mut change: Vec<u64> = groups
        .iter()
        .map(|g| {
            asset
                .group_children(g)
                .iter()
                .fold(0u64, |sum, &c| sum.wrapping_add(scans[c as usize].boundary))
        })
        .collect();
    for (m, scan) in asset.meshlets().iter().zip(scans) {
        if let Some(d) = change.get_mut(m.source_group as usize) {
            *d = d.wrapping_sub(scan.boundary);
        }
    }
    (0..groups.len()).filter(|&g| change[g] != 0).collect()
}

/// A box of grid points, bounds included.
#[derive(Debug, Clone, Copy)]
struct GridBox {
    lo: [u64; 3],
    hi: [u64; 3],
}

impl GridBox {
    const EMPTY: GridBox = GridBox {
        lo: [u64::MAX; 3],
        hi: [0; 3],
    };

    /// Where a meshlet's vertices can lie: its grid minimum plus what its bits hold.
    fn of_meshlet(asset: &MeshletAsset, m: u32) -> Self {
        let m = &asset.meshlets()[m as usize];
        let bits = m.axis_bits();
        let lo = m.grid_min.map(u64::from);
        GridBox {
            lo,
            hi: [0, 1, 2].map(|k| lo[k] + (1u64 << bits[k].min(32)) - 1),
        }
    }

    fn add_point(&mut self, p: Vertex) {
        let p = p.map(u64::from);
        self.add_box(&GridBox { lo: p, hi: p });
    }

    fn add_box(&mut self, b: &GridBox) {
        for k in 0..3 {
            self.lo[k] = self.lo[k].min(b.lo[k]);
            self.hi[k] = self.hi[k].max(b.hi[k]);
        }
    }

    fn overlaps(&self, b: &GridBox) -> bool {
        (0..3).all(|k| self.lo[k] <= b.hi[k] && b.lo[k] <= self.hi[k])
    }

    fn holds(&self, p: Vertex) -> bool {
        (0..3).all(|k| (self.lo[k]..=self.hi[k]).contains(&(p[k] as u64)))
    }
}

/// The groups of each level and the grid box of each group's children, for finding the
/// groups that can use an edge.
struct Level {
    groups: BTreeMap<u32, Vec<usize>>,
    boxes: Vec<GridBox>,
}

impl Level {
    fn index(asset: &MeshletAsset) -> Self {
        let mut groups: BTreeMap<u32, Vec<usize>> = BTreeMap::new();
        let boxes = asset
            .groups()
            .iter()
            .enumerate()
            .map(|(g, group)| {
                groups.entry(group.level).or_default().push(g);
                let mut b = GridBox::EMPTY;
                for &c in asset.group_children(group) {
                    b.add_box(&GridBox::of_meshlet(asset, c));
                }
                b
            })
            .collect();
        Self { groups, boxes }
    }
}

/// How many of group `g`'s changed edges another group of its level uses: those are
/// shared with a neighbour, and the outputs use them differently from the children.
fn cracked_edges(
    asset: &MeshletAsset,
    g: usize,
    outputs: &[u32],
    level: &Level,
    scratch: &mut Scratch,
) -> usize {
    let groups = asset.groups();
    let children = asset.group_children(&groups[g]);
    let mut changed = changed_edges(asset, children, outputs, scratch);
    if changed.is_empty() {
        return 0;
    }
    changed.sort_unstable();
    let mut reach = GridBox::EMPTY;
    for &(a, b) in &changed {
        reach.add_point(a);
        reach.add_point(b);
    }
    let points: FxHashSet<Vertex> = changed.iter().flat_map(|&(a, b)| [a, b]).collect();
    // Per changed edge: the first other group seen using it, and whether a second did.
    let mut users: Vec<(Option<usize>, bool)> = vec![(None, false); changed.len()];
    for &h in &level.groups[&groups[g].level] {
        if h == g || !level.boxes[h].overlaps(&reach) {
            continue;
        }
        for &c in asset.group_children(&groups[h]) {
            // A meshlet can use an edge only if its box, then its vertices, hold both
            // points: most neighbours' meshlets are passed over before their triangles.
            let b = GridBox::of_meshlet(asset, c);
            if !changed.iter().any(|&(p, q)| b.holds(p) && b.holds(q)) {
                continue;
            }
            let grid = asset.decode_grid(c as usize);
            let found: FxHashSet<Vertex> = grid
                .iter()
                .filter(|p| points.contains(*p))
                .copied()
                .collect();
            if !changed
                .iter()
                .any(|(p, q)| found.contains(p) && found.contains(q))
            {
                continue;
            }
            for t in asset.decode_triangles(c as usize) {
                for k in 0..3 {
                    let (p, q) = (grid[t[k] as usize], grid[t[(k + 1) % 3] as usize]);
                    let e = if p < q { (p, q) } else { (q, p) };
                    if let Ok(i) = changed.binary_search(&e) {
                        match users[i].0 {
                            None => users[i].0 = Some(h),
                            Some(first) if first != h => users[i].1 = true,
                            Some(_) => {}
                        }
                    }
                }
            }
        }
    }
    // An edge one other group uses is shared if this group's children use it too.
    let mut own: FxHashSet<Edge> = FxHashSet::default();
    let wanted: FxHashSet<Edge> = changed
        .iter()
        .zip(&users)
        .filter(|(_, u)| u.0.is_some() && !u.1)
        .map(|(&e, _)| e)
        .collect();
    if !wanted.is_empty() {
        for &c in children {
            for_each_edge(asset, c, |e, _| {
                if wanted.contains(&e) {
                    own.insert(e);
                }
            });
        }
    }
    changed
        .iter()
        .zip(&users)
        .filter(|(e, u)| u.1 || (u.0.is_some() && own.contains(*e)))
        .count()
}

/// The edges whose net directed use differs between `before` and `after`, from the
/// boundaries of their meshlets: an edge a meshlet uses both ways nets to zero there, so
/// only a few dozen edges per meshlet are hashed instead of every triangle's three.
fn changed_edges(
    asset: &MeshletAsset,
    before: &[u32],
    after: &[u32],
    scratch: &mut Scratch,
) -> Vec<Edge> {
    let Scratch { local, grid, net } = scratch;
    net.clear();
    for (meshlets, sign) in [(before, 1), (after, -1)] {
        for &m in meshlets {
            let m = &asset.meshlets()[m as usize];
            grid.clear();
            asset.for_each_grid_point(m, |_, p| grid.push(p));
            asset.for_each_triangle(m, |t| local.add(grid.len(), t));
            local.drain(grid.len(), |a, b, n| {
                let (p, q) = (grid[a as usize], grid[b as usize]);
                if p != q {
                    let (key, s) = if p < q { ((p, q), 1) } else { ((q, p), -1) };
                    *net.entry(key).or_default() += sign * s * n;
                }
            });
        }
    }
    net.iter()
        .filter(|&(_, &n)| n != 0)
        .map(|(&e, _)| e)
        .collect()
}

/// What checking one group edge by edge reuses from the last group on its thread.
struct Scratch {
    local: LocalEdges,
    grid: Vec<Vertex>,
    net: FxHashMap<Edge, i32>,
}

thread_local! {
    /// One scratch per thread, kept: allocating the table and first touching its pages
    /// for every group cost more than the group's edges. Nothing run while it is
    /// borrowed waits on rayon, so a thread never takes it up twice.
    static SCRATCH: std::cell::RefCell<Scratch> = std::cell::RefCell::new(Scratch {
        local: LocalEdges::new(),
        grid: Vec::new(),
        net: FxHashMap::default(),
    });
}

/// Net directed uses of a meshlet's local edges, in a table indexed by the pair of
/// local vertex indices `a · vertices + b` (so that a meshlet's entries lie together,
/// in the first cache lines), cleared as they are read.
struct LocalEdges {
    net: Vec<i16>,
    touched: Vec<(u8, u8)>,
}

impl LocalEdges {
    fn new() -> Self {
        Self {
            net: vec![0; 1 << 16],
            touched: Vec::new(),
        }
    }

    fn at(vertices: usize, a: u8, b: u8) -> usize {
        a as usize * vertices.clamp(1, 256) + b as usize
    }

    /// Counts the edges of triangle `t` of a meshlet of `vertices` vertices.
    fn add(&mut self, vertices: usize, t: [u8; 3]) {
        for k in 0..3 {
            let (a, b) = (t[k], t[(k + 1) % 3]);
            if a == b {
                continue;
            }
            let (pair, s) = if a < b { ((a, b), 1) } else { ((b, a), -1) };
            self.net[Self::at(vertices, pair.0, pair.1)] += s;
            self.touched.push(pair);
        }
    }

    /// Calls `each(a, b, n)` for every pair of local vertices `a < b` whose edge the
    /// triangles added use a net `n ≠ 0` times from `a` to `b`, and clears the table.
    fn drain(&mut self, vertices: usize, mut each: impl FnMut(u8, u8, i32)) {
        for &(a, b) in &self.touched {
            let n = std::mem::take(&mut self.net[Self::at(vertices, a, b)]);
            if n != 0 {
                each(a, b, n as i32);
            }
        }
        self.touched.clear();
    }
}

/// Calls `each` with every edge of meshlet `m`'s triangles between two different grid
/// points, keyed by its points in order, and +1 or -1 for its direction.
fn for_each_edge(asset: &MeshletAsset, m: u32, mut each: impl FnMut(Edge, i32)) {
    let (grid, triangles) = asset.decode_topology(m as usize);
    for t in &triangles {
        for k in 0..3 {
            let (a, b) = (grid[t[k] as usize], grid[t[(k + 1) % 3] as usize]);
            if a == b {
                continue;
            }
            if a < b {
                each((a, b), 1)
            } else {
                each((b, a), -1)
            }
        }
    }
}

/// Every group checked edge by edge, hashing every edge of every group's children and
/// outputs, with no fingerprints and no boxes: the reference [`crack_problems`] is
/// tested against.
pub fn exhaustive_crack_problems(asset: &MeshletAsset) -> Vec<String> {
    let groups = asset.groups();
    let meshlets = asset.meshlets();
    let mut outputs: Vec<Vec<u32>> = vec![Vec::new(); groups.len()];
    for (i, m) in meshlets.iter().enumerate() {
        if let Some(o) = outputs.get_mut(m.source_group as usize) {
            o.push(i as u32);
        }
    }
    let mut by_level: BTreeMap<u32, Vec<usize>> = BTreeMap::new();
    for (g, group) in groups.iter().enumerate() {
        by_level.entry(group.level).or_default().push(g);
    }
    let mut problems = Vec::new();
    for at_level in by_level.values() {
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
                let net = |uses: &FxHashMap<Edge, i32>, e: &Edge| uses.get(e).copied().unwrap_or(0);
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
                problems.push(crack_message(g, cracked));
            }
        }
    }
    problems
}

/// Net directed uses (+1 one way, -1 the other) of every edge of `meshlets`' triangles,
/// keyed by its two grid points in order; an edge used both ways nets to zero but is
/// kept, so that "used" and "net" are both known.
fn directed_uses(asset: &MeshletAsset, meshlets: &[u32]) -> FxHashMap<Edge, i32> {
    let mut net: FxHashMap<Edge, i32> = FxHashMap::default();
    for &m in meshlets {
        for_each_edge(asset, m, |e, s| *net.entry(e).or_default() += s);
    }
    net
}
