//! Splitting triangles into meshlets with meshoptimizer.

use glam::Vec3;

/// Most vertices per meshlet: local indices are `u8`, and 255 leaves 255 free as a
/// sentinel for the GPU.
pub const MAX_VERTICES: usize = 255;
/// Most triangles per meshlet: one workgroup of 128 threads rasterises one meshlet.
pub const MAX_TRIANGLES: usize = 128;

/// Splits an indexed triangle list into meshlets; each returned list indexes
/// `positions` like the input does. The cone weight is zero: the renderer culls by
/// sphere and occlusion, and favouring cones costs fill.
pub fn split_into_meshlets(positions: &[Vec3], indices: &[u32]) -> Vec<Vec<u32>> {
    if indices.is_empty() {
        return Vec::new();
    }
    // meshoptimizer's cost grows with the vertex buffer it is handed; a group of a large
    // mesh touches a few hundred vertices, so hand it a compact copy.
    if indices.len() * 4 < positions.len() {
        let Localised { globals, local } = localise(indices);
        let compact: Vec<Vec3> = globals.iter().map(|&g| positions[g as usize]).collect();
        return split_into_meshlets(&compact, &local)
            .into_iter()
            .map(|m| m.into_iter().map(|l| globals[l as usize]).collect())
            .collect();
    }
    let adapter = meshopt::VertexDataAdapter::new(bytemuck::cast_slice(positions), 12, 0)
        .expect("Vec3 is 12 bytes");
    let meshlets = meshopt::build_meshlets(indices, &adapter, MAX_VERTICES, MAX_TRIANGLES, 0.0);
    meshlets
        .iter()
        .map(|m| {
            m.triangles
                .iter()
                .map(|&t| m.vertices[t as usize])
                .collect()
        })
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
    let mut local_of: std::collections::HashMap<u32, u32> = std::collections::HashMap::with_capacity(indices.len() / 2);
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
