//! LOD 0's open edges as baked: recorded by the bake, and a load that finds LOD 0 open
//! anywhere else (a meshlet's grid origin moved, a vertex bit flipped) refuses the asset,
//! while a mesh that was open when baked (the teapot's rim, a height field's border)
//! still loads.

mod common;

use std::path::Path;
use std::sync::OnceLock;

use common::damage::{record_mut, reseal};
use meshlight_scene::asset::format::{
    AssetHeader, MeshletRecord, OpenEdgeRecord, SECTION_MESHLETS, SECTION_OPEN_EDGES,
    SECTION_PAYLOAD,
};
use meshlight_scene::load::load_mesh;
use meshlight_scene::open_edges::decoded_lod0_chain;
use meshlight_scene::verify::verify;
use meshlight_scene::watertight::crack_problems;
use meshlight_scene::{BuildOptions, MeshletAsset, Terrain, build_asset, procedural_mesh};

fn words_of(asset: &MeshletAsset) -> Vec<u32> {
    bytemuck::cast_slice(asset.bytes()).to_vec()
}

/// Reseals `words` and loads them (the structural checks), for the DAG checks to judge.
fn load(mut words: Vec<u32>) -> MeshletAsset {
    reseal(&mut words);
    let len = words.len() as u64 * 4;
    MeshletAsset::from_words(words, len, Path::new("open.mlasset")).expect("structurally sound")
}

fn lod0_problem(asset: &MeshletAsset) -> Option<String> {
    verify(asset)
        .into_iter()
        .find(|p| p.contains("LOD 0 is open"))
}

/// A height field of 24 × 24 cells, baked once: open along its border.
fn terrain() -> &'static MeshletAsset {
    static ASSET: OnceLock<MeshletAsset> = OnceLock::new();
    ASSET.get_or_init(|| {
        let terrain = Terrain {
            origin: glam::Vec2::new(-4.0, -4.0),
            size: 8.0,
            cells: 24,
            amplitude: 1.0,
            wavelength: 4.0,
            octaves: 2,
            seed: 3,
            uv_scale: 0.5,
            calm_centre: glam::Vec2::ZERO,
            calm_radius: 0.0,
        };
        build_asset(
            &terrain.mesh().unwrap(),
            &BuildOptions::default(),
            &mut |_| {},
        )
        .unwrap()
        .asset
    })
}

/// The closed procedural knot of 12 segments, baked once.
fn knot() -> &'static MeshletAsset {
    static ASSET: OnceLock<MeshletAsset> = OnceLock::new();
    ASSET.get_or_init(|| {
        build_asset(&procedural_mesh(12), &BuildOptions::default(), &mut |_| {})
            .unwrap()
            .asset
    })
}

/// The recorded chain is the decoded one: none for the closed procedural mesh, the rim
/// and its non-manifold edges for the teapot, the border for a height field; and every
/// one verifies.
#[test]
fn the_bake_records_lod0s_open_edges() {
    let knot = knot();
    assert!(knot.open_edges().is_empty());
    let teapot = load_mesh(&common::shared_mesh("teapot.obj")).unwrap();
    let teapot = build_asset(&teapot, &BuildOptions::default(), &mut |_| {})
        .unwrap()
        .asset;
    let terrain = terrain();
    // The height field's border: 24 cells a side, each cell edge one grid edge.
    assert_eq!(terrain.open_edges().len(), 4 * 24);
    assert!(!teapot.open_edges().is_empty());
    for (name, asset) in [("knot", knot), ("teapot", &teapot), ("terrain", terrain)] {
        assert_eq!(decoded_lod0_chain(asset), asset.open_edges(), "{name}");
        assert_eq!(verify(asset), Vec::<String>::new(), "{name}");
    }
}

/// Every LOD-0 meshlet of a closed and of an open mesh, its grid origin moved one step:
/// each is refused. The crack check alone misses some of them (meshlets inside their
/// group, whose moved edges no other group uses), which is why LOD 0 is recorded.
#[test]
fn a_lod0_meshlet_moved_one_grid_step_is_refused() {
    let knot = knot();
    let mut crack_check_missed = 0;
    for (name, asset) in [("knot", knot), ("terrain", terrain())] {
        let words = words_of(asset);
        let lod0: Vec<usize> = (0..asset.meshlets().len())
            .filter(|&i| asset.meshlets()[i].level() == 0)
            .collect();
        assert!(lod0.len() > 8, "{name}: {} LOD-0 meshlets", lod0.len());
        for &m in &lod0 {
            let mut w = words.clone();
            let record: &mut MeshletRecord = record_mut(&mut w, SECTION_MESHLETS, m);
            // Along the axis with room to move inside the grid.
            let axis = (0..3).find(|&k| record.grid_min[k] > 0).unwrap();
            record.grid_min[axis] -= 1;
            let moved = load(w);
            let problem = lod0_problem(&moved)
                .unwrap_or_else(|| panic!("{name}: meshlet {m} moved, LOD 0 passed"));
            assert!(problem.contains("bake the source again"), "{problem}");
            crack_check_missed += crack_problems(&moved).is_empty() as usize;
        }
    }
    assert!(crack_check_missed > 0);
}

