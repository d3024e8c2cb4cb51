//! The fuzz target: proptest over mutated files, for the asset loader and every mesh
//! loader. A case passes when loading returns (an error or a value) without panicking,
//! and whatever loads can be built, verified, decoded and summarised without panicking.
//!
//! `MESHLIGHT_FUZZ_CASES=N` sets the random cases per target (default 300, which keeps the
//! suite short); each target prints how many ran and fails if fewer did. The field-by-field
//! asset target also runs every field of two small assets through every fixed mutation
//! first, whatever N is.

mod common;

use std::path::Path;

use meshlight_scene::asset::checksum::seal;
use meshlight_scene::asset::format::{
    AssetHeader, GroupRecord, MeshletRecord, NodeRecord, OpenEdgeRecord, SECTION_CHILDREN,
    SECTION_GROUPS, SECTION_MESHLETS, SECTION_NODE_CLUSTERS, SECTION_NODES, SECTION_OPEN_EDGES,
    SECTION_PAYLOAD,
};
use meshlight_scene::load::{load_gltf_scene, load_mesh, parse_obj, parse_stl};
use meshlight_scene::{
    BuildOptions, Mesh, MeshletAsset, SceneError, Terrain, build_asset, procedural_mesh,
};
use proptest::prelude::*;
use proptest::test_runner::{Config, TestRunner};

fn cases() -> u32 {
    std::env::var("MESHLIGHT_FUZZ_CASES")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(300)
}

/// Runs `strategy` through `test` for [`cases`] cases and checks they all ran.
fn fuzz<S: Strategy>(name: &str, strategy: S, test: impl Fn(S::Value))
where
    S::Value: std::fmt::Debug,
{
    let ran = std::cell::Cell::new(0u32);
    let mut runner = TestRunner::new(Config {
        cases: cases(),
        failure_persistence: None,
        ..Config::default()
    });
    runner
        .run(&strategy, |v| {
            ran.set(ran.get() + 1);
            test(v);
            Ok(())
        })
        .unwrap();
    println!("{name}: {} cases ran", ran.get());
    assert!(ran.get() >= cases(), "{name}: only {} cases ran", ran.get());
}

/// Builds whatever a loader accepted: cleaning and the DAG must cope with it too.
fn build_if_loaded(mesh: Result<Mesh, meshlight_scene::SceneError>) {
    if let Ok(mesh) = mesh {
        let _ = build_asset(&mesh, &BuildOptions::default(), &mut |_| {});
    }
}

/// A glTF file both ways: merged into one mesh, and as a scene (each of its meshes built).
fn build_gltf_if_loaded(path: &Path) {
    build_if_loaded(load_mesh(path));
    if let Ok(scene) = load_gltf_scene(path) {
        for m in scene.meshes {
            build_if_loaded(Ok(m.mesh));
        }
    }
}

/// Values that tend to break counts, offsets and floats.
fn interesting_word() -> impl Strategy<Value = u32> {
    prop_oneof![
        Just(0u32),
        Just(1),
        Just(2),
        Just(3),
        Just(255),
        Just(256),
        Just(0xffff),
        Just(1 << 24),
        Just(u32::MAX),
        Just(u32::MAX - 1),
        Just(f32::NAN.to_bits()),
        Just(f32::INFINITY.to_bits()),
        Just((-1.0f32).to_bits()),
        Just(1e38f32.to_bits()),
        Just(0.0f32.to_bits()),
        any::<u32>(),
    ]
}

