//! Structural checks of a loaded asset, beyond what the checksum gives: a file written by
//! a buggy or hostile writer with a valid checksum must still never make an accessor
//! panic, an allocation explode, or `inspect` report "all hold". Counts are checked
//! against what the file's size can hold before anything trusts them; every failure
//! names the field that is wrong.

use super::format::*;
use crate::compress::{
    MAX_POSITION_BITS, MIN_POSITION_BITS, UV_GRID_CODES, UV_LARGEST_CODE, UV_MAX_SHIFT, get_bits,
};

/// Most levels an asset may have: a meshlet stores its level in 8 bits.
pub const MAX_LEVELS: u32 = 256;

/// One inconsistency: the field and what is wrong with it.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Invalid {
    /// The header field, record field or section that is wrong, e.g. `header.flags` or
    /// `header.sections[2].offset`, so that an error message can point at it.
    pub field: String,
    /// What is wrong with it, worded to follow the field.
    pub problem: String,
}

fn bad(field: impl Into<String>, problem: impl Into<String>) -> Invalid {
    Invalid {
        field: field.into(),
        problem: problem.into(),
    }
}

fn finite_sphere(s: [f32; 4]) -> bool {
    s.iter().all(|v| v.is_finite()) && s[3] >= 0.0
}

/// Checks `words`, a whole file image whose size and checksum already match its header.
pub fn validate(words: &[u32]) -> Result<(), Invalid> {
    validate_prefix(words, words.len() as u64)
}

