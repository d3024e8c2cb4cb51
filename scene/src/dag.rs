//! The meshlet LOD DAG: meshlets of the input, then level after level of groups of
//! about eight neighbouring meshlets, each simplified to half with its border locked
//! and split into new meshlets, until a root of one to three meshlets is left.
//!
//! Why borders are locked: two neighbouring groups simplify independently, so only the
//! vertices they share may never move; then any cut through the DAG (each cluster drawn
//! when its own error is acceptable and its parent's is not) is watertight.
//!
//! Why errors add up: a group's error must bound the distance from its output to the
//! full-detail surface. Its children lie within their errors of LOD 0 and its output
//! within the measured deviation of the children, so the sum of the two is a bound
//! (triangle inequality), and it is never below a child's error.

use glam::Vec3;
use rayon::prelude::*;
use rustc_hash::{FxHashMap, FxHashSet};

use crate::bounds::{LodBounds, merge_spheres, sphere_of_points};
use crate::error::SceneError;
use crate::grouping::{Grouping, group_clusters};
use crate::mesh::{Mesh, edge_key, position_remap, triangle_edges};
use crate::meshlets::{split_into_meshlets, split_mesh_into_meshlets};
use crate::simplify::{Attributes, Mode, VertexFlags, simplify_group};
use crate::uv_slide::{UvSurface, simplified_uv_slide, uv_charts};

/// Marks "none" in cluster → group links.
pub const NO_GROUP: u32 = u32::MAX;

/// One meshlet of the DAG, in the input mesh's vertex ids.
#[derive(Debug, Clone, PartialEq)]
pub struct DagCluster {
    /// Three global vertex ids per triangle.
    pub indices: Vec<u32>,
    /// 0 for the input's meshlets; a simplified cluster is one above the group level.
    pub level: u32,
    /// Sphere around the cluster's own vertices, for culling.
    pub bounds: (Vec3, f32),
    /// The LOD sphere and error of the group that produced this cluster (its own
    /// sphere and zero error at level 0).
    pub lod: LodBounds,
    /// The LOD sphere and error of the group this cluster was simplified in; infinite
    /// error for root clusters, which are drawn whenever nothing finer is.
    pub parent: LodBounds,
    /// The group this cluster is a child of, or [`NO_GROUP`] for roots.
    pub parent_group: u32,
    /// The group that produced this cluster, or [`NO_GROUP`] at level 0.
    pub source_group: u32,
    /// The material slot of all its triangles (see [`Mesh::materials`]).
    pub material: u32,
}

impl DagCluster {
    /// Triangles of the cluster.
    pub fn triangle_count(&self) -> usize {
        self.indices.len() / 3
    }
}

/// A set of clusters simplified together; its outputs are the clusters whose
/// `source_group` is this group.
#[derive(Debug, Clone, PartialEq)]
pub struct DagGroup {
    /// The build iteration that formed the group (children may be from lower levels when
    /// they were stuck before).
    pub level: u32,
    /// Encloses every child's LOD sphere; error = the larger of max(children) +
    /// max(simplify error, deviation) and the UV slide.
    pub lod: LodBounds,
    /// Error of this group's simplification alone, as meshoptimizer estimates it.
    pub simplify_error: f32,
    /// Measured distance from this group's output to its children's triangles.
    pub deviation: f32,
    /// Bound on how far from LOD 0's a texel of this group's output is drawn (see
    /// [`crate::uv_slide`]); 0 for a mesh without UVs. `lod.error` is at least this.
    pub uv_slide: f32,
    /// How hard it had to be pushed to simplify.
    pub mode: Mode,
    /// The clusters simplified together (indices into [`Dag::clusters`]).
    pub children: Vec<u32>,
}