#[test]
fn fuzz_asset_loader() {
    let good: Vec<u32> = bytemuck::cast_slice(
        build_asset(&procedural_mesh(6), &BuildOptions::default(), &mut |_| {})
            .unwrap()
            .asset
            .bytes(),
    )
    .to_vec();
    let header: AssetHeader =
        *bytemuck::from_bytes(bytemuck::cast_slice(&good[..AssetHeader::WORDS]));
    let records = header.sections[SECTION_MESHLETS];
    let n = good.len();
    // Where to write: the header, the meshlet records, or anywhere; what; whether to fix
    // the checksum (so that the structural checks, not the checksum, must notice).
    let edit = (0u8..3, any::<prop::sample::Index>(), interesting_word());
    let strategy = (prop::collection::vec(edit, 1..6), any::<bool>(), 0usize..3);
    fuzz("asset", strategy, |(edits, reseal, cut)| {
        let mut w = good.clone();
        for (region, at, value) in edits {
            let i = match region {
                0 => at.index(AssetHeader::WORDS),
                1 => records.offset as usize + at.index(records.words as usize),
                _ => at.index(n),
            };
            w[i] = value;
        }
        if cut > 0 {
            w.truncate(n - cut);
        }
        if reseal {
            seal(&mut w);
        }
        let len = w.len() as u64 * 4;
        if let Ok(asset) = MeshletAsset::from_words(w, len, Path::new("fuzz.mlasset")) {
            use_everything(&asset);
        }
    });
}

/// What a tool may do with an asset that loads: none of it may panic, whether or not the
/// DAG checks pass.
fn use_everything(asset: &MeshletAsset) {
    let _ = meshlight_scene::verify::verify(asset);
    let _ = meshlight_scene::verify::quality(asset);
    let _ = meshlight_scene::asset::summary::AssetSummary::of(asset);
    let _ = asset.size_breakdown();
    for i in 0..asset.meshlets().len() {
        let _ = asset.decode_meshlet(i);
    }
    for m in asset.meshlets() {
        let _ = (asset.lod(m), asset.parent_lod(m));
    }
    for n in asset.nodes() {
        let _ = asset.node_meshlets(n);
    }
}

/// One 32-bit field of an asset file: what it is called in errors, its word in the file,
/// whether it holds a float, and for a field of a record, the record kind and index (so
/// that a mutation can swap it with the same field of another record).
#[derive(Debug, Clone)]
struct Field {
    name: String,
    word: usize,
    float: bool,
    record: Option<(usize, usize)>,
    /// Which part of the file: the header, a record kind or a word section (see
    /// [`REGIONS`]), so that random cases pick parts evenly, not mostly payload words.
    region: usize,
}

/// The parts of a file [`Field::region`] numbers.
const REGIONS: usize = 8;

/// A record's fields: name, byte offset, 32-bit words, float or not.
type Layout = &'static [(&'static str, usize, usize, bool)];

/// A [`Layout`] from a record's fields, each as `name: words type` with the type of its
/// words (`u32` or `f32`): the name and the offset both come from the one identifier,
/// so an entry cannot pair a name with another field's offset.
macro_rules! layout {
    (@float f32) => {
        true
    };
    (@float u32) => {
        false
    };
    ($t:ty { $($field:ident: $words:literal $word:ident),* $(,)? }) => {
        &[$((
            stringify!($field),
            std::mem::offset_of!($t, $field),
            $words,
            layout!(@float $word),
        )),*]
    };
}

const HEADER: Layout = layout!(AssetHeader {
    magic: 2 u32,
    version: 1 u32,
    flags: 1 u32,
    file_size: 2 u32,
    checksum: 2 u32,
    meshlet_count: 1 u32,
    group_count: 1 u32,
    node_count: 1 u32,
    level_count: 1 u32,
    root_count: 1 u32,
    lod0_meshlets: 1 u32,
    lod0_triangles: 1 u32,
    total_triangles: 1 u32,
    total_vertices: 1 u32,
    lod0_vertices: 1 u32,
    input_triangles: 1 u32,
    dropped_degenerate: 1 u32,
    dropped_duplicate: 1 u32,
    material_count: 1 u32,
    resident_words: 1 u32,
    bounds_min: 3 f32,
    bounds_max: 3 f32,
    quant_origin: 3 f32,
    quant_step: 1 f32,
    quant_bits: 1 u32,
    uv_min: 2 f32,
    uv_step: 2 f32,
    sections: 16 u32,
});

const MESHLET: Layout = layout!(MeshletRecord {
    bounds: 4 f32,
    source_group: 1 u32,
    parent_group: 1 u32,
    data_offset: 1 u32,
    counts: 1 u32,
    grid_min: 3 u32,
    bits: 1 u32,
    normals: 1 u32,
});