/// Checks the first `words` of a file of `total` words whose size and checksum already
/// match its header: the whole file, or (an asset opened for streaming) at least every
/// section before the payload. The records are checked whole; a meshlet whose data lies
/// past `words` has its data checked when its page is read ([`check_page_data`]).
pub fn validate_prefix(words: &[u32], total: u64) -> Result<(), Invalid> {
    let h: &AssetHeader = bytemuck::from_bytes(bytemuck::cast_slice(&words[..AssetHeader::WORDS]));

    if h.flags & !KNOWN_FLAGS != 0 {
        return Err(bad(
            "header.flags",
            format!("has unknown bits {:#x}", h.flags & !KNOWN_FLAGS),
        ));
    }
    // Sections tile the file in order: nothing overlaps, nothing is left over.
    let mut at = AssetHeader::WORDS as u64;
    for (i, s) in h.sections.iter().enumerate() {
        if s.offset as u64 != at {
            return Err(bad(
                format!("header.sections[{i}].offset"),
                format!(
                    "is {}, expected {at} (sections follow each other)",
                    s.offset
                ),
            ));
        }
        at += s.words as u64;
        if at > total {
            return Err(bad(
                format!("header.sections[{i}].words"),
                format!("runs to word {at}, past the file's {total} words"),
            ));
        }
    }
    if at != total {
        return Err(bad(
            "file size",
            format!("{} trailing bytes after the last section", (total - at) * 4),
        ));
    }
    let record = |section: usize, words: usize, count: u32, name: &str| {
        if h.sections[section].words as u64 != words as u64 * count as u64 {
            Err(bad(
                format!("header.{name}_count"),
                format!(
                    "is {count}, but its section holds {} words ({words} per record)",
                    h.sections[section].words
                ),
            ))
        } else {
            Ok(())
        }
    };
    record(
        SECTION_MESHLETS,
        size_of::<MeshletRecord>() / 4,
        h.meshlet_count,
        "meshlet",
    )?;
    record(
        SECTION_GROUPS,
        size_of::<GroupRecord>() / 4,
        h.group_count,
        "group",
    )?;
    // The payload is last and may be cut short; every section before it is in `words`.
    let payload_words = h.sections[SECTION_PAYLOAD].words as u64;
    if (words.len() as u64) < h.sections[SECTION_PAYLOAD].offset as u64 {
        return Err(bad(
            format!("header.sections[{SECTION_PAYLOAD}].offset"),
            "lies past the part of the file that was read",
        ));
    }
    let section = |i: usize| {
        let s = h.sections[i];
        &words[s.offset as usize..((s.offset + s.words) as usize).min(words.len())]
    };
    let meshlets: &[MeshletRecord] = bytemuck::cast_slice(section(SECTION_MESHLETS));
    let groups: &[GroupRecord] = bytemuck::cast_slice(section(SECTION_GROUPS));
    let children = section(SECTION_CHILDREN);
    let payload = section(SECTION_PAYLOAD);

    if h.meshlet_count == 0 {
        return Err(bad(
            "header.meshlet_count",
            "is 0; an asset has at least one meshlet",
        ));
    }
    if h.level_count == 0 || h.level_count > MAX_LEVELS.min(h.meshlet_count) {
        return Err(bad(
            "header.level_count",
            format!(
                "is {}, outside 1..={} (levels are 8-bit and each holds a meshlet)",
                h.level_count,
                MAX_LEVELS.min(h.meshlet_count)
            ),
        ));
    }
    if h.material_count == 0 || h.material_count > MAX_MATERIALS {
        return Err(bad(
            "header.material_count",
            format!(
                "is {}, outside 1..={} (a meshlet keeps its slot in 8 bits)",
                h.material_count, MAX_MATERIALS
            ),
        ));
    }
    header_floats(h)?;
    let sphere_limit = SphereLimit::of(h);

    let has_uvs = h.has_uvs();
    // Where the next meshlet's payload must start: meshlets' data follow each other
    // and together fill the payload, so no word is unreferenced or shared.
    let mut payload_end = 0u64;
    // Page order: the roots, then each group's children in group order.
    let mut previous_parent: Option<u32> = None;
    let grid_max = (1u64 << h.quant_bits) - 1;
    let (mut lod0_meshlets, mut lod0_triangles, mut triangles, mut vertices, mut roots) =
        (0u64, 0u64, 0u64, 0u64, 0u64);
    // LOD 0's vertex records, together and in its largest meshlet: what bounds
    // `lod0_vertices`.
    let (mut lod0_records, mut lod0_widest) = (0u64, 0u64);
    let mut max_level = 0;
    for (i, m) in meshlets.iter().enumerate() {
        let f = |name: &str| format!("meshlet[{i}].{name}");
        let (vc, tc, level) = (m.vertex_count(), m.triangle_count(), m.level());
        if m.material() >= h.material_count {
            return Err(bad(
                f("counts"),
                format!(
                    "material slot {} is not below header.material_count {}",
                    m.material(),
                    h.material_count
                ),
            ));
        }
        if vc == 0
            || tc == 0
            || vc > MAX_MESHLET_VERTICES as u32
            || tc > MAX_MESHLET_TRIANGLES as u32
        {
            return Err(bad(
                f("counts"),
                format!(
                    "says {vc} vertices and {tc} triangles; meshlets hold 1..={MAX_MESHLET_VERTICES} and 1..={MAX_MESHLET_TRIANGLES}"
                ),
            ));
        }
        if level >= h.level_count {
            return Err(bad(
                f("counts"),
                format!(
                    "level {level} is not below header.level_count {}",
                    h.level_count
                ),
            ));
        }
        max_level = max_level.max(level);
        if m.normal_bits()
            .iter()
            .any(|&b| b > crate::compress::NORMAL_BITS)
        {
            return Err(bad(
                f("normals"),
                format!(
                    "gives {:?}-bit normal offsets; components have {} bits",
                    m.normal_bits(),
                    crate::compress::NORMAL_BITS
                ),
            ));
        }
        let tb = m.triangle_bits();
        if tb.offset == 0 || tb.offset > 9 || tb.delta > 8 {
            return Err(bad(
                f("bits"),
                format!(
                    "gives triangle fields of {} and {} bits; they take 1..=9 and 0..=8",
                    tb.offset, tb.delta
                ),
            ));
        }
        // Bit 23 is unused; the UV widths are 0 in an asset without UVs.
        let unused = if has_uvs { 1 << 23 } else { 0x1ff << 15 };
        if m.bits & unused != 0 {
            return Err(bad(
                f("bits"),
                format!(
                    "sets bits {:#x}, which {}",
                    m.bits & unused,
                    if has_uvs {
                        "no field uses"
                    } else {
                        "give UV widths in an asset without UVs"
                    }
                ),
            ));
        }
        let bits = m.axis_bits();
        for (k, (&b, &min)) in bits.iter().zip(&m.grid_min).enumerate() {
            if b > h.quant_bits {
                return Err(bad(
                    f("bits"),
                    format!(
                        "packs {b} bits on axis {k}, more than the grid's {}",
                        h.quant_bits
                    ),
                ));
            }
            // Then minimum + offset < 2^25 cannot overflow 32-bit decoding; whether the
            // decoded points stay inside the bounds is for `verify`, which decodes them.
            if min as u64 > grid_max {
                return Err(bad(
                    f("grid_min"),
                    format!("{min} on axis {k} lies past the grid's last point {grid_max}"),
                ));
            }
        }
        if !finite_sphere(m.bounds) {
            return Err(bad(
                f("bounds"),
                format!("{:?} is not a finite sphere", m.bounds),
            ));
        }
        sphere_limit.check(m.bounds, 1.0, || f("bounds"))?;
        for (name, g) in [
            ("source_group", m.source_group),
            ("parent_group", m.parent_group),
        ] {
            if g != NO_GROUP && g >= h.group_count {
                return Err(bad(
                    f(name),
                    format!("is {g}, past the {} groups", h.group_count),
                ));
            }
        }
        match (m.parent_group, previous_parent) {
            (NO_GROUP, Some(p)) => {
                return Err(bad(
                    f("parent_group"),
                    format!(
                        "is none (a root) after a child of group {p}; meshlets are stored \
                         page by page: the roots first, then each group's children in \
                         group order"
                    ),
                ));
            }
            (NO_GROUP, None) => {}
            (g, Some(p)) if g < p => {
                return Err(bad(
                    f("parent_group"),
                    format!(
                        "is {g} after a child of group {p}; meshlets are stored page by \
                         page: the roots first, then each group's children in group order"
                    ),
                ));
            }
            (g, _) => previous_parent = Some(g),
        }
        if (level == 0) != (m.source_group == NO_GROUP) {
            return Err(bad(
                f("source_group"),
                format!(
                    "is {:#x} at level {level}; exactly the LOD-0 meshlets have none",
                    m.source_group
                ),
            ));
        }
        let layout = PayloadLayout::of(m, h.flags);
        if m.data_offset as u64 + layout.end as u64 > payload_words {
            return Err(bad(f("data_offset"), "puts its data outside the payload"));
        }
        if m.data_offset as u64 != payload_end {
            return Err(bad(
                f("data_offset"),
                format!(
                    "is {}, but the previous meshlet's data ends at word {payload_end}; each \
                     meshlet's data follows the one before",
                    m.data_offset
                ),
            ));
        }
        payload_end += layout.end as u64;
        // Data past what was read is checked when its page is.
        if let Some(data) =
            payload.get(m.data_offset as usize..(m.data_offset + layout.end) as usize)
        {
            meshlet_data(h, m, &layout, data, &sphere_limit)
                .map_err(|p| bad(f("data_offset"), p))?;
        }
        if level == 0 {
            lod0_meshlets += 1;
            lod0_triangles += tc as u64;
            lod0_records += vc as u64;
            lod0_widest = lod0_widest.max(vc as u64);
        }
        triangles += tc as u64;
        vertices += vc as u64;
        roots += (m.parent_group == NO_GROUP) as u64;
    }
    if payload_end != payload_words {
        return Err(bad(
            format!("header.sections[{SECTION_PAYLOAD}].words"),
            format!(
                "the payload holds {payload_words} words, but the meshlets' data ends at word \
                 {payload_end}; every payload word belongs to one meshlet"
            ),
        ));
    }
    if max_level + 1 != h.level_count {
        return Err(bad(
            "header.level_count",
            format!(
                "is {}, but the highest meshlet level is {max_level}",
                h.level_count
            ),
        ));
    }
    for (name, stored, counted) in [
        ("lod0_meshlets", h.lod0_meshlets, lod0_meshlets),
        ("lod0_triangles", h.lod0_triangles, lod0_triangles),
        ("total_triangles", h.total_triangles, triangles),
        ("total_vertices", h.total_vertices, vertices),
        ("root_count", h.root_count, roots),
    ] {
        if stored as u64 != counted {
            return Err(bad(
                format!("header.{name}"),
                format!("is {stored}, but the meshlets give {counted}"),
            ));
        }
    }
    source_counts(h, lod0_records, lod0_widest)?;
    open_edges(h, section(SECTION_OPEN_EDGES))?;
    for (i, g) in groups.iter().enumerate() {
        let f = |name: &str| format!("group[{i}].{name}");
        if !finite_sphere(g.lod_sphere) {
            return Err(bad(
                f("lod_sphere"),
                format!("{:?} is not a finite sphere", g.lod_sphere),
            ));
        }
        sphere_limit.check(g.lod_sphere, LOD_SPHERE_SLACK, || f("lod_sphere"))?;
        if !(g.error.is_finite() && g.error >= 0.0) {
            return Err(bad(f("error"), format!("is {}", g.error)));
        }
        if g.level >= h.level_count {
            return Err(bad(
                f("level"),
                format!(
                    "is {}, not below header.level_count {}",
                    g.level, h.level_count
                ),
            ));
        }
        if g.child_count == 0 || g.first_child as u64 + g.child_count as u64 > children.len() as u64
        {
            return Err(bad(
                f("first_child"),
                format!(
                    "children {}..+{} are empty or outside the {} of their section",
                    g.first_child,
                    g.child_count,
                    children.len()
                ),
            ));
        }
    }
    if let Some(k) = children.iter().position(|&c| c >= h.meshlet_count) {
        return Err(bad(
            format!("children[{k}]"),
            format!(
                "refers to meshlet {}, past the {} meshlets",
                children[k], h.meshlet_count
            ),
        ));
    }
    group_links(meshlets, groups, children)?;
    record(
        SECTION_PAGES,
        size_of::<PageRecord>() / 4,
        h.group_count,
        "group",
    )?;
    pages(
        h,
        meshlets,
        groups,
        children,
        bytemuck::cast_slice(section(SECTION_PAGES)),
    )?;
    record(
        SECTION_NODES,
        size_of::<NodeRecord>() / 4,
        h.node_count,
        "node",
    )?;
    let nodes: &[NodeRecord] = bytemuck::cast_slice(section(SECTION_NODES));
    hierarchy(meshlets, groups, nodes, section(SECTION_NODE_CLUSTERS))
}

