//! The DAG table `meshlight bake` and `meshlight inspect` both print: per level, the
//! roots, the fill, the size and the culling hierarchy.

use meshlight::scene::asset::summary::AssetSummary;
use meshlight::scene::verify::expected_levels;
use std::fmt::Write as _;

/// The lines of the table, each indented by two spaces and ending in a newline.
pub fn dag_table(summary: &AssetSummary) -> String {
    let h = &summary.header;
    let mut s = String::new();
    let _ = writeln!(s, "  level  meshlets  triangles  fill   max error");
    for (level, st) in summary.levels.iter().enumerate() {
        let _ = writeln!(
            s,
            "  {level:>5}  {:>8}  {:>9}  {:>5.1}  {:.3e}",
            st.meshlets,
            st.triangles,
            st.triangles as f64 / st.meshlets.max(1) as f64,
            st.max_error
        );
    }
    let _ = writeln!(
        s,
        "  levels: {} (log2 of LOD-0 meshlets + 1 = {:.1}); root: {} meshlets, {} triangles",
        h.level_count,
        expected_levels(h.lod0_meshlets),
        summary.root_meshlets,
        summary.root_triangles
    );
    let _ = writeln!(
        s,
        "  meshlet fill: {:.1} triangles per meshlet overall, {:.1} at LOD 0",
        h.total_triangles as f64 / h.meshlet_count.max(1) as f64,
        h.lod0_triangles as f64 / h.lod0_meshlets.max(1) as f64
    );
    let _ = writeln!(
        s,
        "  size: {} bytes, {:.2} bytes per LOD-0 triangle ({} triangles in all levels)",
        summary.bytes,
        summary.bytes as f64 / h.lod0_triangles.max(1) as f64,
        h.total_triangles
    );
    let tree = &summary.hierarchy;
    let _ = writeln!(
        s,
        "  culling hierarchy: {} nodes, {} leaves (one per group, one of roots), depth {}",
        tree.nodes, tree.leaves, tree.depth
    );
    let b = &summary.size;
    let per = |bytes: usize| bytes as f64 / h.lod0_triangles.max(1) as f64;
    let _ = writeln!(
        s,
        "  bytes per LOD-0 triangle: records {:.2}, groups {:.2}, hierarchy {:.2}, positions {:.2}, normals {:.2}, UVs {:.2}, colours {:.2}, indices {:.2}, open edges {:.2}; {:.2} vertex copies per triangle",
        per(b.meshlet_records),
        per(b.groups),
        per(b.hierarchy),
        per(b.positions),
        per(b.normals),
        per(b.uvs),
        per(b.colors),
        per(b.indices),
        per(b.open_edges),
        h.total_vertices as f64 / h.total_triangles.max(1) as f64
    );
    s
}
