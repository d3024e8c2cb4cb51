//! The in-memory triangle mesh every loader produces and the builder consumes, and the
//! checks that turn untrusted input into a mesh the builder can rely on.

use glam::Vec3;

use crate::error::SceneError;

/// Most triangles one asset may hold. The payload is addressed with 32-bit word offsets
/// and the whole DAG holds about twice the input triangles at a few words each, so
/// 2^25 input triangles keeps every offset far inside `u32` with room for bad cases.
pub const MAX_TRIANGLES: u64 = 1 << 25;
/// Most vertices one input mesh may hold (same reasoning as [`MAX_TRIANGLES`]).
pub const MAX_VERTICES: u64 = 1 << 26;

/// Largest absolute coordinate a mesh may have. Bounding spheres square distances in
/// `f32` (which overflows past about 1.8e19) and the grid decodes `origin + q · step`;
/// at 1e16 every square, sum and sphere merge stays far inside the `f32` range.
pub const MAX_COORDINATE: f32 = 1e16;

/// The smallest mesh extent: the finest position grid (2^24 cells a side) over it still
/// has a step that is a normal `f32` (a denormal step decodes every vertex to the
/// grid's origin), with a margin for the builder's error arithmetic.
pub const MIN_EXTENT: f32 = 1e-30;

/// Most material slots one mesh may use (the asset format's limit).
pub use crate::asset::format::MAX_MATERIALS;

/// An indexed triangle mesh with per-vertex normals and optional texture coordinates.
///
/// Vertices on UV seams or hard edges appear several times with the same position; the
/// builder treats such copies as one point for adjacency, so seams never split groups.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Mesh {
    /// Where the mesh came from (a file path or a generator name), quoted in errors.
    pub source: String,
    /// Vertex positions, in the source's units.
    pub positions: Vec<Vec3>,
    /// Unit normals, one per position.
    pub normals: Vec<Vec3>,
    /// Texture coordinates, one per position, or empty when the source has none.
    pub uvs: Vec<[f32; 2]>,
    /// Vertex colours (glTF's `COLOR_0`), linear RGBA in 0..1, one per position, or empty
    /// when the source has none. They multiply the material's base colour and alpha.
    pub colors: Vec<[f32; 4]>,
    /// Three indices per triangle, counter-clockwise front faces.
    pub indices: Vec<u32>,
    /// Each triangle's material slot (below [`MAX_MATERIALS`]), or empty when every
    /// triangle has slot 0. A slot is the mesh's own: whoever places the mesh maps its
    /// slots to materials (a glTF mesh's primitives each take one). Meshlets never
    /// straddle two slots, and simplification keeps the borders between them, so a
    /// coarse level draws each material where the full mesh does.
    pub materials: Vec<u32>,
}

/// What [`Mesh::clean`] changed, for the bake summary.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct CleanReport {
    /// Triangles that repeated a vertex or had zero area (after welding); dropped
    /// before building.
    pub dropped_degenerate: usize,
    /// Triangles with the same three points in the same winding as an earlier one
    /// (after welding): drawn twice they only z-fight, and no simplification can halve
    /// a stack of identical faces, so only the first is kept.
    pub dropped_duplicate: usize,
    /// Vertices moved onto a near vertex by welding (see [`crate::weld`]).
    pub welded_vertices: usize,
}

impl Mesh {
    /// Triangles of the mesh.
    pub fn triangle_count(&self) -> usize {
        self.indices.len() / 3
    }

    /// Whether the mesh has texture coordinates, which the asset then stores.
    pub fn has_uvs(&self) -> bool {
        !self.uvs.is_empty()
    }

    /// Whether the mesh has vertex colours, which the asset then stores.
    pub fn has_colors(&self) -> bool {
        !self.colors.is_empty()
    }

    /// Material slots the mesh uses: one past the largest slot of a triangle (1 when
    /// [`Self::materials`] is empty).
    pub fn material_count(&self) -> u32 {
        self.materials.iter().max().map_or(1, |&m| m + 1)
    }

    /// Each vertex's material slot. After [`Self::clean`] no vertex is shared by two
    /// slots, so this is well defined; vertices no triangle uses get slot 0.
    pub fn vertex_materials(&self) -> Vec<u32> {
        let mut slot = vec![0u32; self.positions.len()];
        if !self.materials.is_empty() {
            for (t, corners) in self.indices.chunks_exact(3).enumerate() {
                for &v in corners {
                    slot[v as usize] = self.materials[t];
                }
            }
        }
        slot
    }