/// The header's counts of the source: the triangles it had are LOD 0's and those
/// dropped, and the distinct vertices LOD 0 uses lie between its largest meshlet's and
/// all its meshlets' vertex records (a vertex on a border between meshlets is stored in
/// each).
fn source_counts(h: &AssetHeader, lod0_records: u64, lod0_widest: u64) -> Result<(), Invalid> {
    let sum = h.lod0_triangles as u64 + h.dropped_degenerate as u64 + h.dropped_duplicate as u64;
    if h.input_triangles as u64 != sum {
        return Err(bad(
            "header.input_triangles",
            format!(
                "is {}, but LOD 0's {} triangles and the {} degenerate and {} duplicate ones \
                 dropped make {sum}",
                h.input_triangles, h.lod0_triangles, h.dropped_degenerate, h.dropped_duplicate
            ),
        ));
    }
    let vertices = h.lod0_vertices as u64;
    if !(lod0_widest..=lod0_records).contains(&vertices) {
        return Err(bad(
            "header.lod0_vertices",
            format!(
                "is {vertices}, outside {lod0_widest}..={lod0_records}: LOD 0 uses at least \
                 its largest meshlet's vertices and at most all its meshlets' vertex records"
            ),
        ));
    }
    Ok(())
}

/// The open-edge section in its one form: whole records, each an edge between two
/// different grid points on the grid, used at least once, in ascending order of its
/// ends with each pair once. Whether LOD 0 still has them is a DAG check
/// ([`crate::open_edges::lod0_problem`]), which decodes the meshlets.
fn open_edges(h: &AssetHeader, words: &[u32]) -> Result<(), Invalid> {
    let size = size_of::<OpenEdgeRecord>() / 4;
    if !words.len().is_multiple_of(size) {
        return Err(bad(
            format!("header.sections[{SECTION_OPEN_EDGES}].words"),
            format!(
                "is {}, not a whole number of {size}-word open edges",
                words.len()
            ),
        ));
    }
    let records: &[OpenEdgeRecord] = bytemuck::cast_slice(words);
    let grid_max = (1u64 << h.quant_bits) - 1;
    let on_grid = |p: [u32; 3]| p.iter().all(|&c| c as u64 <= grid_max);
    let mut uses = 0u64;
    for (i, r) in records.iter().enumerate() {
        let field = |name: &str| format!("open_edge[{i}].{name}");
        if !on_grid(r.from) || !on_grid(r.to) {
            return Err(bad(
                field("from/to"),
                format!(
                    "{:?}–{:?} lies off the {}-bit grid",
                    r.from, r.to, h.quant_bits
                ),
            ));
        }
        if r.from == r.to {
            return Err(bad(field("to"), "equals `from`; an edge joins two points"));
        }
        // Together at most three uses per LOD-0 triangle: so they sum in 64 bits.
        uses += r.uses as u64;
        if r.uses == 0 || uses > 3 * h.lod0_triangles as u64 {
            return Err(bad(
                field("uses"),
                format!(
                    "is {}; each edge is used at least once, and all at most {} times (three \
                     edges per LOD-0 triangle)",
                    r.uses,
                    3 * h.lod0_triangles as u64
                ),
            ));
        }
        if i > 0 && records[i - 1].key() >= r.key() {
            return Err(bad(
                field("from/to"),
                "does not follow the edge before in ascending order (each edge once)",
            ));
        }
    }
    Ok(())
}

