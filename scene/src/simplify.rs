//! Simplifying one group of clusters to about half its triangles without moving its
//! border, so that neighbouring groups still meet exactly at every level.
//!
//! A group that regular simplification cannot halve is pushed harder in the same build
//! iteration, as meshoptimizer's clusterlod does: first permissive mode (collapses
//! across attribute seams, seam vertices protected), then the group welded by position
//! (seams ignored, each output corner given the copy whose normal best fits its
//! triangle), then sloppy simplification with its error scaled up. Retrying the group
//! at a later level instead, with other neighbours, mixed levels and let some groups go
//! round for ever.

use glam::Vec3;
use meshopt::{SimplifyOptions, SimplifyVertex};

use crate::deviation::simplified_deviation;
use crate::mesh::{edge_key, triangle_edges};

/// A group counts as simplified when it lost at least this share of its triangles;
/// otherwise it is stuck.
const STUCK_RATIO: f32 = 0.85;
/// A mode's result is taken without trying the next mode when it holds at most this
/// share of the input: levels then shrink to at most about this ratio.
const GOOD_RATIO: f32 = 0.55;
/// Weight of each normal component against position error. With `ErrorClamped` the
/// attribute error cannot exceed the position error scale, so the weight only steers
/// which collapses happen first.
const NORMAL_WEIGHT: f32 = 0.5;
/// Weight of each vertex colour component (0..1), like a normal's: with `ErrorClamped`
/// it steers which collapses happen first, so a colour gradient keeps its vertices
/// longer than a flat patch.
const COLOR_WEIGHT: f32 = 0.5;
/// Weight of each UV component, in object units per UV unit ([`crate::uv_slide::texel_size`]):
/// a UV difference then counts as far as the texel moves on the surface, as the measured
/// slide does.
const UV_WEIGHT: f32 = 1.0;
/// Sloppy simplification ignores topology and attributes; its error estimate is scaled
/// up, as clusterlod does, so that such groups switch to their parent later.
pub const SLOPPY_ERROR_FACTOR: f32 = 2.0;
/// New folds (edges of more than two triangles) a result may add per 64 input
/// triangles, plus one. Collapses next to existing non-manifold edges almost always add
/// one, and near the root opposite sides of thin parts meet; refusing any fold left 21
/// roots on the beast mesh and 2 on the bunny and teapot. Measured on the test meshes:
/// 1 + 1 per 64 triangles (17 for a full group) is the smallest bound tried that ends
/// every one in at most 2 roots with halving levels; a fold closes the surface onto
/// itself, it does not open a crack, and its distance is measured like any other.
pub const FOLDS_PER_64_TRIANGLES: usize = 1;

/// How a group was simplified, for statistics.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Mode {
    /// Attribute-aware, seams kept: what almost every group needs.
    Regular,
    /// Collapses across attribute seams allowed, seam vertices protected: for a group
    /// whose seams leave regular mode too few collapses.
    Permissive,
    /// Simplified as if every attribute seam were welded: needed where nearly every
    /// vertex is on a seam (a faceted mesh), where the modes that keep seams are stuck.
    Welded,
    /// Topology and attributes ignored, error scaled by [`SLOPPY_ERROR_FACTOR`]: the
    /// last resort before a group is left for the next level.
    Sloppy,
}

impl Mode {
    /// Every mode, in the order a stuck group escalates.
    pub const ALL: [Mode; 4] = [Mode::Regular, Mode::Permissive, Mode::Welded, Mode::Sloppy];
}

/// One simplified group in the group's own (global) vertex ids.
pub struct Simplified {
    /// Three global vertex ids per output triangle.
    pub indices: Vec<u32>,
    /// Object-space error of this simplification alone, as meshoptimizer estimates it
    /// (scaled by [`SLOPPY_ERROR_FACTOR`] for sloppy results).
    pub error: f32,
    /// Measured distance from the output's triangles to the input's (see
    /// [`simplified_deviation`]).
    pub deviation: f32,
    /// The mode that gave this result, counted in the build's statistics.
    pub mode: Mode,
}