/// One bit of a LOD-0 vertex on a meshlet's border flipped in the payload: the vertex
/// leaves its neighbours, and the asset is refused.
#[test]
fn a_flipped_bit_in_a_border_vertex_is_refused() {
    let asset = knot();
    let m = (0..asset.meshlets().len())
        .find(|&i| asset.meshlets()[i].level() == 0)
        .unwrap();
    let record = asset.meshlets()[m];
    let grid = asset.decode_grid(m);
    // A vertex another LOD-0 meshlet also holds: on the border.
    let others: std::collections::HashSet<[u32; 3]> = (0..asset.meshlets().len())
        .filter(|&i| i != m && asset.meshlets()[i].level() == 0)
        .flat_map(|i| asset.decode_grid(i))
        .collect();
    let v = grid.iter().position(|p| others.contains(p)).unwrap();
    // The lowest bit of its offset along the first axis the meshlet spans (a record's
    // fields: x, y, z offsets, then the normal).
    let bits = record.axis_bits();
    let axis = (0..3).find(|&k| bits[k] > 0).unwrap();
    let bit = v as u64 * record.vertex_stride() as u64 + bits[..axis].iter().sum::<u32>() as u64;
    let payload = asset.header().sections[SECTION_PAYLOAD].offset as u64;
    let word = (payload + record.data_offset as u64 + bit / 32) as usize;
    let mut w = words_of(asset);
    w[word] ^= 1 << (bit % 32);
    let flipped = load(w);
    assert_ne!(flipped.decode_grid(m)[v], grid[v]);
    assert!(lod0_problem(&flipped).is_some(), "{:?}", verify(&flipped));
}

/// An open mesh whose record no longer matches: an edge left out, or one reversed. The
/// meshlets are unchanged, so only the comparison with the record can see it.
#[test]
fn an_open_edge_record_that_does_not_match_lod0_is_refused() {
    let asset = terrain();
    let words = words_of(asset);
    let h: AssetHeader = *asset.header();
    let section = h.sections[SECTION_OPEN_EDGES];
    let size = size_of::<OpenEdgeRecord>() / 4;

    // The last record cut out (the section one record shorter, the payload after it).
    let mut w = words.clone();
    let end = (section.offset + section.words) as usize;
    w.drain(end - size..end);
    {
        let h: &mut AssetHeader =
            bytemuck::from_bytes_mut(bytemuck::cast_slice_mut(&mut w[..AssetHeader::WORDS]));
        h.sections[SECTION_OPEN_EDGES].words -= size as u32;
        h.sections[SECTION_PAYLOAD].offset -= size as u32;
    }
    let cut = load(w);
    let problem = lod0_problem(&cut).expect("a missing open edge");
    assert!(problem.contains("1 differ"), "{problem}");

    // The first record reversed: the same edge, the other way.
    let mut w = words.clone();
    let r: &mut OpenEdgeRecord = record_mut(&mut w, SECTION_OPEN_EDGES, 0);
    std::mem::swap(&mut r.from, &mut r.to);
    assert!(lod0_problem(&load(w)).is_some());

    // Untouched, resealed: passes.
    assert_eq!(lod0_problem(&load(words)), None);
}

/// The record's own form is checked at load, before any DAG check: whole records, two
/// different points on the grid, a use, ascending order.
#[test]
fn a_malformed_open_edge_record_is_refused_at_load() {
    let words = words_of(terrain());
    let quant_bits = terrain().header().quant_bits;
    let refused = |what: &str, field: &str, edit: &dyn Fn(&mut Vec<u32>)| {
        let mut w = words.clone();
        edit(&mut w);
        reseal(&mut w);
        let len = w.len() as u64 * 4;
        match MeshletAsset::from_words(w, len, Path::new("open.mlasset")) {
            Err(meshlight_scene::SceneError::AssetField { field: f, .. }) => {
                assert!(f.contains(field), "{what}: named {f}")
            }
            other => panic!("{what}: {:?}", other.map(|_| ())),
        }
    };
    let edge = |w: &mut Vec<u32>, i: usize| -> OpenEdgeRecord {
        *record_mut::<OpenEdgeRecord>(w, SECTION_OPEN_EDGES, i)
    };
    refused("an edge from a point to itself", "open_edge[2].to", &|w| {
        let r: &mut OpenEdgeRecord = record_mut(w, SECTION_OPEN_EDGES, 2);
        r.to = r.from;
    });
    refused("no use", "open_edge[0].uses", &|w| {
        record_mut::<OpenEdgeRecord>(w, SECTION_OPEN_EDGES, 0).uses = 0
    });
    refused(
        "more uses than LOD 0 has edges",
        "open_edge[0].uses",
        &|w| record_mut::<OpenEdgeRecord>(w, SECTION_OPEN_EDGES, 0).uses = u32::MAX,
    );
    refused("off the grid", "open_edge[1].from/to", &|w| {
        record_mut::<OpenEdgeRecord>(w, SECTION_OPEN_EDGES, 1).from[2] = 1 << quant_bits
    });
    refused("out of order", "open_edge[1].from/to", &|w| {
        let (a, b) = (edge(w, 0), edge(w, 1));
        *record_mut::<OpenEdgeRecord>(w, SECTION_OPEN_EDGES, 0) = b;
        *record_mut::<OpenEdgeRecord>(w, SECTION_OPEN_EDGES, 1) = a;
    });
    refused("an edge twice", "open_edge[1].from/to", &|w| {
        let a = edge(w, 0);
        *record_mut::<OpenEdgeRecord>(w, SECTION_OPEN_EDGES, 1) = a;
    });
    refused("a part record", "sections[6].words", &|w| {
        let h: &mut AssetHeader =
            bytemuck::from_bytes_mut(bytemuck::cast_slice_mut(&mut w[..AssetHeader::WORDS]));
        h.sections[SECTION_OPEN_EDGES].words -= 1;
        h.sections[SECTION_PAYLOAD].offset -= 1;
        let at = h.sections[SECTION_PAYLOAD].offset as usize;
        w.remove(at);
    });
}