const GROUP: Layout = layout!(GroupRecord {
    lod_sphere: 4 f32,
    error: 1 f32,
    level: 1 u32,
    first_child: 1 u32,
    child_count: 1 u32,
});

const OPEN_EDGE: Layout = layout!(OpenEdgeRecord {
    from: 3 u32,
    to: 3 u32,
    uses: 1 u32,
});

const NODE: Layout = layout!(NodeRecord {
    bounds: 4 f32,
    lod_sphere: 4 f32,
    min_error: 1 f32,
    max_parent_error: 1 f32,
    first_child: 1 u32,
    child_count: 1 u32,
    first_cluster: 1 u32,
    cluster_count: 1 u32,
    reserved: 2 u32,
});

/// Every 32-bit field of a valid asset: the header's, every record's, and every word of
/// the child lists, the payload and the cluster list.
fn fields(words: &[u32]) -> Vec<Field> {
    let h: &AssetHeader = bytemuck::from_bytes(bytemuck::cast_slice(&words[..AssetHeader::WORDS]));
    let mut out = Vec::new();
    let mut layout = |name: &str, base: usize, layout: Layout, record: Option<(usize, usize)>| {
        for &(field, offset, count, float) in layout {
            for k in 0..count {
                out.push(Field {
                    name: format!("{name}.{field}[{k}]"),
                    word: base + offset / 4 + k,
                    float,
                    record,
                    region: record.map_or(0, |(kind, _)| 1 + kind),
                });
            }
        }
    };
    layout("header", 0, HEADER, None);
    for (kind, (section, name, record)) in [
        (SECTION_MESHLETS, "meshlet", MESHLET),
        (SECTION_GROUPS, "group", GROUP),
        (SECTION_NODES, "node", NODE),
        (SECTION_OPEN_EDGES, "open_edge", OPEN_EDGE),
    ]
    .into_iter()
    .enumerate()
    {
        let s = h.sections[section];
        let size = record
            .iter()
            .map(|&(_, o, c, _)| o / 4 + c)
            .max()
            .unwrap_or(1);
        for i in 0..s.words as usize / size {
            layout(
                &format!("{name}[{i}]"),
                s.offset as usize + i * size,
                record,
                Some((kind, i)),
            );
        }
    }
    for (region, (section, name)) in [
        (SECTION_CHILDREN, "children"),
        (SECTION_PAYLOAD, "payload"),
        (SECTION_NODE_CLUSTERS, "node_clusters"),
    ]
    .into_iter()
    .enumerate()
    {
        let s = h.sections[section];
        for k in 0..s.words as usize {
            out.push(Field {
                name: format!("{name}[{k}]"),
                word: s.offset as usize + k,
                float: false,
                record: None,
                region: 5 + region,
            });
        }
    }
    out
}

/// A change to one field.
#[derive(Debug, Clone, Copy)]
enum Mutation {
    Set(u32),
    Add(i32),
    FlipBit(u32),
    SetFloat(f32),
    ScaleFloat(f32),
    /// Exchange with the same field of another record of the kind (the number picks
    /// which), or, for a field of no record, with the field that many fields on.
    Swap(usize),
}

/// Float values that break comparisons, products and ranges.
const SPECIAL_FLOATS: [f32; 12] = [
    f32::NAN,
    f32::INFINITY,
    f32::NEG_INFINITY,
    -0.0,
    0.0,
    f32::MAX,
    f32::MIN,
    f32::MIN_POSITIVE,
    1e-45,
    -1.0,
    1e30,
    1e-30,
];