/// The whole hierarchy for one mesh.
#[derive(Debug, Clone, PartialEq)]
pub struct Dag {
    /// Every cluster of every level, in page order: the roots first, then each group's
    /// children in group order (so a group's children are one range, the asset's page;
    /// see [`crate::asset::format`]).
    pub clusters: Vec<DagCluster>,
    /// Every group, in the order they were formed.
    pub groups: Vec<DagGroup>,
    /// Number of cluster levels (max level + 1).
    pub level_count: u32,
    /// Groups whose first result would have cracked a LOD cut, and what was done.
    pub fallbacks: Fallbacks,
}

/// Groups with no result that keeps the edges they share with neighbouring groups as
/// their children used them (anything else is a crack in some LOD cut), repaired
/// locally.
///
/// Border locking alone does not always keep them: where an edge has more than two
/// triangles, a triangle is wound the other way (a scan's), or a locked vertex's last
/// triangles collapse, the simplifier may drop or add a use of a border edge. Each
/// mode's result is checked, so a group takes the smallest result that keeps its border
/// (a mode that broke it does not end the search). A group none of whose modes keep it,
/// or that is stuck, is simplified again with every corner of its border triangles
/// locked (`relocked`); if that still fails, the group is not formed
/// (`unsimplified`): its children stay the cut there and are tried once more at the
/// next level with other neighbours. That leaves a level short and the next one long,
/// which is why a mode that breaks the border must not end the search.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Fallbacks {
    /// Groups simplified again with their border triangles locked.
    pub relocked: usize,
    /// Groups not formed: their children stayed the cut there.
    pub unsimplified: usize,
}

/// How to build the DAG.
#[derive(Debug, Clone, Copy, Default)]
pub struct DagOptions {
    /// How the clusters of a level are grouped for simplification.
    pub grouping: Grouping,
}

/// Reported once per finished level, for progress bars.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct LevelProgress {
    /// Levels built so far (1 after the first simplification).
    pub level: u32,
    /// Clusters not yet simplified (the candidates for the next level).
    pub active_clusters: usize,
    /// Triangles of those clusters: what is left to simplify, which about halves per
    /// level and so measures how far the build has come.
    pub active_triangles: usize,
}