/// The checks of one meshlet's `data` (its payload words, `layout.end` of them) that
/// the structure relies on: its vertices within the header's bounds and its UV blocks'
/// shifts in range. The problem, worded to follow `meshlet[i].data_offset`.
fn meshlet_data(
    h: &AssetHeader,
    m: &MeshletRecord,
    layout: &PayloadLayout,
    data: &[u32],
    sphere_limit: &SphereLimit,
) -> Result<(), String> {
    if let Some((k, p)) = vertex_outside_bounds(h, m, data, sphere_limit) {
        return Err(outside_bounds_problem(h, k, p));
    }
    if let Some(k) = uv_shift_past_grid(h, layout, data) {
        return Err(uv_shift_problem(k, data[layout.uvs as usize + k]));
    }
    Ok(())
}

fn outside_bounds_problem(h: &AssetHeader, k: usize, p: f64) -> String {
    format!(
        "points at vertex records that decode to {p:?} on axis {k}, outside the \
         header's bounds {:?}..{:?} (the grid's rounding allowed)",
        h.bounds_min, h.bounds_max
    )
}

/// The UV offset (0: u, 1: v) of a meshlet's UV block whose shift is past the grid.
fn uv_shift_past_grid(h: &AssetHeader, layout: &PayloadLayout, data: &[u32]) -> Option<usize> {
    let at = layout.uvs as usize;
    (0..2).find(|&k| h.has_uvs() && data[at + k] >> 24 > UV_MAX_SHIFT)
}

fn uv_shift_problem(k: usize, word: u32) -> String {
    format!(
        "points at a UV block whose {} offsets are shifted by {}; at most \
         {UV_MAX_SHIFT} reaches every code of the UV grid",
        ["u", "v"][k],
        word >> 24
    )
}

/// Checks a page's words as read from the file, for an asset opened for streaming
/// (whose structure [`validate_prefix`] checked): the page is `group`'s, `words` long as
/// its record says, and each of its meshlets' data passes what a whole file's load
/// checks (vertices within the bounds, UV shifts) and what `inspect` checks of one
/// meshlet (triangle corners within its vertices, vertices within its culling sphere).
/// The page's checksum is the reader's to check, before this.
pub fn check_page_data(
    h: &AssetHeader,
    meshlets: &[MeshletRecord],
    page: &PageRecord,
    children: std::ops::Range<usize>,
    words: &[u32],
) -> Result<(), Invalid> {
    if words.len() as u64 != page.words as u64 {
        return Err(bad(
            "page",
            format!(
                "is {} words where its record says {}",
                words.len(),
                page.words
            ),
        ));
    }
    let sphere_limit = SphereLimit::of(h);
    let (origin, step) = (h.quant_origin, h.quant_step);
    for i in children {
        let m = &meshlets[i];
        let f = |name: &str| format!("meshlet[{i}].{name}");
        let layout = PayloadLayout::of(m, h.flags);
        // `validate_prefix` checked that the page's meshlets tile its range.
        let start = (m.data_offset - page.first_word) as usize;
        let data = &words[start..start + layout.end as usize];
        // One decoding of the vertices gives the bounds check of a whole file's load
        // (`vertex_outside_bounds`, from the grid's extremes) and the culling sphere
        // check of `inspect` (`verify`'s, in the same f32 operations).
        let centre = [m.bounds[0], m.bounds[1], m.bounds[2]];
        let (mut lo, mut hi, mut farthest_bits) = ([u32::MAX; 3], [0u32; 3], 0u32);
        super::grid_points(m, bytemuck::cast_slice(data), |_, q| {
            let mut squared = 0.0f32;
            for k in 0..3 {
                lo[k] = lo[k].min(q[k]);
                hi[k] = hi[k].max(q[k]);
                let d = (origin[k] + q[k] as f32 * step) - centre[k];
                squared += d * d;
            }
            farthest_bits = farthest_bits.max(squared.to_bits());
        });
        if let Some((k, p)) = outside_bounds(h, lo, hi, &sphere_limit) {
            return Err(bad(f("data_offset"), outside_bounds_problem(h, k, p)));
        }
        if let Some(k) = uv_shift_past_grid(h, &layout, data) {
            return Err(bad(
                f("data_offset"),
                uv_shift_problem(k, data[layout.uvs as usize + k]),
            ));
        }
        let farthest = f32::from_bits(farthest_bits).sqrt();
        let largest = centre.iter().fold(0.0f32, |a, c| a.max(c.abs()));
        if farthest > m.bounds[3] * (1.0 + 1e-5) + 1e-6 * largest {
            return Err(bad(
                f("bounds"),
                format!(
                    "a vertex lies {farthest} from the centre of its culling sphere of radius {}",
                    m.bounds[3]
                ),
            ));
        }
        let (vc, tc) = (m.vertex_count(), m.triangle_count());
        let block = &data[layout.triangles as usize..layout.uvs as usize];
        if let Some(t) = super::triangles::first_out_of_range(block, m.triangle_bits(), vc, tc) {
            return Err(bad(
                f("triangles"),
                format!("triangle {t} refers past the meshlet's {vc} vertices"),
            ));
        }
    }
    Ok(())
}