/// Per global vertex: is it on the group border (locked), and is it on an attribute
/// seam (protected in permissive mode)?
pub struct VertexFlags<'a> {
    /// Whether a global vertex is on the group's border: moving it would open a crack
    /// against the neighbouring group.
    pub locked: &'a (dyn Fn(u32) -> bool + Sync),
    /// Per global vertex, whether it lies on an attribute seam (several copies of one
    /// position).
    pub seam: &'a [bool],
    /// Per global vertex, its material slot (each vertex has one; see
    /// [`crate::mesh::Mesh::clean`]).
    pub materials: &'a [u32],
    /// Per global vertex, whether a copy of its position belongs to another material.
    /// Regular and permissive modes keep such a border as a seam; the welded and
    /// sloppy modes, which ignore seams, lock it.
    pub material_border: &'a [bool],
}

/// A mesh's vertex attributes, in its global vertex ids.
pub struct Attributes<'a> {
    /// One unit normal per vertex.
    pub normals: &'a [Vec3],
    /// One UV per vertex, or none for a mesh without UVs.
    pub uvs: &'a [[f32; 2]],
    /// One linear RGBA colour per vertex, or none for a mesh without vertex colours.
    pub colors: &'a [[f32; 4]],
    /// Object units per UV unit ([`crate::uv_slide::texel_size`]).
    pub texel: f32,
}