    /// Refuses counts beyond the asset format's limits before any large allocation.
    pub fn check_limits(source: &str, vertices: u64, triangles: u64) -> Result<(), SceneError> {
        for (what, count, limit) in [
            ("triangles", triangles, MAX_TRIANGLES),
            ("vertices", vertices, MAX_VERTICES),
        ] {
            if count > limit {
                return Err(SceneError::TooLarge {
                    source_name: source.to_owned(),
                    what,
                    count,
                    limit,
                });
            }
        }
        Ok(())
    }

    /// [`Mesh::clean_with`] at the default weld distance
    /// ([`crate::weld::DEFAULT_WELD_TOLERANCE`] of the extent).
    pub fn clean(&mut self) -> Result<CleanReport, SceneError> {
        self.clean_with(crate::weld::DEFAULT_WELD_TOLERANCE)
    }

    /// Validates the mesh, welds positions within `weld_tolerance` × its extent (the
    /// largest bounding-box side; 0 joins only identical positions), then drops
    /// degenerate and duplicate triangles, so that the builder only ever sees finite
    /// positions, in-range indices, and distinct triangles with area.
    ///
    /// Errors: empty mesh, non-finite position, index out of range, attribute arrays of
    /// the wrong length, counts beyond the format's limits.
    pub fn clean_with(&mut self, weld_tolerance: f32) -> Result<CleanReport, SceneError> {
        let n = self.positions.len();
        if !self.indices.len().is_multiple_of(3) {
            return Err(SceneError::AttributeMismatch {
                source_name: self.source.clone(),
                vertex_count: n,
                detail: format!(
                    "{} indices is not a whole number of triangles",
                    self.indices.len()
                ),
            });
        }
        Self::check_limits(&self.source, n as u64, self.triangle_count() as u64)?;
        if self.normals.len() != n && !self.normals.is_empty() {
            return Err(SceneError::AttributeMismatch {
                source_name: self.source.clone(),
                vertex_count: n,
                detail: format!("{} normals", self.normals.len()),
            });
        }
        if self.uvs.len() != n && !self.uvs.is_empty() {
            return Err(SceneError::AttributeMismatch {
                source_name: self.source.clone(),
                vertex_count: n,
                detail: format!("{} texture coordinates", self.uvs.len()),
            });
        }
        if self.colors.len() != n && !self.colors.is_empty() {
            return Err(SceneError::AttributeMismatch {
                source_name: self.source.clone(),
                vertex_count: n,
                detail: format!("{} vertex colours", self.colors.len()),
            });
        }
        if !self.materials.is_empty() && self.materials.len() != self.triangle_count() {
            return Err(SceneError::AttributeMismatch {
                source_name: self.source.clone(),
                vertex_count: n,
                detail: format!(
                    "{} material slots for {} triangles",
                    self.materials.len(),
                    self.triangle_count()
                ),
            });
        }
        if let Some(triangle) = self.materials.iter().position(|&m| m >= MAX_MATERIALS) {
            return Err(SceneError::TooManyMaterials {
                source_name: self.source.clone(),
                triangle,
                slot: self.materials[triangle],
                limit: MAX_MATERIALS,
            });
        }
        if let Some(vertex) = self.positions.iter().position(|p| !p.is_finite()) {
            return Err(SceneError::NonFinitePosition {
                source_name: self.source.clone(),
                vertex,
                position: self.positions[vertex].to_array(),
            });
        }
        if let Some(vertex) = self
            .uvs
            .iter()
            .position(|t| !(t[0].is_finite() && t[1].is_finite()))
        {
            let t = self.uvs[vertex];
            return Err(SceneError::NonFiniteAttribute {
                source_name: self.source.clone(),
                location: format!("vertex {vertex}"),
                attribute: "texture coordinate".into(),
                value: if t[0].is_finite() { t[1] } else { t[0] },
            });
        }
        if let Some(vertex) = self
            .colors
            .iter()
            .position(|c| !c.iter().all(|v| v.is_finite()))
        {
            let c = self.colors[vertex];
            return Err(SceneError::NonFiniteAttribute {
                source_name: self.source.clone(),
                location: format!("vertex {vertex}"),
                attribute: "vertex colour".into(),
                value: c.into_iter().find(|v| !v.is_finite()).unwrap_or(f32::NAN),
            });
        }
        if let Some(vertex) = self
            .positions
            .iter()
            .position(|p| p.abs().max_element() > MAX_COORDINATE)
        {
            return Err(SceneError::CoordinateRange {
                source_name: self.source.clone(),
                vertex,
                position: self.positions[vertex].to_array(),
                limit: MAX_COORDINATE,
            });
        }
        let (lo, hi) = self.positions.iter().fold(
            (Vec3::splat(f32::MAX), Vec3::splat(f32::MIN)),
            |(lo, hi), &p| (lo.min(p), hi.max(p)),
        );
        let extent = (hi - lo).max_element();
        if n > 0 && extent > 0.0 && extent < MIN_EXTENT {
            return Err(SceneError::ExtentTooSmall {
                source_name: self.source.clone(),
                extent,
                limit: MIN_EXTENT,
            });
        }
        for (i, &index) in self.indices.iter().enumerate() {
            if index as usize >= n {
                return Err(SceneError::IndexOutOfRange {
                    source_name: self.source.clone(),
                    triangle: i / 3,
                    index,
                    vertex_count: n,
                });
            }
        }
        let (min, max) = self.bounds();
        let welded_vertices = crate::weld::weld_positions(
            &mut self.positions,
            weld_tolerance * (max - min).max_element(),
        );
        let before = self.triangle_count();
        let positions = &self.positions;
        let unit = unit_scale(positions);
        let point = position_remap(positions);
        // Sized for every triangle up front, and keyed by the three points packed into
        // one integer: FxHash mixes an integer well, where an array's bytes hashed in
        // turn clustered and made this loop a third of cleaning.
        let mut seen = rustc_hash::FxHashSet::with_capacity_and_hasher(
            self.indices.len() / 3,
            Default::default(),
        );
        let mut dropped_duplicate = 0;
        let mut kept = Vec::with_capacity(self.indices.len());
        let mut kept_materials = Vec::with_capacity(self.materials.len());
        for (i, t) in self.indices.chunks_exact(3).enumerate() {
            let (a, b, c) = (t[0], t[1], t[2]);
            if a == b || b == c || a == c {
                continue;
            }
            let (pa, pb, pc) = (
                positions[a as usize],
                positions[b as usize],
                positions[c as usize],
            );
            // Exact zero area: repeated positions or collinear points. A relative threshold
            // would drop legitimate slivers of dense scans. At unit scale, so that whether a
            // sliver's area underflows to zero does not depend on the mesh's size.
            if ((pb - pa) * unit).cross((pc - pa) * unit) == Vec3::ZERO {
                continue;
            }
            // The same points in the same winding, whichever corner comes first.
            let p = [a, b, c].map(|v| point[v as usize]);
            let r = (0..3).min_by_key(|&k| p[k]).unwrap_or(0);
            let key =
                p[r] as u128 | (p[(r + 1) % 3] as u128) << 32 | (p[(r + 2) % 3] as u128) << 64;
            if !seen.insert(key) {
                dropped_duplicate += 1;
                continue;
            }
            kept.extend_from_slice(t);
            if let Some(&m) = self.materials.get(i) {
                kept_materials.push(m);
            }
        }
        self.indices = kept;
        self.materials = kept_materials;
        let report = CleanReport {
            dropped_degenerate: before - self.triangle_count() - dropped_duplicate,
            dropped_duplicate,
            welded_vertices,
        };
        if self.indices.is_empty() {
            let detail = if before == 0 {
                String::new()
            } else {
                format!(" left after dropping {before} degenerate ones")
            };
            return Err(SceneError::EmptyMesh {
                source_name: self.source.clone(),
                detail,
            });
        }
        if self.normals.len() != n || self.normals.iter().any(|v| !v.is_finite()) {
            self.normals.clear();
            self.split_shared_vertices();
            self.generate_normals();
        } else {
            for v in &mut self.normals {
                *v = v.normalize_or(Vec3::Z);
            }
            self.split_shared_vertices();
        }
        Ok(report)
    }

