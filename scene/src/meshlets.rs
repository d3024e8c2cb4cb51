//! Splitting triangles into meshlets: whole meshes in parallel chunks, groups on their
//! own vertices.

use glam::Vec3;
use rayon::prelude::*;

use crate::greedy_meshlets::{SeedOrder, grow_meshlets};

/// The asset format's limits, which the splitter fills meshlets up to (they live with the
/// format, so that reading assets needs no builder).
pub use crate::asset::format::{
    MAX_MESHLET_TRIANGLES as MAX_TRIANGLES, MAX_MESHLET_VERTICES as MAX_VERTICES,
};

/// Triangles per independently split chunk of a large mesh. Fixed, not derived from the
/// thread count, so the meshlets are the same on every machine; large enough that the
/// partly filled meshlet at the end of each chunk costs well under 1% of fill.
pub const CHUNK_TRIANGLES: usize = 1 << 15;

/// Splits a whole mesh into meshlets, in parallel: the triangles are put in Morton order
/// of their centroids and cut into chunks of [`CHUNK_TRIANGLES`], which are spatially
/// compact, and each chunk is split on its own. `weld`: see [`split_into_meshlets`].
pub fn split_mesh_into_meshlets(
    positions: &[Vec3],
    indices: &[u32],
    weld: Option<&[u32]>,
) -> Vec<Vec<u32>> {
    if indices.len() <= CHUNK_TRIANGLES * 3 {
        return split_into_meshlets(positions, indices, weld);
    }
    let ordered = morton_ordered(positions, indices);
    let chunks: Vec<Vec<Vec<u32>>> = ordered
        .par_chunks(CHUNK_TRIANGLES * 3)
        .map(|chunk| {
            // Already along the curve: the chunk's own order seeds its meshlets.
            split_compact(positions, chunk, weld, SeedOrder::AsGiven)
        })
        .collect();
    chunks.into_iter().flatten().collect()
}

/// The triangle list reordered along a Morton curve through the triangles' centroids
/// (over the mesh bounds); ties keep input order.
fn morton_ordered(positions: &[Vec3], indices: &[u32]) -> Vec<u32> {
    let grid = MortonGrid::around(positions.iter().copied());
    let mut keyed: Vec<(u32, u32)> = indices
        .par_chunks_exact(3)
        .enumerate()
        .map(|(i, t)| {
            let centroid =
                (positions[t[0] as usize] + positions[t[1] as usize] + positions[t[2] as usize])
                    / 3.0;
            (grid.code(centroid), i as u32)
        })
        .collect();
    keyed.par_sort_unstable();
    keyed
        .iter()
        .flat_map(|&(_, t)| {
            let t = t as usize * 3;
            [indices[t], indices[t + 1], indices[t + 2]]
        })
        .collect()
}

/// Morton codes of points in a box: 10 bits per axis over its longest side.
pub(crate) struct MortonGrid {
    lo: Vec3,
    scale: f32,
}

impl MortonGrid {
    /// The grid over the bounds of `points`.
    pub(crate) fn around(points: impl Iterator<Item = Vec3>) -> Self {
        let (lo, hi) = points.fold((Vec3::MAX, Vec3::MIN), |(lo, hi), p| (lo.min(p), hi.max(p)));
        let extent = (hi - lo).max_element();
        let scale = if extent > 0.0 { 1023.0 / extent } else { 0.0 };
        Self { lo, scale }
    }

    pub(crate) fn code(&self, p: Vec3) -> u32 {
        let q = ((p - self.lo) * self.scale).clamp(Vec3::ZERO, Vec3::splat(1023.0));
        morton3(q.x as u32, q.y as u32, q.z as u32)
    }
}

/// Interleaves the low 10 bits of three coordinates into a 30-bit Morton code.
fn morton3(x: u32, y: u32, z: u32) -> u32 {
    fn spread(v: u32) -> u32 {
        let mut v = v & 0x3ff;
        v = (v | (v << 16)) & 0x0300_00ff;
        v = (v | (v << 8)) & 0x0300_f00f;
        v = (v | (v << 4)) & 0x030c_30c3;
        (v | (v << 2)) & 0x0924_9249
    }
    spread(x) | (spread(y) << 1) | (spread(z) << 2)
}