/// Builds the DAG of a cleaned mesh (see [`Mesh::clean`]).
pub fn build_dag(
    mesh: &Mesh,
    options: &DagOptions,
    progress: &mut dyn FnMut(LevelProgress),
) -> Result<Dag, SceneError> {
    // Built at unit scale, and scaled back at the end (see `crate::mesh::unit_scale`).
    let unit = crate::mesh::unit_scale(&mesh.positions);
    let scaled: Vec<Vec3> = mesh.positions.iter().map(|&p| p * unit).collect();
    let positions = &scaled;
    let attributes = Attributes {
        normals: &mesh.normals,
        uvs: &mesh.uvs,
        colors: &mesh.colors,
        texel: crate::uv_slide::texel_size(positions, &mesh.uvs, &mesh.indices),
    };
    let remap = position_remap(positions);
    // Meshlets grow across attribute seams, where there are any.
    let weld = remap
        .iter()
        .enumerate()
        .any(|(v, &r)| r != v as u32)
        .then_some(remap.as_slice());

    // Each vertex's material slot, and the slots' triangles split on their own, so that
    // no meshlet straddles two materials.
    let slots = mesh.vertex_materials();
    let lod0 = meshlets_by_material(&mesh.indices, &slots, |indices| {
        split_mesh_into_meshlets(positions, indices, weld)
    });
    let mut clusters: Vec<DagCluster> = lod0
        .into_par_iter()
        .map(|(material, indices)| {
            let bounds = sphere_of(positions, &indices);
            DagCluster {
                indices,
                level: 0,
                bounds,
                lod: LodBounds {
                    center: bounds.0,
                    radius: bounds.1,
                    error: 0.0,
                },
                parent: LodBounds::ROOT_PARENT,
                parent_group: NO_GROUP,
                source_group: NO_GROUP,
                material,
            }
        })
        .collect();
    let mut groups: Vec<DagGroup> = Vec::new();
    let mut active: Vec<u32> = (0..clusters.len() as u32).collect();
    // Clusters whose group was stuck once; stuck again, they become terminal roots.
    let mut retried = vec![false; clusters.len()];
    let mut level = 0u32;
    let (seam, material_border) = seam_vertices(mesh, &remap, &slots);
    let charts = match mesh.has_uvs() {
        true => uv_charts(positions.len(), &mesh.indices),
        false => Vec::new(),
    };
    // Which group uses each welded vertex this level; shared ones are the borders.
    let mut owner = vec![u32::MAX; positions.len()];
    let mut border = vec![false; positions.len()];
    let mut fallbacks = Fallbacks::default();

    while active.len() > 1 {
        let keyed: Vec<Vec<u32>> = active
            .iter()
            .map(|&c| {
                clusters[c as usize]
                    .indices
                    .iter()
                    .map(|&v| remap[v as usize])
                    .collect()
            })
            .collect();
        let level_groups = group_clusters(options.grouping, &keyed, positions, &mesh.source)?;

        owner.fill(u32::MAX);
        border.fill(false);
        for (g, members) in level_groups.iter().enumerate() {
            for &m in members {
                for &k in &keyed[m as usize] {
                    let o = &mut owner[k as usize];
                    if *o == u32::MAX {
                        *o = g as u32;
                    } else if *o != g as u32 {
                        border[k as usize] = true;
                    }
                }
            }
        }

        let shared = shared_edges(&level_groups, &keyed, &border);
        // The level as a textured surface, each triangle with its cluster's error: what
        // a group's texture slide is measured against (see `crate::uv_slide`).
        // (Nothing to measure on a mesh without UVs: the surface is left empty.)
        let textured: &[u32] = match mesh.has_uvs() {
            true => &active,
            false => &[],
        };
        let level_indices: Vec<u32> = textured
            .iter()
            .flat_map(|&c| clusters[c as usize].indices.iter().copied())
            .collect();
        let level_errors: Vec<f32> = textured
            .iter()
            .flat_map(|&c| {
                let c = &clusters[c as usize];
                std::iter::repeat_n(c.lod.error, c.triangle_count())
            })
            .collect();
        let level_surface = UvSurface::new(
            positions,
            &mesh.uvs,
            &charts,
            &level_indices,
            attributes.texel,
        )
        .with_errors(level_errors);
        let locked = |v: u32| border[remap[v as usize] as usize];
        let flags = VertexFlags {
            locked: &locked,
            seam: &seam,
            materials: &slots,
            material_border: &material_border,
        };
        let results: Vec<_> = level_groups
            .par_iter()
            .map(|members| {
                let indices: Vec<u32> = members
                    .iter()
                    .flat_map(|&m| {
                        clusters[active[m as usize] as usize]
                            .indices
                            .iter()
                            .copied()
                    })
                    .collect();
                let seals = |out: &[u32]| seals_borders(&indices, out, &remap, &border, &shared);
                let mut fallback = None;
                let simplified =
                    match simplify_group(positions, &attributes, &indices, &flags, &seals) {
                        Some(s) => s,
                        None => {
                            let relocked =
                                border_triangle_corners(&indices, &remap, &border, &shared);
                            let locked = |v: u32| {
                                let w = remap[v as usize];
                                border[w as usize] || relocked.contains(&w)
                            };
                            let flags = VertexFlags {
                                locked: &locked,
                                seam: &seam,
                                materials: &slots,
                                material_border: &material_border,
                            };
                            match simplify_group(positions, &attributes, &indices, &flags, &seals) {
                                Some(s) => {
                                    fallback = Some(Fallback::Relocked);
                                    s
                                }
                                _ => return (None, Some(Fallback::Unsimplified)),
                            }
                        }
                    };
                let uv_slide = simplified_uv_slide(&level_surface, &indices, &simplified.indices);
                let meshlets = meshlets_by_material(&simplified.indices, &slots, |indices| {
                    split_into_meshlets(positions, indices, weld)
                });
                let bounds: Vec<_> = meshlets
                    .iter()
                    .map(|(_, m)| sphere_of(positions, m))
                    .collect();
                (Some((simplified, uv_slide, meshlets, bounds)), fallback)
            })
            .collect();

        let mut next = Vec::with_capacity(active.len() / 2);
        for (members, (result, fallback)) in level_groups.iter().zip(results) {
            match fallback {
                Some(Fallback::Relocked) => fallbacks.relocked += 1,
                Some(Fallback::Unsimplified) => fallbacks.unsimplified += 1,
                None => {}
            }
            let children: Vec<u32> = members.iter().map(|&m| active[m as usize]).collect();
            let Some((simplified, uv_slide, meshlets, bounds)) = result else {
                // Stuck even with the sloppy fallback: once more with other neighbours,
                // then a terminal root (drawn whenever nothing finer is).
                for &c in &children {
                    if !retried[c as usize] {
                        retried[c as usize] = true;
                        next.push(c);
                    }
                }
                continue;
            };
            let own_error = simplified.error.max(simplified.deviation);
            let mut lod = group_lod(&clusters, &children, own_error);
            lod.error = lod.error.max(uv_slide);
            let id = groups.len() as u32;
            for &c in &children {
                let child = &mut clusters[c as usize];
                child.parent = lod;
                child.parent_group = id;
            }
            for ((material, indices), bounds) in meshlets.into_iter().zip(bounds) {
                next.push(clusters.len() as u32);
                retried.push(false);
                clusters.push(DagCluster {
                    indices,
                    level: level + 1,
                    bounds,
                    lod,
                    parent: LodBounds::ROOT_PARENT,
                    parent_group: NO_GROUP,
                    source_group: id,
                    material,
                });
            }
            groups.push(DagGroup {
                level,
                lod,
                simplify_error: simplified.error,
                deviation: simplified.deviation,
                uv_slide,
                mode: simplified.mode,
                children,
            });
        }
        active = next;
        level += 1;
        progress(LevelProgress {
            level,
            active_clusters: active.len(),
            active_triangles: active
                .iter()
                .map(|&c| clusters[c as usize].triangle_count())
                .sum(),
        });
    }
    let roots = clusters
        .iter()
        .filter(|c| c.parent_group == NO_GROUP)
        .count();
    if roots > crate::verify::MAX_ROOTS as usize {
        log::warn!(
            "{}: {roots} root clusters; some groups stayed stuck even with sloppy simplification",
            mesh.source
        );
    }
    let level_count = clusters.iter().map(|c| c.level).max().unwrap_or(0) + 1;
    let back = |b: LodBounds| LodBounds {
        center: b.center / unit,
        radius: b.radius / unit,
        error: b.error / unit,
    };
    for c in &mut clusters {
        c.bounds = (c.bounds.0 / unit, c.bounds.1 / unit);
        c.lod = back(c.lod);
        c.parent = back(c.parent);
    }
    for g in &mut groups {
        g.lod = back(g.lod);
        g.simplify_error /= unit;
        g.deviation /= unit;
        g.uv_slide /= unit;
    }
    Ok(Dag {
        clusters,
        groups,
        level_count,
        fallbacks,
    }
    .in_page_order())
}