/// How far a group's LOD sphere may reach beyond the mesh's bounds, in multiples of
/// their diagonal. A group's sphere encloses its children's and each merge adds a
/// little: the largest radius on the test meshes and the procedural mesh is 0.48 to
/// 0.68 of the diagonal. 4 leaves room for any mesh and still refuses a radius that
/// would overflow projecting it.
const LOD_SPHERE_SLACK: f64 = 4.0;

/// The first of meshlet `m`'s decoded vertices (its payload `data`) that lies outside
/// the header's bounds padded by the grid's rounding, as its axis and coordinate: the
/// culling and the LOD spheres are derived from the bounds, so a vertex outside them
/// could be culled while on screen.
fn vertex_outside_bounds(
    h: &AssetHeader,
    m: &MeshletRecord,
    data: &[u32],
    limit: &SphereLimit,
) -> Option<(usize, f64)> {
    if m.vertex_count() == 0 {
        return None;
    }
    let bits = m.axis_bits();
    let stride = m.vertex_stride() as usize;
    let mut lo = [u32::MAX; 3];
    let mut hi = [0u32; 3];
    for v in 0..m.vertex_count() as usize {
        let mut at = v * stride;
        for k in 0..3 {
            let q = m.grid_min[k].wrapping_add(get_bits(data, at, bits[k]).unwrap_or(0));
            at += bits[k] as usize;
            lo[k] = lo[k].min(q);
            hi[k] = hi[k].max(q);
        }
    }
    outside_bounds(h, lo, hi, limit)
}

/// The first axis, and coordinate, where grid extremes `lo`..`hi` decode outside the
/// header's bounds padded by the grid's rounding.
fn outside_bounds(
    h: &AssetHeader,
    lo: [u32; 3],
    hi: [u32; 3],
    limit: &SphereLimit,
) -> Option<(usize, f64)> {
    (0..3).find_map(|k| {
        let at = |q: u32| h.quant_origin[k] as f64 + q as f64 * h.quant_step as f64;
        [at(lo[k]), at(hi[k])]
            .into_iter()
            .find(|&p| p < limit.lo[k] - limit.pad || p > limit.hi[k] + limit.pad)
            .map(|p| (k, p))
    })
}

/// Spheres must lie around the mesh: a culling sphere (around decoded vertices) within
/// its bounds, padded by the grid's rounding, and a LOD sphere within a few diagonals.
/// A radius of `f32::MAX` would make every cull and error projection overflow.
struct SphereLimit {
    lo: [f64; 3],
    hi: [f64; 3],
    diagonal: f64,
    pad: f64,
}

impl SphereLimit {
    fn of(h: &AssetHeader) -> Self {
        let lo = h.bounds_min.map(f64::from);
        let hi = h.bounds_max.map(f64::from);
        let diagonal = (0..3).map(|k| (hi[k] - lo[k]).powi(2)).sum::<f64>().sqrt();
        // The quantiser's largest error, plus float rounding of the coordinates.
        let magnitude = lo.iter().chain(&hi).fold(0.0f64, |m, &c| m.max(c.abs()));
        let pad = h.quant_step as f64 * 3f64.sqrt() + magnitude * 1e-6;
        Self {
            lo,
            hi,
            diagonal,
            pad,
        }
    }

    fn check(
        &self,
        sphere: [f32; 4],
        slack: f64,
        field: impl Fn() -> String,
    ) -> Result<(), Invalid> {
        let reach = self.diagonal * slack + self.pad;
        let radius = sphere[3] as f64;
        let outside = (0..3).any(|k| {
            let c = sphere[k] as f64;
            c < self.lo[k] - reach || c > self.hi[k] + reach
        });
        if radius > reach || outside {
            return Err(bad(
                field(),
                format!(
                    "{sphere:?} reaches beyond the mesh's bounds {:?} .. {:?} (diagonal {:e})",
                    self.lo, self.hi, self.diagonal
                ),
            ));
        }
        Ok(())
    }
}