/// Simplifies `indices` (global vertex ids) to about half, taking only results that
/// `seals` accepts (given in global ids: the border the group shares is kept). Returns
/// `None` when no mode's accepted result removes 15% of the triangles (`STUCK_RATIO`).
///
/// Works on a compact copy of the group's vertices: meshoptimizer's cost is per vertex
/// of the buffer it is given, and a group is a tiny part of the mesh.
pub fn simplify_group(
    positions: &[Vec3],
    attributes: &Attributes<'_>,
    indices: &[u32],
    flags: &VertexFlags<'_>,
    seals: &dyn Fn(&[u32]) -> bool,
) -> Option<Simplified> {
    let crate::meshlets::Localised { globals, local } = crate::meshlets::localise(indices);
    let pos: Vec<Vec3> = globals.iter().map(|&g| positions[g as usize]).collect();
    let normals: Vec<Vec3> = globals
        .iter()
        .map(|&g| attributes.normals[g as usize])
        .collect();
    // What the attribute-aware modes weigh: the normal, then the UV and the colour
    // where there are any.
    let has_uvs = !attributes.uvs.is_empty();
    let has_colors = !attributes.colors.is_empty();
    let mut attrs: Vec<f32> = Vec::with_capacity(globals.len() * 9);
    for &g in &globals {
        let g = g as usize;
        attrs.extend_from_slice(&attributes.normals[g].to_array());
        if has_uvs {
            attrs.extend_from_slice(&attributes.uvs[g]);
        }
        if has_colors {
            attrs.extend_from_slice(&attributes.colors[g]);
        }
    }
    let mut weights = vec![NORMAL_WEIGHT; 3];
    if has_uvs {
        weights.extend([UV_WEIGHT * attributes.texel; 2]);
    }
    if has_colors {
        weights.extend([COLOR_WEIGHT; 4]);
    }
    // Welded ids for the fold check: seams must not count as separate edges.
    let weld = crate::mesh::position_remap(&pos);
    let mut locked: Vec<bool> = globals.iter().map(|&g| (flags.locked)(g)).collect();
    lock_lone_corners(&local, &weld, &mut locked);
    let slot: Vec<u32> = globals
        .iter()
        .map(|&g| flags.materials[g as usize])
        .collect();
    let several_materials = slot.iter().any(|&m| m != slot[0]);
    // What the modes that ignore seams lock: the group border, and the material
    // borders, which they would otherwise merge across.
    let hard_locked: Vec<bool> = globals
        .iter()
        .zip(&locked)
        .map(|(&g, &lock)| lock || flags.material_border[g as usize])
        .collect();
    // Positions welded only within a material, for the welded mode.
    let material_weld: std::borrow::Cow<[u32]> = match several_materials {
        true => weld_within_materials(&pos, &slot).into(),
        false => weld.as_slice().into(),
    };
    let locks: Vec<SimplifyVertex> = globals
        .iter()
        .zip(&locked)
        .map(|(&g, &lock)| {
            let mut f = SimplifyVertex::None;
            if lock {
                f |= SimplifyVertex::Lock;
            }
            if flags.seam[g as usize] {
                f |= SimplifyVertex::Protect;
            }
            f
        })
        .collect();
    let adapter = meshopt::VertexDataAdapter::new(bytemuck::cast_slice(&pos), 12, 0)
        .expect("Vec3 is 12 bytes");
    let triangles = indices.len() / 3;
    let target = (triangles / 2).max(1) * 3;
    let good = (triangles as f32 * GOOD_RATIO) as usize;
    let stuck = (triangles as f32 * STUCK_RATIO) as usize;
    let allowed_folds = 1 + triangles / 64 * FOLDS_PER_64_TRIANGLES;
    // The input's own folds, counted only when an output has any (most have none).
    let mut folds_before: Option<usize> = None;

    let mut best: Option<(Vec<u32>, f32, Mode)> = None;
    for mode in Mode::ALL {
        let mut error = 0.0f32;
        let out = match mode {
            Mode::Welded => {
                let weld = &material_weld;
                let welded: Vec<u32> = local.iter().map(|&v| weld[v as usize]).collect();
                if welded == local {
                    // No seam in the group: the same input regular mode had.
                    continue;
                }
                // A buffer of the welded vertices alone: meshoptimizer treats vertices
                // at one position as seams (or locks them) even when unreferenced.
                let crate::meshlets::Localised {
                    globals: reps,
                    local: compact,
                } = crate::meshlets::localise(&welded);
                let rep_pos: Vec<Vec3> = reps.iter().map(|&r| pos[r as usize]).collect();
                // Seams are gone once welded, so nothing is protected; the border stays.
                let border: Vec<SimplifyVertex> = reps
                    .iter()
                    .map(|&r| match hard_locked[r as usize] {
                        true => SimplifyVertex::Lock,
                        false => SimplifyVertex::None,
                    })
                    .collect();
                let rep_adapter =
                    meshopt::VertexDataAdapter::new(bytemuck::cast_slice(&rep_pos), 12, 0)
                        .expect("Vec3 is 12 bytes");
                let out = meshopt::simplify_with_locks(
                    &compact,
                    &rep_adapter,
                    &border,
                    target,
                    f32::MAX,
                    SimplifyOptions::ErrorAbsolute,
                    Some(&mut error),
                );
                let out: Vec<u32> = out.iter().map(|&c| reps[c as usize]).collect();
                unweld(&out, &pos, &normals, weld)
            }
            Mode::Regular | Mode::Permissive => {
                let mut options = SimplifyOptions::ErrorAbsolute | SimplifyOptions::ErrorClamped;
                if mode == Mode::Permissive {
                    options |= SimplifyOptions::Permissive;
                }
                meshopt::simplify_with_attributes_and_locks(
                    &local,
                    &adapter,
                    &attrs,
                    &weights,
                    4 * weights.len(),
                    &locks,
                    target,
                    f32::MAX,
                    options,
                    Some(&mut error),
                )
            }
            Mode::Sloppy => {
                let hard_locks: Vec<SimplifyVertex> = hard_locked
                    .iter()
                    .map(|&lock| match lock {
                        true => SimplifyVertex::Lock,
                        false => SimplifyVertex::None,
                    })
                    .collect();
                let out = meshopt::simplify_sloppy_with_locks(
                    &local,
                    &adapter,
                    &hard_locks,
                    target,
                    f32::MAX,
                    Some(&mut error),
                );
                // Relative to the piece's scale; made absolute and counted more heavily.
                error *= meshopt::simplify_scale(&adapter) * SLOPPY_ERROR_FACTOR;
                out
            }
        };
        let count = out.len() / 3;
        if out.is_empty() || count > stuck {
            continue;
        }
        // A triangle whose corners belong to two materials has no material to draw it
        // in: the result is not taken (the locks above make this rare).
        if several_materials
            && out.chunks_exact(3).any(|t| {
                slot[t[0] as usize] != slot[t[1] as usize]
                    || slot[t[0] as usize] != slot[t[2] as usize]
            })
        {
            continue;
        }
        let folds = overused_edges(&out, &weld);
        if folds > 0 {
            let before = *folds_before.get_or_insert_with(|| overused_edges(&local, &weld));
            if folds > before + allowed_folds {
                continue;
            }
        }
        if best.as_ref().is_some_and(|(b, _, _)| out.len() >= b.len()) {
            continue;
        }
        // A result that moves the border is no result: the next mode may keep it.
        let global: Vec<u32> = out.iter().map(|&l| globals[l as usize]).collect();
        if !seals(&global) {
            continue;
        }
        best = Some((out, error, mode));
        if count <= good {
            break;
        }
    }
    let (out, error, mode) = best?;
    Some(Simplified {
        deviation: simplified_deviation(&pos, &local, &out),
        indices: out.iter().map(|&l| globals[l as usize]).collect(),
        error,
        mode,
    })
}