/// The mutations every field goes through in the systematic pass (payload words, which
/// are most of a file and alike, through fewer).
fn fixed_mutations(field: &Field) -> Vec<Mutation> {
    if field.name.starts_with("payload") {
        return vec![
            Mutation::Set(0),
            Mutation::Set(u32::MAX),
            Mutation::FlipBit(0),
            Mutation::FlipBit(31),
            Mutation::Swap(1),
        ];
    }
    let mut m = vec![
        Mutation::Set(0),
        Mutation::Set(u32::MAX),
        Mutation::Set(1),
        Mutation::Add(1),
        Mutation::Add(-1),
        Mutation::FlipBit(0),
        Mutation::FlipBit(31),
        Mutation::Swap(1),
    ];
    if field.float {
        m.extend(SPECIAL_FLOATS.map(Mutation::SetFloat));
        m.extend([0.5, 2.0, -1.0, 1.0 + f32::EPSILON].map(Mutation::ScaleFloat));
    } else {
        m.extend([
            Mutation::Set(0x8000_0000),
            Mutation::Set(0xff),
            Mutation::Set(1 << 24),
        ]);
    }
    m
}

/// Applies `mutation` to field `f` of `words`.
fn mutate(words: &mut [u32], fields: &[Field], f: usize, mutation: Mutation) {
    let field = &fields[f];
    let w = &mut words[field.word];
    match mutation {
        Mutation::Set(v) => *w = v,
        Mutation::Add(d) => *w = w.wrapping_add_signed(d),
        Mutation::FlipBit(b) => *w ^= 1 << (b % 32),
        Mutation::SetFloat(v) => *w = v.to_bits(),
        Mutation::ScaleFloat(s) => *w = (f32::from_bits(*w) * s).to_bits(),
        Mutation::Swap(step) => {
            // The same field of another record of the kind, or the next field's word.
            let other = match field.record {
                Some((kind, i)) => {
                    let suffix = &field.name[field.name.find('.').unwrap_or(0)..];
                    let same: Vec<usize> = fields
                        .iter()
                        .enumerate()
                        .filter(|(_, g)| {
                            g.record.is_some_and(|(k, j)| k == kind && j != i)
                                && g.name.ends_with(suffix)
                        })
                        .map(|(k, _)| k)
                        .collect();
                    same.get(step % same.len().max(1)).copied()
                }
                None => Some((f + step) % fields.len()),
            };
            if let Some(o) = other {
                words.swap(field.word, fields[o].word);
            }
        }
    }
}

/// Recomputes what the header sums up from the meshlet records (LOD-0 counts, totals,
/// roots, levels) and chains the records' data offsets where their payload still adds up
/// to the section, so that a changed record passes the sums and reaches the checks after
/// them. Does nothing where the sections no longer lie within the file.
fn repair_sums(words: &mut [u32]) {
    let h: AssetHeader = *bytemuck::from_bytes(bytemuck::cast_slice(&words[..AssetHeader::WORDS]));
    let (records, payload) = (h.sections[SECTION_MESHLETS], h.sections[SECTION_PAYLOAD]);
    let size = size_of::<MeshletRecord>() / 4;
    let end = records.offset as u64 + records.words as u64;
    if end > words.len() as u64 || !(records.words as usize).is_multiple_of(size) {
        return;
    }
    let mut meshlets: Vec<MeshletRecord> =
        bytemuck::cast_slice(&words[records.offset as usize..end as usize]).to_vec();
    let (mut lod0_meshlets, mut lod0_triangles, mut triangles, mut vertices, mut roots) =
        (0u32, 0u32, 0u32, 0u32, 0u32);
    let mut top = 0;
    let mut at = 0u64;
    for m in &meshlets {
        if m.level() == 0 {
            lod0_meshlets += 1;
            lod0_triangles = lod0_triangles.wrapping_add(m.triangle_count());
        }
        triangles = triangles.wrapping_add(m.triangle_count());
        vertices = vertices.wrapping_add(m.vertex_count());
        roots += (m.parent_group == u32::MAX) as u32;
        top = top.max(m.level());
        at += meshlight_scene::asset::format::PayloadLayout::of(m, h.flags).end as u64;
    }
    if at == payload.words as u64 {
        let mut at = 0;
        for m in &mut meshlets {
            m.data_offset = at;
            at += meshlight_scene::asset::format::PayloadLayout::of(m, h.flags).end;
        }
        words[records.offset as usize..end as usize]
            .copy_from_slice(bytemuck::cast_slice(&meshlets));
    }
    let header: &mut AssetHeader =
        bytemuck::from_bytes_mut(bytemuck::cast_slice_mut(&mut words[..AssetHeader::WORDS]));
    header.lod0_meshlets = lod0_meshlets;
    header.lod0_triangles = lod0_triangles;
    header.total_triangles = triangles;
    header.total_vertices = vertices;
    header.root_count = roots;
    header.level_count = top + 1;
}