/// The DAG's links, as the builder makes them: a group's children are meshlets that
/// name it as their parent and lie at or below its level; its outputs (meshlets naming
/// it as their source) lie one level above it, and it has at least one.
fn group_links(
    meshlets: &[MeshletRecord],
    groups: &[GroupRecord],
    children: &[u32],
) -> Result<(), Invalid> {
    for (g, group) in groups.iter().enumerate() {
        let range = group.first_child as usize..(group.first_child + group.child_count) as usize;
        for &c in &children[range] {
            let child = &meshlets[c as usize];
            if child.parent_group != g as u32 {
                return Err(bad(
                    format!("meshlet[{c}].parent_group"),
                    format!(
                        "is {:#x}, but group {g} lists the meshlet as its child",
                        child.parent_group
                    ),
                ));
            }
            if child.level() > group.level {
                return Err(bad(
                    format!("group[{g}].level"),
                    format!(
                        "is {}, below its child meshlet {c}'s level {}; a group is formed at \
                         or above its children's level",
                        group.level,
                        child.level()
                    ),
                ));
            }
        }
    }
    let mut outputs = vec![0u32; groups.len()];
    for (i, m) in meshlets.iter().enumerate() {
        let Some(group) = groups.get(m.source_group as usize) else {
            continue;
        };
        outputs[m.source_group as usize] += 1;
        if m.level() != group.level + 1 {
            return Err(bad(
                format!("meshlet[{i}].source_group"),
                format!(
                    "is group {}, of level {}, but the meshlet is at level {}; a group's \
                     simplified meshlets are one level above it",
                    m.source_group,
                    group.level,
                    m.level()
                ),
            ));
        }
        if m.parent_group == m.source_group {
            return Err(bad(
                format!("meshlet[{i}].parent_group"),
                "is its source group; a meshlet cannot be simplified in the group that made it",
            ));
        }
    }
    if let Some(g) = outputs.iter().position(|&n| n == 0) {
        return Err(bad(
            format!("group[{g}]"),
            "has no simplified meshlets (none names it as its source group)",
        ));
    }
    Ok(())
}

/// The pages: each group's children are the meshlets after the previous group's (after
/// the roots for group 0), in order, so that a page is one range of meshlets; its record
/// gives its payload's range exactly, and the roots' payload is the resident part.
/// Meshlets' payloads follow each other (checked above), so the pages then tile the
/// payload after the roots'.
fn pages(
    h: &AssetHeader,
    meshlets: &[MeshletRecord],
    groups: &[GroupRecord],
    children: &[u32],
    pages: &[PageRecord],
) -> Result<(), Invalid> {
    let roots = meshlets
        .iter()
        .take_while(|m| m.parent_group == NO_GROUP)
        .count();
    let payload_end = |m: &MeshletRecord| m.data_offset + PayloadLayout::of(m, h.flags).end;
    let resident = meshlets[..roots].last().map_or(0, payload_end);
    if h.resident_words != resident {
        return Err(bad(
            "header.resident_words",
            format!(
                "is {}, but the roots' payload ends at word {resident}",
                h.resident_words
            ),
        ));
    }
    let mut next = roots as u32;
    for (g, (group, page)) in groups.iter().zip(pages).enumerate() {
        let list = &children[group.first_child as usize..][..group.child_count as usize];
        if let Some(k) = (0..list.len()).find(|&k| list[k] != next + k as u32) {
            return Err(bad(
                format!("group[{g}].first_child"),
                format!(
                    "lists meshlet {} as child {k}, where meshlet {} stands; a group's \
                     children are the meshlets after the previous group's, in order",
                    list[k],
                    next + k as u32
                ),
            ));
        }
        let (first, last) = (
            &meshlets[next as usize],
            &meshlets[(next + group.child_count - 1) as usize],
        );
        let words = payload_end(last) - first.data_offset;
        if (page.first_word, page.words) != (first.data_offset, words) {
            return Err(bad(
                format!("page[{g}]"),
                format!(
                    "gives words {}..+{}, but group {g}'s children's payload is words \
                     {}..+{words}",
                    page.first_word, page.words, first.data_offset
                ),
            ));
        }
        next += group.child_count;
    }
    if next as usize != meshlets.len() {
        return Err(bad(
            "header.group_count",
            format!(
                "is {}, but its groups' children end at meshlet {next} of {}; every meshlet \
                 but the roots is one group's child",
                groups.len(),
                meshlets.len()
            ),
        ));
    }
    Ok(())
}