enum Fallback {
    Relocked,
    Unsimplified,
}

/// The edges (between welded vertices) that the children of more than one group of
/// this level use: where neighbouring groups meet. Both ends of such an edge are
/// border vertices, so only those edges are looked up.
fn shared_edges(level_groups: &[Vec<u32>], keyed: &[Vec<u32>], border: &[bool]) -> FxHashSet<u64> {
    let mut first_user: FxHashMap<u64, u32> = FxHashMap::default();
    let mut shared = FxHashSet::default();
    for (g, members) in level_groups.iter().enumerate() {
        for &m in members {
            for (a, b) in triangle_edges(&keyed[m as usize]) {
                if a == b || !border[a as usize] || !border[b as usize] {
                    continue;
                }
                let key = edge_key(a, b);
                if *first_user.entry(key).or_insert(g as u32) != g as u32 {
                    shared.insert(key);
                }
            }
        }
    }
    shared
}

/// Whether `output` uses every shared edge the same net number of times in each
/// direction as `input` (both in global vertex ids): then any cut mixing this group's
/// children or output with its neighbours' closes up. The same rule as
/// [`crate::watertight`] applies to the packed asset, here on welded vertices.
fn seals_borders(
    input: &[u32],
    output: &[u32],
    remap: &[u32],
    border: &[bool],
    shared: &FxHashSet<u64>,
) -> bool {
    let mut net: FxHashMap<u64, i32> = FxHashMap::default();
    for (indices, sign) in [(input, 1), (output, -1)] {
        for (a, b) in triangle_edges(indices) {
            let (a, b) = (remap[a as usize], remap[b as usize]);
            if a == b || !border[a as usize] || !border[b as usize] {
                continue;
            }
            let key = edge_key(a, b);
            if shared.contains(&key) {
                *net.entry(key).or_default() += if a < b { sign } else { -sign };
            }
        }
    }
    net.values().all(|&n| n == 0)
}