/// Rewrites the checksum over the mutated file, so that the checks after it see the
/// mutation (a mutation of the checksum itself is kept: the checksum check sees that).
fn reseal(words: &mut [u32], fields: &[Field], mutated: &[usize]) {
    let at = std::mem::offset_of!(AssetHeader, checksum) / 4;
    if mutated
        .iter()
        .any(|&f| (at..at + 2).contains(&fields[f].word))
    {
        return;
    }
    seal(words);
}

/// How a mutated file fared.
#[derive(Debug, Default)]
struct Outcomes {
    /// Loaded and passed every check (a change no check can see, such as a normal's bit).
    loaded: u64,
    /// Refused, by the kind of error.
    refused: std::collections::BTreeMap<&'static str, u64>,
}

/// Loads `words` as the renderer does (the structural checks, then the DAG checks) and
/// holds the result to the contract: a typed asset error naming the file, or an asset
/// that `check_all` accepts and every tool can use.
fn load_mutated(words: Vec<u32>, outcomes: &mut Outcomes) {
    let path = Path::new("fuzz.mlasset");
    let len = words.len() as u64 * 4;
    let loaded = MeshletAsset::from_words(words, len, path).and_then(|asset| {
        use_everything(&asset);
        asset.verify_dag(path).map(|()| asset)
    });
    match loaded {
        Ok(asset) => {
            if let Err(e) = asset.check_all(path) {
                panic!("loaded, but check_all refuses it: {e}");
            }
            // What the fingerprint check passed, edge by edge: LOD 0 is open exactly
            // where the bake recorded.
            assert_eq!(
                meshlight_scene::open_edges::decoded_lod0_chain(&asset),
                asset.open_edges(),
                "verified, but LOD 0's open edges are not the recorded ones"
            );
            outcomes.loaded += 1;
        }
        Err(e) => {
            let kind = match &e {
                SceneError::AssetMagic { .. } => "magic",
                SceneError::AssetVersion { .. } => "version",
                SceneError::AssetTruncated { .. } => "truncated",
                SceneError::AssetChecksum { .. } => "checksum",
                // A header field that moves the pages (now in the header's layout).
                SceneError::AssetPageChecksum { .. } => "page checksum",
                SceneError::AssetField { .. } => "field",
                SceneError::AssetCorrupt { .. } => "DAG",
                other => panic!("not an asset error: {other:?}"),
            };
            assert!(e.to_string().contains("fuzz.mlasset"), "{e}");
            *outcomes.refused.entry(kind).or_default() += 1;
        }
    }
}

/// Two small valid assets: the procedural mesh's (no UVs) and a height field's (UVs).
fn base_assets() -> Vec<Vec<u32>> {
    let terrain = Terrain {
        origin: glam::Vec2::new(-4.0, -4.0),
        size: 8.0,
        cells: 12,
        amplitude: 1.0,
        wavelength: 4.0,
        octaves: 2,
        seed: 1,
        uv_scale: 0.5,
        calm_centre: glam::Vec2::ZERO,
        calm_radius: 0.0,
    };
    [procedural_mesh(6), terrain.mesh().unwrap()]
        .iter()
        .map(|mesh| {
            let built = build_asset(mesh, &BuildOptions::default(), &mut |_| {}).unwrap();
            bytemuck::cast_slice(built.asset.bytes()).to_vec()
        })
        .collect()
}