/// The culling hierarchy (see [`crate::hierarchy`]): a tree rooted at node 0 whose
/// children come after their parent (so no walk can cycle) and whose every other node
/// has exactly one parent; the cluster list a permutation of the meshlets, tiled by the
/// leaves in depth-first order; each leaf the meshlets of one group (or roots), every
/// group in exactly one leaf; and every node's spheres and errors bounding everything
/// below it, which the GPU's conservative skipping relies on.
fn hierarchy(
    meshlets: &[MeshletRecord],
    groups: &[GroupRecord],
    nodes: &[NodeRecord],
    list: &[u32],
) -> Result<(), Invalid> {
    use crate::hierarchy::{MAX_CHILDREN, MAX_DEPTH, encloses};
    if nodes.is_empty() {
        return Err(bad("header.node_count", "is 0; the hierarchy has a root"));
    }
    if list.len() != meshlets.len() {
        return Err(bad(
            "header.sections[5].words",
            format!(
                "the hierarchy's cluster list holds {} entries for {} meshlets; it lists each once",
                list.len(),
                meshlets.len()
            ),
        ));
    }
    let mut seen = vec![false; meshlets.len()];
    for (k, &m) in list.iter().enumerate() {
        match seen.get_mut(m as usize) {
            None => {
                return Err(bad(
                    format!("node_clusters[{k}]"),
                    format!(
                        "refers to meshlet {m}, past the {} meshlets",
                        meshlets.len()
                    ),
                ));
            }
            Some(true) => {
                return Err(bad(
                    format!("node_clusters[{k}]"),
                    format!("lists meshlet {m} a second time; each meshlet is listed once"),
                ));
            }
            Some(s) => *s = true,
        }
    }
    let mut parents = vec![0u32; nodes.len()];
    // Each node's level below the root, set by its parent (children come after it).
    let mut depth = vec![0u32; nodes.len()];
    let mut group_leaf = vec![false; groups.len()];
    for (i, n) in nodes.iter().enumerate() {
        let f = |name: &str| format!("node[{i}].{name}");
        if n.reserved != [0; 2] {
            return Err(bad(f("reserved"), "is not zero"));
        }
        for (name, s) in [("bounds", n.bounds), ("lod_sphere", n.lod_sphere)] {
            if !finite_sphere(s) {
                return Err(bad(f(name), format!("{s:?} is not a finite sphere")));
            }
        }
        for (name, e) in [
            ("min_error", n.min_error),
            ("max_parent_error", n.max_parent_error),
        ] {
            if !(e.is_finite() && e >= 0.0) {
                return Err(bad(f(name), format!("is {e}")));
            }
        }
        if n.first_cluster as u64 + n.cluster_count as u64 > list.len() as u64
            || n.cluster_count == 0
        {
            return Err(bad(
                f("first_cluster"),
                format!(
                    "meshlets {}..+{} are empty or outside the cluster list's {}",
                    n.first_cluster,
                    n.cluster_count,
                    list.len()
                ),
            ));
        }
        if i == 0 && (n.first_cluster != 0 || n.cluster_count as usize != list.len()) {
            return Err(bad(
                f("cluster_count"),
                "the root does not cover the whole cluster list",
            ));
        }
        if n.is_leaf() {
            let below: Vec<&MeshletRecord> = list[n.clusters()]
                .iter()
                .map(|&m| &meshlets[m as usize])
                .collect();
            if n.first_child != 0 {
                return Err(bad(f("first_child"), "is not 0 in a leaf"));
            }
            leaf_group(i, n, &below, groups, &mut group_leaf)?;
            for m in &below {
                let ((own_sphere, own_error), parent) = crate::hierarchy::meshlet_lod(m, groups);
                let (parent_sphere, parent_error) =
                    parent.unwrap_or((own_sphere, crate::asset::format::ROOT_PARENT_ERROR));
                if !encloses(n.bounds, m.bounds)
                    || !encloses(n.lod_sphere, own_sphere)
                    || !encloses(n.lod_sphere, parent_sphere)
                {
                    return Err(bad(
                        f("bounds"),
                        "does not enclose the spheres of a meshlet below it",
                    ));
                }
                if own_error < n.min_error {
                    return Err(bad(
                        f("min_error"),
                        format!("is above the own error {own_error} of a meshlet below it"),
                    ));
                }
                if parent_error > n.max_parent_error {
                    return Err(bad(
                        f("max_parent_error"),
                        format!("is below the parent error {parent_error} of a meshlet below it"),
                    ));
                }
            }
            continue;
        }
        if n.child_count > MAX_CHILDREN
            || (n.first_child as usize) <= i
            || n.first_child as u64 + n.child_count as u64 > nodes.len() as u64
        {
            return Err(bad(
                f("first_child"),
                format!(
                    "children {}..+{} are not after the node, within the {} nodes, at most {MAX_CHILDREN}",
                    n.first_child,
                    n.child_count,
                    nodes.len()
                ),
            ));
        }
        let mut at = n.first_cluster;
        for c in n.children() {
            parents[c] += 1;
            depth[c] = depth[i] + 1;
            if depth[c] >= MAX_DEPTH {
                return Err(bad(
                    format!("node[{c}]"),
                    format!(
                        "lies {} levels below the root, where the GPU walk never reaches \
                         (it tests levels 0 to {}); rebake the mesh: a baked hierarchy \
                         branches several ways and stays far shallower",
                        depth[c],
                        MAX_DEPTH - 1
                    ),
                ));
            }
            let child = &nodes[c];
            if child.first_cluster != at {
                return Err(bad(
                    f("first_cluster"),
                    format!("its children's meshlets do not follow each other at child {c}"),
                ));
            }
            at = at.saturating_add(child.cluster_count);
            if !encloses(n.bounds, child.bounds) || !encloses(n.lod_sphere, child.lod_sphere) {
                return Err(bad(
                    f("bounds"),
                    format!("does not enclose child node {c}'s spheres"),
                ));
            }
            if child.min_error < n.min_error {
                return Err(bad(f("min_error"), format!("is above child node {c}'s")));
            }
            if child.max_parent_error > n.max_parent_error {
                return Err(bad(
                    f("max_parent_error"),
                    format!("is below child node {c}'s"),
                ));
            }
        }
        if at != n.first_cluster + n.cluster_count {
            return Err(bad(f("cluster_count"), "is not the sum of its children's"));
        }
    }
    if let Some(k) = (1..nodes.len()).find(|&k| parents[k] != 1) {
        return Err(bad(
            format!("node[{k}]"),
            format!(
                "is a child of {} nodes; every node but the root has one parent",
                parents[k]
            ),
        ));
    }
    if let Some(g) = group_leaf.iter().position(|&reached| !reached) {
        return Err(bad(
            format!("group[{g}]"),
            "is in no leaf of the hierarchy; each group is one leaf",
        ));
    }
    Ok(())
}

/// A leaf holds the children of one group, all of them (or only roots), and no group
/// has two leaves.
fn leaf_group(
    i: usize,
    n: &NodeRecord,
    below: &[&MeshletRecord],
    groups: &[GroupRecord],
    group_leaf: &mut [bool],
) -> Result<(), Invalid> {
    let parent = below[0].parent_group;
    if below.iter().any(|m| m.parent_group != parent) {
        return Err(bad(
            format!("node[{i}]"),
            "is a leaf whose meshlets have different parent groups; a leaf holds one group",
        ));
    }
    if parent == NO_GROUP {
        return Ok(());
    }
    let g = parent as usize;
    if group_leaf[g] || groups[g].child_count != n.cluster_count {
        return Err(bad(
            format!("node[{i}]"),
            format!("is a leaf of group {g}, which has another leaf or other children"),
        ));
    }
    group_leaf[g] = true;
    Ok(())
}