/// Splits an indexed triangle list into meshlets (see [`crate::greedy_meshlets`]); each
/// returned list indexes `positions` like the input does. `weld`, where the mesh has
/// attribute seams, maps each vertex to one at the same position.
pub fn split_into_meshlets(
    positions: &[Vec3],
    indices: &[u32],
    weld: Option<&[u32]>,
) -> Vec<Vec<u32>> {
    if indices.is_empty() {
        return Vec::new();
    }
    // The splitter's per-vertex arrays are the size of the buffer it is handed; a group
    // of a large mesh touches a few hundred vertices, so hand it a compact copy.
    if indices.len() * 4 < positions.len() {
        return split_compact(positions, indices, weld, SeedOrder::Morton);
    }
    grow_meshlets(
        positions,
        indices,
        weld,
        MAX_VERTICES,
        MAX_TRIANGLES,
        SeedOrder::Morton,
    )
}

/// [`grow_meshlets`] on a compact copy of the vertices `indices` use.
fn split_compact(
    positions: &[Vec3],
    indices: &[u32],
    weld: Option<&[u32]>,
    seeds: SeedOrder,
) -> Vec<Vec<u32>> {
    let Localised { globals, local } = localise(indices);
    let compact: Vec<Vec3> = globals.iter().map(|&g| positions[g as usize]).collect();
    // The weld in local ids: each local vertex maps to the first local vertex welded to
    // the same one.
    let local_weld: Option<Vec<u32>> = weld.map(|weld| {
        let mut first: rustc_hash::FxHashMap<u32, u32> =
            rustc_hash::FxHashMap::with_capacity_and_hasher(globals.len(), Default::default());
        (0..globals.len() as u32)
            .map(|l| *first.entry(weld[globals[l as usize] as usize]).or_insert(l))
            .collect()
    });
    grow_meshlets(
        &compact,
        &local,
        local_weld.as_deref(),
        MAX_VERTICES,
        MAX_TRIANGLES,
        seeds,
    )
    .into_iter()
    .map(|m| m.into_iter().map(|l| globals[l as usize]).collect())
    .collect()
}

/// A triangle list re-indexed over only the vertices it uses.
pub(crate) struct Localised {
    /// Mesh-wide index of each local vertex, in first-use order.
    pub globals: Vec<u32>,
    /// The triangle list in local indices.
    pub local: Vec<u32>,
}

/// Re-indexes `indices` over the vertices they use, so meshoptimizer works on arrays the
/// size of the piece rather than of the whole mesh. First-use order keeps it deterministic.
pub(crate) fn localise(indices: &[u32]) -> Localised {
    let mut local_of: rustc_hash::FxHashMap<u32, u32> =
        rustc_hash::FxHashMap::with_capacity_and_hasher(indices.len() / 2, Default::default());
    let mut globals: Vec<u32> = Vec::with_capacity(indices.len() / 2);
    let local = indices
        .iter()
        .map(|&g| {
            *local_of.entry(g).or_insert_with(|| {
                globals.push(g);
                (globals.len() - 1) as u32
            })
        })
        .collect();
    Localised { globals, local }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn morton_code_interleaves_axes() {
        assert_eq!(morton3(1, 0, 0), 0b001);
        assert_eq!(morton3(0, 1, 0), 0b010);
        assert_eq!(morton3(0, 0, 1), 0b100);
        assert_eq!(morton3(1023, 1023, 1023), (1 << 30) - 1);
        assert_eq!(morton3(2, 0, 0), 0b001_000);
    }

    #[test]
    fn chunked_split_keeps_every_triangle_once() {
        let mesh = crate::procedural_mesh(48);
        let meshlets = split_mesh_into_meshlets(&mesh.positions, &mesh.indices, None);
        let mut seen: Vec<[u32; 3]> = meshlets
            .iter()
            .flat_map(|m| m.chunks_exact(3).map(|t| canonical([t[0], t[1], t[2]])))
            .collect();
        let mut input: Vec<[u32; 3]> = mesh
            .indices
            .chunks_exact(3)
            .map(|t| canonical([t[0], t[1], t[2]]))
            .collect();
        assert!(
            input.len() > CHUNK_TRIANGLES,
            "the test mesh must span several chunks"
        );
        seen.sort_unstable();
        input.sort_unstable();
        assert_eq!(seen, input);
        assert!(meshlets.iter().all(|m| m.len() / 3 <= MAX_TRIANGLES));
    }

    /// A triangle rotated to start at its smallest index, keeping its winding.
    fn canonical(t: [u32; 3]) -> [u32; 3] {
        let r = (0..3).min_by_key(|&i| t[i]).unwrap();
        [t[r], t[(r + 1) % 3], t[(r + 2) % 3]]
    }
}