/// Every corner (welded) of the group's triangles that have an edge on a shared
/// border: locked, those triangles cannot change, so neither can the border.
fn border_triangle_corners(
    indices: &[u32],
    remap: &[u32],
    border: &[bool],
    shared: &FxHashSet<u64>,
) -> FxHashSet<u32> {
    let mut corners = FxHashSet::default();
    for t in indices.chunks_exact(3) {
        let w = [t[0], t[1], t[2]].map(|v| remap[v as usize]);
        let on_border = (0..3).any(|k| {
            let (a, b) = (w[k], w[(k + 1) % 3]);
            a != b && border[a as usize] && border[b as usize] && shared.contains(&edge_key(a, b))
        });
        if on_border {
            corners.extend(w);
        }
    }
    corners
}

/// Vertices on an attribute seam: another vertex at the same position has a different
/// normal, UV or material. Permissive simplification may collapse across seams elsewhere
/// but must keep these, or textures and shading tear. Second: the vertices on a border
/// between two materials, which the modes that ignore seams must not move.
fn seam_vertices(mesh: &Mesh, remap: &[u32], slots: &[u32]) -> (Vec<bool>, Vec<bool>) {
    let mut differs = vec![false; remap.len()];
    let mut material_differs = vec![false; remap.len()];
    for (v, &r) in remap.iter().enumerate() {
        let r = r as usize;
        if r == v {
            continue;
        }
        if slots[v] != slots[r] {
            material_differs[r] = true;
        }
        if mesh.normals[v] != mesh.normals[r]
            || (mesh.has_uvs() && mesh.uvs[v] != mesh.uvs[r])
            || (mesh.has_colors() && mesh.colors[v] != mesh.colors[r])
            || slots[v] != slots[r]
        {
            differs[r] = true;
        }
    }
    (
        remap.iter().map(|&r| differs[r as usize]).collect(),
        remap
            .iter()
            .map(|&r| material_differs[r as usize])
            .collect(),
    )
}

/// The meshlets `split` makes of each material slot's triangles on their own, each with
/// its slot, in slot order.
fn meshlets_by_material(
    indices: &[u32],
    slots: &[u32],
    split: impl Fn(&[u32]) -> Vec<Vec<u32>>,
) -> Vec<(u32, Vec<u32>)> {
    by_material(indices, slots)
        .into_iter()
        .flat_map(|(material, triangles)| split(&triangles).into_iter().map(move |m| (material, m)))
        .collect()
}

/// The triangles of `indices` split by the material slot of their corners (which
/// agree: see [`Mesh::clean`]), in slot order; one list when there is one slot.
fn by_material(indices: &[u32], slots: &[u32]) -> Vec<(u32, Vec<u32>)> {
    let mut lists: std::collections::BTreeMap<u32, Vec<u32>> = Default::default();
    let first = indices.first().map_or(0, |&v| slots[v as usize]);
    if indices.iter().all(|&v| slots[v as usize] == first) {
        return vec![(first, indices.to_vec())];
    }
    for t in indices.chunks_exact(3) {
        lists
            .entry(slots[t[0] as usize])
            .or_default()
            .extend_from_slice(t);
    }
    lists.into_iter().collect()
}