/// The header's floating-point fields: grid, bounds and UV rectangle.
fn header_floats(h: &AssetHeader) -> Result<(), Invalid> {
    if !(MIN_POSITION_BITS..=MAX_POSITION_BITS).contains(&h.quant_bits) {
        return Err(bad(
            "header.quant_bits",
            format!(
                "is {}, outside {MIN_POSITION_BITS}..={MAX_POSITION_BITS}",
                h.quant_bits
            ),
        ));
    }
    if !(h.quant_step.is_finite() && h.quant_step > 0.0) {
        return Err(bad(
            "header.quant_step",
            format!(
                "is {}; the grid step must be finite and positive",
                h.quant_step
            ),
        ));
    }
    let reach = h.quant_step as f64 * ((1u64 << h.quant_bits) - 1) as f64;
    for k in 0..3 {
        let o = h.quant_origin[k];
        if !o.is_finite() || (o as f64 + reach).abs() >= f32::MAX as f64 {
            return Err(bad(
                "header.quant_origin",
                format!(
                    "{:?} with step {} leaves the finite range",
                    h.quant_origin, h.quant_step
                ),
            ));
        }
    }
    let (lo, hi) = (h.bounds_min, h.bounds_max);
    if (0..3).any(|k| !lo[k].is_finite() || !hi[k].is_finite() || lo[k] > hi[k]) {
        return Err(bad(
            "header.bounds_min/bounds_max",
            format!("{lo:?} .. {hi:?} is not a finite, ordered box"),
        ));
    }
    // The extent is computed in f32 by the quantiser and the renderer: it must not
    // overflow, and a mesh with triangles has one.
    let extent = (0..3).map(|k| hi[k] - lo[k]).fold(0.0f32, f32::max);
    if !extent.is_finite() || extent <= 0.0 {
        return Err(bad(
            "header.bounds_min/bounds_max",
            format!("{lo:?} .. {hi:?} has the size {extent}; it must be finite and positive"),
        ));
    }
    // The grid spans the bounds: its step is the extent over the grid's cells. A step far
    // off (1e38, or a denormal) decodes every vertex to the origin or to infinity.
    let cells = ((1u64 << h.quant_bits) - 1) as f64;
    let span = h.quant_step as f64 * cells;
    if !h.quant_step.is_normal() || span < extent as f64 * 0.999 || span > extent as f64 * 1.001 {
        return Err(bad(
            "header.quant_step",
            format!(
                "is {:e}: {} bits of it span {span:e}, but the bounds' extent is {extent:e}; \
                 the grid's step is the extent over its {cells} cells",
                h.quant_step, h.quant_bits
            ),
        ));
    }
    if h.has_uvs()
        && (0..2)
            .any(|k| !(h.uv_min[k].is_finite() && h.uv_step[k].is_finite() && h.uv_step[k] >= 0.0))
    {
        return Err(bad(
            "header.uv_min/uv_step",
            format!("{:?} / {:?} is not a finite rectangle", h.uv_min, h.uv_step),
        ));
    }
    // The largest UV a record can encode is `uv_min + code · uv_step`, a code below
    // `UV_GRID_CODES` plus an offset of at most `UV_MAX_BITS` shifted by at most
    // `UV_MAX_SHIFT`, computed in f32 on the GPU: past the f32 range it decodes to
    // infinity and shades black.
    let largest_code = (UV_GRID_CODES + UV_LARGEST_CODE) as f32;
    if h.has_uvs() && (0..2).any(|k| !(h.uv_min[k] + largest_code * h.uv_step[k]).is_finite()) {
        return Err(bad(
            "header.uv_min/uv_step",
            format!(
                "{:?} / {:?} reaches past the f32 range at the largest encoded UV",
                h.uv_min, h.uv_step
            ),
        ));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::asset::format::{NO_GROUP, ROOT_PARENT_ERROR};
    use crate::hierarchy::MAX_DEPTH;

    /// A chain of `levels` nodes over one root meshlet: each inner node's one child is
    /// the next, the last a leaf, every node covering the meshlet with the same spheres.
    fn chain(levels: usize) -> (Vec<MeshletRecord>, Vec<NodeRecord>) {
        let sphere = [0.0, 0.0, 0.0, 1.0];
        let meshlet = MeshletRecord {
            bounds: sphere,
            parent_group: NO_GROUP,
            source_group: NO_GROUP,
            ..bytemuck::Zeroable::zeroed()
        };
        let nodes = (0..levels)
            .map(|i| NodeRecord {
                bounds: sphere,
                lod_sphere: sphere,
                min_error: 0.0,
                max_parent_error: ROOT_PARENT_ERROR,
                first_child: if i + 1 < levels { i as u32 + 1 } else { 0 },
                child_count: u32::from(i + 1 < levels),
                first_cluster: 0,
                cluster_count: 1,
                reserved: [0; 2],
            })
            .collect();
        (vec![meshlet], nodes)
    }

    #[test]
    fn a_hierarchy_deeper_than_the_gpu_walk_reaches_is_refused() {
        let (meshlets, nodes) = chain(MAX_DEPTH as usize);
        hierarchy(&meshlets, &[], &nodes, &[0]).unwrap_or_else(|e| panic!("{e:?}"));
        let (meshlets, nodes) = chain(MAX_DEPTH as usize + 1);
        let e = hierarchy(&meshlets, &[], &nodes, &[0]).unwrap_err();
        assert_eq!(e.field, format!("node[{MAX_DEPTH}]"));
        assert!(e.problem.contains("never reaches"), "{e:?}");
    }
}
