//! Packing a built DAG into an asset: positions quantised on the mesh-wide grid and
//! bit-packed per meshlet, normals octahedral, UVs quantised, triangles encoded, then
//! the groups, the culling hierarchy, the header and the checksum. Only baking packs;
//! loading reads the words as they are.

use glam::Vec3;
use rayon::prelude::*;

use super::format::*;
use super::{MeshletAsset, checksum, triangles};
use crate::compress::{
    BitWriter, NORMAL_BITS, Quantization, UvQuantization, bits_for, encode_color, encode_octahedral,
};
use crate::dag::Dag;
use crate::mesh::Mesh;

/// Triangles of the source that cleaning dropped (see [`crate::mesh::CleanReport`]), for
/// the header's counts: the source had LOD 0's triangles and these.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Dropped {
    /// Triangles dropped as degenerate.
    pub degenerate: usize,
    /// Triangles dropped as duplicates of earlier ones.
    pub duplicate: usize,
}

impl MeshletAsset {
    /// Quantises and packs a DAG of `mesh` (the cleaned mesh it was built from) on a
    /// grid of `position_bits` over the mesh's bounds.
    pub fn from_dag(mesh: &Mesh, dag: &Dag, position_bits: u32, dropped: Dropped) -> Self {
        let (min, max) = mesh.bounds();
        let quant = Quantization::new(min, max, position_bits);
        Self::from_dag_on_grid(mesh, dag, quant, dropped)
    }