fn sphere_of(positions: &[Vec3], indices: &[u32]) -> (Vec3, f32) {
    sphere_of_points(indices.iter().map(|&i| positions[i as usize]))
}

/// The group's LOD bounds: a sphere around the children's LOD spheres, so that the
/// projected error of a parent is never below a child's from any viewpoint, and
/// error = max(children) + own, which bounds the distance to LOD 0 and never decreases
/// toward the root.
fn group_lod(clusters: &[DagCluster], children: &[u32], own_error: f32) -> LodBounds {
    let mut sphere: Option<(Vec3, f32)> = None;
    let mut error = 0.0f32;
    for &c in children {
        let lod = clusters[c as usize].lod;
        let s = (lod.center, lod.radius);
        sphere = Some(match sphere {
            None => s,
            Some(acc) => merge_spheres(acc, s),
        });
        error = error.max(lod.error);
    }
    let (center, radius) = sphere.unwrap_or((Vec3::ZERO, 0.0));
    LodBounds {
        center,
        radius,
        error: error + own_error,
    }
}

impl Dag {
    /// Triangles and clusters per level, for summaries.
    pub fn level_stats(&self) -> Vec<(usize, usize)> {
        let mut stats = vec![(0usize, 0usize); self.level_count as usize];
        for c in &self.clusters {
            let s = &mut stats[c.level as usize];
            s.0 += c.triangle_count();
            s.1 += 1;
        }
        stats
    }

    /// The clusters with no parent.
    pub fn roots(&self) -> impl Iterator<Item = &DagCluster> {
        self.clusters.iter().filter(|c| c.parent_group == NO_GROUP)
    }

    /// The same DAG with its clusters in page order: the roots (in their order), then
    /// each group's children in group order; the groups' children renumbered.
    fn in_page_order(mut self) -> Self {
        let order: Vec<usize> = (self.clusters.iter().enumerate())
            .filter(|(_, c)| c.parent_group == NO_GROUP)
            .map(|(i, _)| i)
            .chain((self.groups.iter()).flat_map(|g| g.children.iter().map(|&c| c as usize)))
            .collect();
        assert_eq!(
            order.len(),
            self.clusters.len(),
            "every cluster is a root or the child of exactly one group"
        );
        let mut new_index = vec![0u32; order.len()];
        for (new, &old) in order.iter().enumerate() {
            new_index[old] = new as u32;
        }
        let mut old: Vec<Option<DagCluster>> = self.clusters.into_iter().map(Some).collect();
        self.clusters = order
            .iter()
            .map(|&i| old[i].take().expect("each cluster once"))
            .collect();
        for g in &mut self.groups {
            for c in &mut g.children {
                *c = new_index[*c as usize];
            }
        }
        self
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Two triangles of one group along a border edge (0, 1) shared with a neighbour:
    /// the output must keep using that edge once, in the same direction.
    #[test]
    fn a_result_that_drops_or_flips_a_shared_edge_does_not_seal() {
        let remap: Vec<u32> = (0..5).collect();
        let border = [true, true, false, false, true];
        let shared: FxHashSet<u64> = [edge_key(0, 1)].into_iter().collect();
        let input = [0, 1, 2, 0, 2, 3];
        let seal = |out: &[u32]| seals_borders(&input, out, &remap, &border, &shared);
        assert!(seal(&[0, 1, 3]));
        assert!(!seal(&[0, 2, 3]), "the shared edge is gone");
        assert!(!seal(&[1, 0, 3]), "the shared edge is reversed");
        assert!(!seal(&[0, 1, 3, 0, 1, 2]), "the shared edge is used twice");
        // An edge between border vertices that no neighbour uses may change.
        assert!(seal(&[0, 1, 3, 4, 0, 3]));
        let corners = border_triangle_corners(&input, &remap, &border, &shared);
        assert_eq!(corners, [0, 1, 2].into_iter().collect());
    }
}