/// For every vertex, the first vertex with a bit-identical position and the same
/// material slot: [`crate::mesh::position_remap`] that never joins two materials.
fn weld_within_materials(pos: &[Vec3], slot: &[u32]) -> Vec<u32> {
    let mut map = rustc_hash::FxHashMap::default();
    pos.iter()
        .zip(slot)
        .enumerate()
        .map(|(i, (p, &m))| {
            let key = ((*p + Vec3::ZERO).to_array().map(f32::to_bits), m);
            *map.entry(key).or_insert(i as u32)
        })
        .collect()
}

/// Gives each corner of the welded triangles `out` the copy of its position whose normal
/// is closest to its triangle's face normal, so that a faceted piece keeps facets that
/// face the right way after its seams were ignored.
fn unweld(out: &[u32], pos: &[Vec3], normals: &[Vec3], weld: &[u32]) -> Vec<u32> {
    // Copies of each welded vertex, in CSR form.
    let mut start = vec![0u32; weld.len() + 1];
    for &w in weld {
        start[w as usize + 1] += 1;
    }
    for i in 0..weld.len() {
        start[i + 1] += start[i];
    }
    let mut fill = start.clone();
    let mut copies = vec![0u32; weld.len()];
    for (v, &w) in weld.iter().enumerate() {
        copies[fill[w as usize] as usize] = v as u32;
        fill[w as usize] += 1;
    }
    let mut result = Vec::with_capacity(out.len());
    for t in out.chunks_exact(3) {
        let [a, b, c] = [t[0], t[1], t[2]].map(|v| pos[v as usize]);
        let face = (b - a).cross(c - a).normalize_or_zero();
        for &w in t {
            let run = &copies[start[w as usize] as usize..start[w as usize + 1] as usize];
            let best = run
                .iter()
                .copied()
                .max_by(|&x, &y| {
                    normals[x as usize]
                        .dot(face)
                        .total_cmp(&normals[y as usize].dot(face))
                })
                .unwrap_or(w);
            result.push(best);
        }
    }
    result
}

/// Locks the other corners of every triangle at a locked vertex that has at most two
/// triangles in the piece. Locking keeps a vertex in place but not its triangles:
/// collapsing one of the other corners onto another removes the triangle, and when the
/// locked vertex loses all of them it leaves the piece and the edges it shares with the
/// neighbouring group open a crack. Found by the crack check on the bunny grouped with
/// `partition_clusters`: a vertex with one triangle in its group, then one with two
/// triangles that met only at it.
fn lock_lone_corners(indices: &[u32], weld: &[u32], locked: &mut [bool]) {
    let mut uses = vec![0u32; weld.len()];
    for &v in indices {
        uses[weld[v as usize] as usize] += 1;
    }
    let lone: Vec<[u32; 3]> = indices
        .chunks_exact(3)
        .map(|t| [t[0], t[1], t[2]])
        .filter(|t| {
            t.iter()
                .any(|&v| locked[v as usize] && uses[weld[v as usize] as usize] <= 2)
        })
        .collect();
    for t in lone {
        for v in t {
            locked[v as usize] = true;
        }
    }
    // Copies of one position are locked together.
    let mut welded_locked = vec![false; weld.len()];
    for (v, &l) in locked.iter().enumerate() {
        welded_locked[weld[v] as usize] |= l;
    }
    for (v, l) in locked.iter_mut().enumerate() {
        *l = welded_locked[weld[v] as usize];
    }
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn unwelding_gives_each_corner_the_copy_facing_its_triangle() {
        // A ridge: two copies of each of the points 0 and 1, one per side; the copies
        // 2 and 3 have normals facing down (-Z), 0 and 1 up (+Z); 4 and 5 are the tips.
        let pos = [
            Vec3::ZERO,
            Vec3::X,
            Vec3::ZERO,
            Vec3::X,
            Vec3::new(0.5, 1.0, 0.0),
            Vec3::new(0.5, -1.0, 0.0),
        ];
        let normals = [Vec3::Z, Vec3::Z, -Vec3::Z, -Vec3::Z, Vec3::Z, -Vec3::Z];
        let weld = [0, 1, 0, 1, 4, 5];
        // Welded triangles: one facing +Z (0, 1, 4), one facing -Z (0, 1, 5).
        let out = unweld(&[0, 1, 4, 0, 1, 5], &pos, &normals, &weld);
        assert_eq!(out, vec![0, 1, 4, 2, 3, 5]);
    }
}