    /// Gives every material slot its own copies of the vertices its triangles share
    /// with another slot's, so that each vertex has one slot: the border between two
    /// materials becomes a seam, which simplification keeps like a UV seam, and a
    /// meshlet's vertices all belong to its slot.
    fn split_shared_vertices(&mut self) {
        if self.materials.is_empty() {
            return;
        }
        let mut owner = vec![u32::MAX; self.positions.len()];
        let mut copies = rustc_hash::FxHashMap::<(u32, u32), u32>::default();
        for (t, corners) in self.indices.chunks_exact_mut(3).enumerate() {
            let slot = self.materials[t];
            for v in corners {
                let o = &mut owner[*v as usize];
                if *o == u32::MAX {
                    *o = slot;
                } else if *o != slot {
                    let source = *v as usize;
                    *v = *copies.entry((*v, slot)).or_insert_with(|| {
                        self.positions.push(self.positions[source]);
                        if !self.normals.is_empty() {
                            self.normals.push(self.normals[source]);
                        }
                        if !self.uvs.is_empty() {
                            self.uvs.push(self.uvs[source]);
                        }
                        if !self.colors.is_empty() {
                            self.colors.push(self.colors[source]);
                        }
                        (self.positions.len() - 1) as u32
                    });
                }
            }
        }
    }

