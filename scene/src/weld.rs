//! Welding positions that are meant to be one point but were written a little apart.
//!
//! Exporters compute a vertex once per face, per seam copy or per pole slot, so one
//! point of the surface arrives as several positions a few units in the last place
//! apart (a UV sphere written at full precision has seam and pole copies 1e-16 apart).
//! The builder joins vertices by exact position, so such copies would be separate
//! points: the mesh would be open there, border locking would miss them, and once the
//! asset's position grid snaps them together the cut would crack. Welding them to one
//! position first makes the surface connected the way it looks.

use glam::Vec3;
use rustc_hash::FxHashMap;

/// Default weld distance relative to the mesh's extent (its largest bounding-box side):
/// about 16 units in the last place of the largest coordinate of a mesh centred on the
/// origin, enough for recomputed exporter positions, and 60 times finer than the finest
/// position grid an asset stores (24 bits), so no detail the asset could keep is lost.
pub const DEFAULT_WELD_TOLERANCE: f32 = 1e-6;

/// Largest relative weld distance an option may ask for: beyond it whole features of
/// an ordinary mesh would be merged.
pub const MAX_WELD_TOLERANCE: f32 = 1e-2;

/// Moves every vertex within `distance` of an earlier kept vertex onto that vertex's
/// position; returns how many moved. A vertex joins the lowest-numbered kept vertex in
/// reach, and kept vertices are more than `distance` apart, so the result does not
/// depend on chains of near points and is the same on every run.
///
/// Only positions change: copies keep their own normals and UVs (they become seams,
/// which the builder already joins by position).
pub fn weld_positions(positions: &mut [Vec3], distance: f32) -> usize {
    if distance.is_nan() || distance <= 0.0 || positions.is_empty() {
        return 0;
    }
    let (min, _) = positions.iter().fold(
        (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY)),
        |(lo, hi), &p| (lo.min(p), hi.max(p)),
    );
    // Cells of twice the distance: a point's neighbours in reach lie in its own cell or,
    // per axis, the one on its nearer side, so 8 cells are searched instead of 27.
    let size = 2.0 * distance as f64;
    let scaled = |p: Vec3| [0, 1, 2].map(|k| (p[k] as f64 - min[k] as f64) / size);
    // Kept vertices per cell, as linked lists through `next` (oldest first).
    // First and last kept vertex of each cell, in one table sized for every vertex
    // having a cell of its own (the usual case at a tolerance this small).
    let mut cells: FxHashMap<(i64, i64, i64), (u32, u32)> =
        FxHashMap::with_capacity_and_hasher(positions.len(), Default::default());
    let mut next: Vec<u32> = vec![u32::MAX; positions.len()];
    // In f64: the squares of tiny distances underflow f32.
    let within = |a: Vec3, b: Vec3| a.as_dvec3().distance(b.as_dvec3()) <= distance as f64;
    let mut moved = 0;
    for v in 0..positions.len() {
        let p = positions[v];
        let s = scaled(p);
        let cell = s.map(|c| c.floor() as i64);
        let side = [0, 1, 2].map(|k| if s[k] - (cell[k] as f64) < 0.5 { -1 } else { 1 });
        let mut best: Option<u32> = None;
        for corner in 0..8 {
            let c = [0, 1, 2].map(|k| cell[k] + side[k] * ((corner >> k) & 1));
            let mut k = cells
                .get(&(c[0], c[1], c[2]))
                .map_or(u32::MAX, |&(head, _)| head);
            while k != u32::MAX {
                if best.is_none_or(|b| k < b) && within(positions[k as usize], p) {
                    best = Some(k);
                }
                k = next[k as usize];
            }
        }
        match best {
            Some(k) => {
                if positions[k as usize] != p {
                    positions[v] = positions[k as usize];
                    moved += 1;
                }
            }
            None => {
                let (_, tail) = cells
                    .entry((cell[0], cell[1], cell[2]))
                    .or_insert((v as u32, u32::MAX));
                if *tail != u32::MAX {
                    next[*tail as usize] = v as u32;
                }
                *tail = v as u32;
            }
        }
    }
    moved
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn near_copies_join_the_first_and_far_points_stay() {
        let mut p = vec![
            Vec3::new(1.0, 0.0, 0.0),
            Vec3::new(1.0, 1e-16, 0.0),
            Vec3::new(2.0, 0.0, 0.0),
            Vec3::new(1.0 + 1e-7, 0.0, -1e-7),
            Vec3::new(1.0 + 3e-6, 0.0, 0.0),
        ];
        assert_eq!(weld_positions(&mut p, 1e-6), 2);
        assert_eq!(p[1], p[0]);
        assert_eq!(p[3], p[0]);
        assert_eq!(p[2], Vec3::new(2.0, 0.0, 0.0));
        assert_ne!(p[4], p[0]);
    }

    /// A point in reach of two kept points joins the lower-numbered one, and a point
    /// that joined is not itself a target: no chains.
    #[test]
    fn no_chains() {
        let mut p = vec![
            Vec3::ZERO,
            Vec3::new(0.9, 0.0, 0.0),
            Vec3::new(1.8, 0.0, 0.0),
            Vec3::new(2.0, 0.0, 0.0),
        ];
        weld_positions(&mut p, 1.0);
        assert_eq!(p[1], Vec3::ZERO);
        assert_eq!(p[2], Vec3::new(1.8, 0.0, 0.0));
        assert_eq!(p[3], Vec3::new(1.8, 0.0, 0.0));
    }

    #[test]
    fn zero_distance_moves_nothing() {
        let mut p = vec![Vec3::ZERO, Vec3::splat(1e-30)];
        assert_eq!(weld_positions(&mut p, 0.0), 0);
        assert_eq!(p[1], Vec3::splat(1e-30));
    }
}