/// Valid assets changed field by field, checksum rewritten: first every field of both
/// assets through every fixed mutation, then random combinations of up to four
/// mutations (any value, any bit, any special float, swaps), half of them with the
/// header's sums made to agree with the changed records.
#[test]
fn fuzz_asset_fields() {
    let start = std::time::Instant::now();
    let bases = base_assets();
    let catalogs: Vec<Vec<Field>> = bases.iter().map(|w| fields(w)).collect();
    // Per asset, its fields by region.
    let regions: Vec<Vec<Vec<usize>>> = catalogs
        .iter()
        .map(|fields| {
            let mut r = vec![Vec::new(); REGIONS];
            for (f, field) in fields.iter().enumerate() {
                r[field.region].push(f);
            }
            r
        })
        .collect();
    let mut outcomes = Outcomes::default();
    let mut systematic = 0u64;
    for (good, fields) in bases.iter().zip(&catalogs) {
        for f in 0..fields.len() {
            // A meshlet record's change also with the header's sums made to agree.
            let repairs: &[bool] = match fields[f].record {
                Some((0, _)) => &[false, true],
                _ => &[false],
            };
            for mutation in fixed_mutations(&fields[f]) {
                for &repair in repairs {
                    let mut w = good.clone();
                    mutate(&mut w, fields, f, mutation);
                    if repair {
                        repair_sums(&mut w);
                    }
                    reseal(&mut w, fields, &[f]);
                    load_mutated(w, &mut outcomes);
                    systematic += 1;
                }
            }
        }
    }
    let outcomes = std::cell::RefCell::new(outcomes);
    let mutation = prop_oneof![
        interesting_word().prop_map(Mutation::Set),
        (-2i32..=2).prop_map(Mutation::Add),
        (0u32..32).prop_map(Mutation::FlipBit),
        prop::sample::select(SPECIAL_FLOATS.to_vec()).prop_map(Mutation::SetFloat),
        prop::sample::select(vec![0.5f32, 2.0, -1.0, 1.0 + f32::EPSILON, 1e10])
            .prop_map(Mutation::ScaleFloat),
        (1usize..8).prop_map(Mutation::Swap),
    ];
    let strategy = (
        0..bases.len(),
        prop::collection::vec((0..REGIONS, any::<prop::sample::Index>(), mutation), 1..=4),
        any::<bool>(),
    );
    fuzz("asset fields", strategy, |(base, edits, repair)| {
        let fields = &catalogs[base];
        let mut w = bases[base].clone();
        let mut mutated = Vec::new();
        for (region, at, mutation) in edits {
            let in_region = &regions[base][region];
            // A closed mesh has no open edges to change.
            if in_region.is_empty() {
                continue;
            }
            let f = in_region[at.index(in_region.len())];
            mutate(&mut w, fields, f, mutation);
            mutated.push(f);
        }
        if repair {
            repair_sums(&mut w);
        }
        reseal(&mut w, fields, &mutated);
        load_mutated(w, &mut outcomes.borrow_mut());
    });
    let outcomes = outcomes.into_inner();
    println!(
        "asset fields: {systematic} systematic and {} random cases in {:.1} s: {} loaded, \
         refused {:?}",
        cases(),
        start.elapsed().as_secs_f64(),
        outcomes.loaded,
        outcomes.refused
    );
}

const OBJ: &str = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nvt 0 0\nvt 1 0\nvt 0 1\nvn 0 0 1\n\
                   f 1/1/1 3/3/1 2/2/1\nf 1/1/1 2/2/1 4/1/1\nf 1/1/1 4/2/1 3/3/1\nf 2/1/1 3/2/1 4/3/1\n";

/// Byte edits: (position, replacement) pairs, replacements from the format's alphabet.
fn byte_edits(alphabet: &'static [u8]) -> impl Strategy<Value = Vec<(prop::sample::Index, u8)>> {
    prop::collection::vec(
        (any::<prop::sample::Index>(), prop::sample::select(alphabet)),
        1..8,
    )
}

#[test]
fn fuzz_obj_loader() {
    fuzz("obj", byte_edits(b" \n0123456789-.e/fvtn#"), |edits| {
        let mut text = OBJ.as_bytes().to_vec();
        for (at, b) in edits {
            let i = at.index(text.len());
            text[i] = b;
        }
        build_if_loaded(parse_obj(Path::new("fuzz.obj"), &text));
    });
}