    /// Area-weighted smooth normals. Copies of one position (seams) are accumulated
    /// together so that seams stay invisible in shading.
    pub fn generate_normals(&mut self) {
        let remap = position_remap(&self.positions);
        let mut acc = vec![Vec3::ZERO; self.positions.len()];
        // At unit scale: on a mesh scaled to 1e-10 the areas' squares underflow.
        let unit = unit_scale(&self.positions);
        for t in self.indices.chunks_exact(3) {
            let [a, b, c] = [t[0], t[1], t[2]].map(|i| self.positions[i as usize] * unit);
            // Unnormalised cross product = area weighting.
            let n = (b - a).cross(c - a);
            for &i in t {
                acc[remap[i as usize] as usize] += n;
            }
        }
        self.normals = (0..self.positions.len())
            .map(|i| acc[remap[i] as usize].normalize_or(Vec3::Z))
            .collect();
    }

    /// Axis-aligned bounds of all positions.
    pub fn bounds(&self) -> (Vec3, Vec3) {
        self.positions.iter().fold(
            (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY)),
            |(lo, hi), &p| (lo.min(p), hi.max(p)),
        )
    }
}

/// The power of two that brings the mesh's extent (its largest bounding-box side) to
/// about 1, or 1 for a mesh of no extent.
///
/// The DAG is built on the positions times this, and its spheres and errors divided by
/// it, and cleaning tests triangle areas on it: the products of coordinates (cross and
/// dot products, squared distances) of the meshlet splitter, the simplifier and the
/// area test then neither underflow into denormals on a mesh scaled to 1e-10 nor
/// overflow on one scaled to 1e16, and a mesh scaled by a power of two gives the same
/// DAG with its bounds and errors scaled alike. Multiplying by a power of two is exact,
/// so nothing is lost on the way there and back.
pub(crate) fn unit_scale(positions: &[Vec3]) -> f32 {
    let (lo, hi) = positions
        .iter()
        .fold((Vec3::MAX, Vec3::MIN), |(lo, hi), &p| {
            (lo.min(p), hi.max(p))
        });
    let extent = (hi - lo).max_element();
    if !(extent.is_normal() && extent > 0.0) {
        return 1.0;
    }
    2f32.powi(-(extent.log2().round() as i32))
}

/// For every vertex, the first vertex with a bit-identical position. Deterministic,
/// and independent of attributes so that UV seams do not break adjacency.
pub fn position_remap(positions: &[Vec3]) -> Vec<u32> {
    let mut map =
        rustc_hash::FxHashMap::with_capacity_and_hasher(positions.len(), Default::default());
    positions
        .iter()
        .enumerate()
        .map(|(i, p)| {
            // +0.0 and -0.0 are one point.
            let key = (*p + Vec3::ZERO).to_array().map(f32::to_bits);
            *map.entry(key).or_insert(i as u32)
        })
        .collect()
}

/// The triangles around each vertex, in compressed rows: vertex `v`'s triangles are
/// `triangles[start[v]..start[v + 1]]`, in input order.
pub(crate) struct Fans {
    start: Vec<u32>,
    triangles: Vec<u32>,
}

impl Fans {
    pub(crate) fn new(vertices: usize, indices: &[u32]) -> Self {
        let mut start = vec![0u32; vertices + 1];
        for &v in indices {
            start[v as usize + 1] += 1;
        }
        for v in 0..vertices {
            start[v + 1] += start[v];
        }
        let mut fill = start.clone();
        let mut triangles = vec![0u32; indices.len()];
        for (i, &v) in indices.iter().enumerate() {
            let f = &mut fill[v as usize];
            triangles[*f as usize] = (i / 3) as u32;
            *f += 1;
        }
        Self { start, triangles }
    }

    /// The triangles that have `v` as a corner.
    pub(crate) fn of(&self, v: u32) -> &[u32] {
        &self.triangles[self.start[v as usize] as usize..self.start[v as usize + 1] as usize]
    }
}

/// The three edges of every triangle, as (from, to) in winding order.
pub(crate) fn triangle_edges(indices: &[u32]) -> impl Iterator<Item = (u32, u32)> + '_ {
    indices
        .chunks_exact(3)
        .flat_map(|t| [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])])
}

/// An undirected edge as one sortable key: both directions give the same value.
pub(crate) fn edge_key(a: u32, b: u32) -> u64 {
    ((a.min(b) as u64) << 32) | a.max(b) as u64
}