    /// Quantises and packs a DAG of `mesh` on the given grid, which must cover the
    /// mesh's bounds (a mesh snapped to a grid keeps the grid it was snapped to).
    pub fn from_dag_on_grid(mesh: &Mesh, dag: &Dag, quant: Quantization, dropped: Dropped) -> Self {
        let (min, max) = mesh.bounds();
        let uvq = UvQuantization::new(&mesh.uvs);
        let has_uvs = mesh.has_uvs();
        let has_colors = mesh.has_colors();
        let grid: Vec<[u32; 3]> = mesh
            .positions
            .par_iter()
            .map(|&p| quant.quantize(p))
            .collect();
        // Once per vertex, not per copy in each meshlet (about three copies each).
        let octahedral: Vec<[i32; 2]> = mesh
            .normals
            .par_iter()
            .map(|&n| encode_octahedral(n, NORMAL_BITS))
            .collect();
        let pad = quant.max_error();
        let flags = if has_uvs { FLAG_UVS } else { 0 } | if has_colors { FLAG_COLORS } else { 0 };

        let encoded: Vec<(MeshletRecord, Vec<u32>)> = dag
            .clusters
            .par_iter()
            .map(|c| {
                // Local vertices in order of first use, which meshoptimizer already
                // arranged for locality.
                let mut locals: Vec<u32> = Vec::with_capacity(c.indices.len());
                let mut slot = rustc_hash::FxHashMap::with_capacity_and_hasher(
                    c.indices.len(),
                    Default::default(),
                );
                let local_index: Vec<u8> = c
                    .indices
                    .iter()
                    .map(|&g| {
                        *slot.entry(g).or_insert_with(|| {
                            locals.push(g);
                            (locals.len() - 1) as u8
                        })
                    })
                    .collect();
                let lo = locals.iter().fold([u32::MAX; 3], |m, &v| {
                    let q = grid[v as usize];
                    [m[0].min(q[0]), m[1].min(q[1]), m[2].min(q[2])]
                });
                let hi = locals.iter().fold([0u32; 3], |m, &v| {
                    let q = grid[v as usize];
                    [m[0].max(q[0]), m[1].max(q[1]), m[2].max(q[2])]
                });
                let bits = [0, 1, 2].map(|k| bits_for(hi[k] - lo[k]));
                let oct: Vec<[i32; 2]> = locals.iter().map(|&v| octahedral[v as usize]).collect();
                let oct_lo = oct
                    .iter()
                    .fold([i32::MAX; 2], |m, o| [m[0].min(o[0]), m[1].min(o[1])]);
                let oct_hi = oct
                    .iter()
                    .fold([i32::MIN; 2], |m, o| [m[0].max(o[0]), m[1].max(o[1])]);
                let oct_bits = [0, 1].map(|k| bits_for((oct_hi[k] - oct_lo[k]) as u32));
                let mut data = Vec::new();
                let mut w = BitWriter::new(&mut data);
                for (&v, o) in locals.iter().zip(&oct) {
                    let q = grid[v as usize];
                    for k in 0..3 {
                        w.put(q[k] - lo[k], bits[k]);
                    }
                    for k in 0..2 {
                        w.put((o[k] - oct_lo[k]) as u32, oct_bits[k]);
                    }
                }
                let local: Vec<[u32; 3]> = local_index
                    .chunks_exact(3)
                    .map(|t| [t[0] as u32, t[1] as u32, t[2] as u32])
                    .collect();
                let tri_bits = triangles::encode(&local, locals.len() as u32, &mut data);
                let uv_bits = has_uvs.then(|| {
                    let block = uvq.encode_meshlet(locals.iter().map(|&v| mesh.uvs[v as usize]));
                    data.extend(block.origin);
                    let mut w = BitWriter::new(&mut data);
                    for o in &block.offsets {
                        w.put(o[0], block.bits[0]);
                        w.put(o[1], block.bits[1]);
                    }
                    block.bits
                });
                if has_colors {
                    data.extend(
                        locals
                            .iter()
                            .map(|&v| encode_color(mesh.colors[v as usize])),
                    );
                }
                let sphere4 = |c: Vec3, r: f32| [c.x, c.y, c.z, r];
                let record = MeshletRecord {
                    bounds: sphere4(c.bounds.0, c.bounds.1 + pad),
                    source_group: c.source_group,
                    parent_group: c.parent_group,
                    data_offset: 0,
                    counts: locals.len() as u32
                        | ((c.triangle_count() as u32) << 8)
                        | (c.level.min(255) << 16)
                        | (c.material << 24),
                    grid_min: lo,
                    bits: MeshletRecord::pack_bits(bits, uv_bits, tri_bits),
                    normals: (oct_lo[0] + NORMAL_BIAS) as u32
                        | (((oct_lo[1] + NORMAL_BIAS) as u32) << 12)
                        | (oct_bits[0] << 24)
                        | (oct_bits[1] << 28),
                };
                (record, data)
            })
            .collect();

        // The DAG is in page order (see `format`): the roots, then each group's
        // children in group order, so a page's meshlets and payload are each one range.
        let root_count = dag.roots().count();
        let mut meshlets = Vec::with_capacity(encoded.len());
        let mut payload = Vec::new();
        let mut resident_words = 0;
        for (i, (mut record, data)) in encoded.into_iter().enumerate() {
            record.data_offset = payload.len() as u32;
            payload.extend_from_slice(&data);
            meshlets.push(record);
            if i + 1 == root_count {
                resident_words = payload.len() as u32;
            }
        }
        let mut children = Vec::new();
        let mut pages = Vec::with_capacity(dag.groups.len());
        let groups: Vec<GroupRecord> = dag
            .groups
            .iter()
            .map(|g| {
                let first_child = children.len() as u32;
                children.extend_from_slice(&g.children);
                let (first, last) = (
                    &meshlets[g.children[0] as usize],
                    &meshlets[*children.last().expect("a group has children") as usize],
                );
                let (start, end) = (
                    first.data_offset,
                    last.data_offset + PayloadLayout::of(last, flags).end,
                );
                pages.push(PageRecord {
                    first_word: start,
                    words: end - start,
                    // Filled in by `checksum::seal`.
                    checksum: [0; 2],
                });
                GroupRecord {
                    // Padded like the meshlet bounds that LOD-0 meshlets use as their LOD
                    // spheres, so that every group sphere still holds its children's.
                    lod_sphere: [
                        g.lod.center.x,
                        g.lod.center.y,
                        g.lod.center.z,
                        g.lod.radius + pad,
                    ],
                    error: g.lod.error,
                    level: g.level,
                    first_child,
                    child_count: g.children.len() as u32,
                }
            })
            .collect();

        let hierarchy = crate::hierarchy::build(&meshlets, &groups, &children);
        let lod0: Vec<&crate::dag::DagCluster> =
            dag.clusters.iter().filter(|c| c.level == 0).collect();
        // LOD 0 on the grid, as the asset stores it: what a load compares it with.
        let open_edges = crate::open_edges::boundary_chain(lod0.len(), |i| {
            lod0[i]
                .indices
                .chunks_exact(3)
                .map(|t| [0, 1, 2].map(|k| grid[t[k] as usize]))
        });
        let mut used = vec![false; mesh.positions.len()];
        for c in &lod0 {
            for &v in &c.indices {
                used[v as usize] = true;
            }
        }

        let mut header = <AssetHeader as bytemuck::Zeroable>::zeroed();
        header.magic = MAGIC;
        header.version = VERSION;
        header.flags = flags;
        header.meshlet_count = meshlets.len() as u32;
        header.group_count = groups.len() as u32;
        header.node_count = hierarchy.nodes.len() as u32;
        header.level_count = dag.level_count;
        header.root_count = dag.roots().count() as u32;
        header.lod0_meshlets = lod0.len() as u32;
        header.lod0_triangles = lod0.iter().map(|c| c.triangle_count() as u32).sum();
        header.total_triangles = meshlets.iter().map(|m| m.triangle_count()).sum();
        header.total_vertices = meshlets.iter().map(|m| m.vertex_count()).sum();
        header.lod0_vertices = used.iter().filter(|&&u| u).count() as u32;
        header.dropped_degenerate = dropped.degenerate as u32;
        header.dropped_duplicate = dropped.duplicate as u32;
        header.input_triangles =
            header.lod0_triangles + header.dropped_degenerate + header.dropped_duplicate;
        header.material_count = mesh.material_count();
        header.resident_words = resident_words;
        header.bounds_min = min.to_array();
        header.bounds_max = max.to_array();
        header.quant_origin = quant.origin.to_array();
        header.quant_step = quant.step;
        header.quant_bits = quant.bits;
        header.uv_min = uvq.min;
        header.uv_step = uvq.step;

        let mut words: Vec<u32> = vec![0; AssetHeader::WORDS];
        let push = |words: &mut Vec<u32>, data: &[u32]| {
            let s = Section {
                offset: words.len() as u32,
                words: data.len() as u32,
            };
            words.extend_from_slice(data);
            s
        };
        header.sections[SECTION_MESHLETS] = push(&mut words, bytemuck::cast_slice(&meshlets));
        header.sections[SECTION_GROUPS] = push(&mut words, bytemuck::cast_slice(&groups));
        header.sections[SECTION_CHILDREN] = push(&mut words, &children);
        header.sections[SECTION_NODES] = push(&mut words, bytemuck::cast_slice(&hierarchy.nodes));
        header.sections[SECTION_NODE_CLUSTERS] = push(&mut words, &hierarchy.clusters);
        header.sections[SECTION_PAGES] = push(&mut words, bytemuck::cast_slice(&pages));
        header.sections[SECTION_OPEN_EDGES] = push(&mut words, bytemuck::cast_slice(&open_edges));
        header.sections[SECTION_PAYLOAD] = push(&mut words, &payload);
        let size = words.len() as u64 * 4;
        header.file_size = [size as u32, (size >> 32) as u32];
        words[..AssetHeader::WORDS]
            .copy_from_slice(bytemuck::cast_slice(std::slice::from_ref(&header)));
        checksum::seal(&mut words);
        Self {
            words,
            dag_verified: false,
            page_file: None,
        }
    }
}