fn binary_stl() -> Vec<u8> {
    let (p, idx) = common::tetrahedron();
    let mut stl = vec![0u8; 80];
    stl.extend_from_slice(&4u32.to_le_bytes());
    for t in idx.chunks(3) {
        stl.extend_from_slice(&[0u8; 12]);
        for &i in t {
            for c in p[i as usize] {
                stl.extend_from_slice(&c.to_le_bytes());
            }
        }
        stl.extend_from_slice(&[0u8; 2]);
    }
    stl
}

#[test]
fn fuzz_stl_loader() {
    let good = binary_stl();
    let strategy = (
        prop::collection::vec((any::<prop::sample::Index>(), interesting_word()), 1..6),
        any::<bool>(),
    );
    fuzz("stl", strategy, |(edits, ascii)| {
        let bytes = if ascii {
            let mut text = b"solid t\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 0 1 0\nendloop\nendfacet\nendsolid t\n".to_vec();
            for (at, v) in edits {
                let i = at.index(text.len());
                text[i] = b" \n0123456789-.eE+nafiouterlopvx"[v as usize % 31];
            }
            text
        } else {
            let mut b = good.clone();
            for (at, v) in edits {
                // Word-aligned within the body, or the count field.
                let i = 80 + at.index((b.len() - 80) / 4) * 4;
                b[i..i + 4].copy_from_slice(&v.to_le_bytes());
            }
            b
        };
        build_if_loaded(parse_stl(Path::new("fuzz.stl"), &bytes));
    });
}

/// A small valid glTF: two nodes instancing a tetrahedron with UVs, and a camera node.
fn gltf_text() -> String {
    let (p, idx) = common::tetrahedron();
    let mut buf: Vec<u8> = bytemuck::cast_slice(&p).to_vec();
    buf.extend_from_slice(bytemuck::cast_slice(&idx));
    let uvs: [[f32; 2]; 4] = [[0.0, 0.0], [1.0, 0.0], [0.0, 1.0], [1.0, 1.0]];
    buf.extend_from_slice(bytemuck::cast_slice(&uvs));
    format!(
        r#"{{"asset":{{"version":"2.0"}},"scene":0,"scenes":[{{"nodes":[0]}}],
        "nodes":[{{"children":[1,2,3]}},{{"mesh":0,"translation":[10,0,0]}},{{"mesh":0,"scale":[-1,1,1]}},{{"camera":0,"translation":[0,1,5]}}],
        "cameras":[{{"type":"perspective","perspective":{{"yfov":0.8,"znear":0.1}}}}],
        "meshes":[{{"primitives":[{{"attributes":{{"POSITION":0,"TEXCOORD_0":2}},"indices":1,"mode":4}}]}}],
        "buffers":[{{"byteLength":{},"uri":"data:application/octet-stream;base64,{}"}}],
        "bufferViews":[{{"buffer":0,"byteOffset":0,"byteLength":48}},{{"buffer":0,"byteOffset":48,"byteLength":24}},{{"buffer":0,"byteOffset":72,"byteLength":32,"byteStride":8}}],
        "accessors":[{{"bufferView":0,"componentType":5126,"count":4,"type":"VEC3"}},
                     {{"bufferView":1,"componentType":5123,"count":12,"type":"SCALAR"}},
                     {{"bufferView":2,"componentType":5126,"count":4,"type":"VEC2"}}]}}"#,
        buf.len(),
        common::base64(&buf)
    )
}

/// The byte ranges of the JSON's bare numbers (outside the base64 string).
fn number_spans(text: &str) -> Vec<(usize, usize)> {
    let data = text.find("data:").unwrap_or(text.len());
    let end = data + text[data..].find('"').unwrap_or(0);
    let b = text.as_bytes();
    let mut spans = Vec::new();
    let mut i = 0;
    while i < b.len() {
        if (data..end).contains(&i) {
            i = end;
            continue;
        }
        if b[i].is_ascii_digit() && (i == 0 || !b[i - 1].is_ascii_alphanumeric()) {
            let s = i;
            while i < b.len() && (b[i].is_ascii_digit() || b[i] == b'.') {
                i += 1;
            }
            spans.push((s, i));
        } else {
            i += 1;
        }
    }
    spans
}

/// Numbers a glTF field is likely to be checked against: small indices, the component
/// types, the largest u32, a negative, a huge float and an array where a number goes.
static GLTF_REPLACEMENTS: [&str; 12] = [
    "0",
    "1",
    "2",
    "3",
    "5120",
    "5122",
    "5125",
    "5126",
    "4294967295",
    "-1",
    "1e30",
    "[0,0]",
];

#[test]
fn fuzz_gltf_loader() {
    let text = gltf_text();
    let spans = number_spans(&text);
    let dir = common::scratch("fuzz-gltf");
    // Each fixed replacement as likely as a random number.
    let replacement = prop_oneof![
        GLTF_REPLACEMENTS.len() as u32 =>
            prop::sample::select(&GLTF_REPLACEMENTS[..]).prop_map(str::to_owned),
        1 => any::<u16>().prop_map(|v| v.to_string()),
    ];
    let strategy = prop::collection::vec((any::<prop::sample::Index>(), replacement), 1..5);
    fuzz("gltf", strategy, |edits| {
        let mut picked: Vec<(usize, usize, String)> = edits
            .into_iter()
            .map(|(at, r)| {
                let (s, e) = spans[at.index(spans.len())];
                (s, e, r)
            })
            .collect();
        // Apply from the back so earlier spans stay valid; one edit per span.
        picked.sort_by_key(|p| std::cmp::Reverse(p.0));
        picked.dedup_by_key(|p| p.0);
        let mut t = text.clone();
        for (s, e, r) in picked {
            t.replace_range(s..e, &r);
        }
        let path = dir.join("fuzz.gltf");
        std::fs::write(&path, t).unwrap();
        build_gltf_if_loaded(&path);
    });
}

/// The same glTF as a .glb: JSON chunk, then the buffer as the binary chunk.
fn glb_bytes() -> Vec<u8> {
    let (p, idx) = common::tetrahedron();
    let mut buf: Vec<u8> = bytemuck::cast_slice(&p).to_vec();
    buf.extend_from_slice(bytemuck::cast_slice(&idx));
    let json = format!(
        r#"{{"asset":{{"version":"2.0"}},"scene":0,"scenes":[{{"nodes":[0]}}],"nodes":[{{"mesh":0}}],
        "meshes":[{{"primitives":[{{"attributes":{{"POSITION":0}},"indices":1}}]}}],
        "buffers":[{{"byteLength":{}}}],
        "bufferViews":[{{"buffer":0,"byteOffset":0,"byteLength":48}},{{"buffer":0,"byteOffset":48,"byteLength":24}}],
        "accessors":[{{"bufferView":0,"componentType":5126,"count":4,"type":"VEC3"}},
                     {{"bufferView":1,"componentType":5123,"count":12,"type":"SCALAR"}}]}}"#,
        buf.len()
    );
    common::gltf::glb_container(&json, &buf)
}

#[test]
fn fuzz_glb_loader() {
    let good = glb_bytes();
    let json_len = u32::from_le_bytes(good[12..16].try_into().unwrap()) as usize;
    let dir = common::scratch("fuzz-glb");
    // Words of the headers and the binary chunk (the JSON text is the glTF target's).
    let words: Vec<usize> = (0..5).chain((20 + json_len) / 4..good.len() / 4).collect();
    let strategy = (
        prop::collection::vec((prop::sample::select(words), interesting_word()), 1..5),
        0usize..3,
    );
    fuzz("glb", strategy, |(edits, cut)| {
        let mut b = good.clone();
        for (w, v) in edits {
            b[w * 4..w * 4 + 4].copy_from_slice(&v.to_le_bytes());
        }
        b.truncate(b.len() - cut * 7);
        let path = dir.join("fuzz.glb");
        std::fs::write(&path, b).unwrap();
        build_gltf_if_loaded(&path);
    });
}
