//! The fuzz target: proptest over mutated files, for the asset loader and every mesh
//! loader. A case passes when loading returns (an error or a value) without panicking,
//! and whatever loads can be built, verified, decoded and summarised without panicking.
//!
//! `MESHLIGHT_FUZZ_CASES=N` sets the cases per target (default 300, which keeps the
//! suite short); each target prints how many ran and fails if fewer did.

mod common;

use std::path::Path;

use meshlight_scene::asset::checksum::file_checksum;
use meshlight_scene::asset::format::{AssetHeader, SECTION_MESHLETS};
use meshlight_scene::load::{load_mesh, parse_obj, parse_stl};
use meshlight_scene::{BuildOptions, Mesh, MeshletAsset, build_asset, procedural_mesh};
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
        if reseal && w.len() >= AssetHeader::WORDS {
            let sum = file_checksum(&w[..AssetHeader::WORDS], &w[AssetHeader::WORDS..]);
            let at = std::mem::offset_of!(AssetHeader, checksum) / 4;
            w[at] = sum as u32;
            w[at + 1] = (sum >> 32) as u32;
        }
        let len = w.len() as u64 * 4;
        if let Ok(asset) = MeshletAsset::from_words(w, len, Path::new("fuzz.mlasset")) {
            let _ = meshlight_scene::verify::verify(&asset);
            let _ = meshlight_scene::verify::quality(&asset);
            let _ = meshlight_scene::cli::inspect_summary(Path::new("fuzz.mlasset"), &asset);
            for i in 0..asset.meshlets().len() {
                let _ = asset.decode_meshlet(i);
            }
        }
    });
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

/// A small valid glTF: two nodes instancing a tetrahedron with UVs.
fn gltf_text() -> String {
    let (p, idx) = common::tetrahedron();
    let mut buf: Vec<u8> = bytemuck::cast_slice(&p).to_vec();
    buf.extend_from_slice(bytemuck::cast_slice(&idx));
    let uvs: [[f32; 2]; 4] = [[0.0, 0.0], [1.0, 0.0], [0.0, 1.0], [1.0, 1.0]];
    buf.extend_from_slice(bytemuck::cast_slice(&uvs));
    format!(
        r#"{{"asset":{{"version":"2.0"}},"scene":0,"scenes":[{{"nodes":[0]}}],
        "nodes":[{{"children":[1,2]}},{{"mesh":0,"translation":[10,0,0]}},{{"mesh":0,"scale":[-1,1,1]}}],
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

#[test]
fn fuzz_gltf_loader() {
    let text = gltf_text();
    let spans = number_spans(&text);
    let dir = common::scratch("fuzz-gltf");
    let replacement = prop_oneof![
        Just("0".to_owned()),
        Just("1".to_owned()),
        Just("2".to_owned()),
        Just("3".to_owned()),
        Just("5120".to_owned()),
        Just("5122".to_owned()),
        Just("5125".to_owned()),
        Just("5126".to_owned()),
        Just("4294967295".to_owned()),
        Just("-1".to_owned()),
        Just("1e30".to_owned()),
        Just("[0,0]".to_owned()),
        any::<u16>().prop_map(|v| v.to_string()),
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
        build_if_loaded(load_mesh(&path));
    });
}

/// The same glTF as a .glb: JSON chunk, then the buffer as the binary chunk.
fn glb_bytes() -> Vec<u8> {
    let (p, idx) = common::tetrahedron();
    let mut buf: Vec<u8> = bytemuck::cast_slice(&p).to_vec();
    buf.extend_from_slice(bytemuck::cast_slice(&idx));
    let mut json = format!(
        r#"{{"asset":{{"version":"2.0"}},"scene":0,"scenes":[{{"nodes":[0]}}],"nodes":[{{"mesh":0}}],
        "meshes":[{{"primitives":[{{"attributes":{{"POSITION":0}},"indices":1}}]}}],
        "buffers":[{{"byteLength":{}}}],
        "bufferViews":[{{"buffer":0,"byteOffset":0,"byteLength":48}},{{"buffer":0,"byteOffset":48,"byteLength":24}}],
        "accessors":[{{"bufferView":0,"componentType":5126,"count":4,"type":"VEC3"}},
                     {{"bufferView":1,"componentType":5123,"count":12,"type":"SCALAR"}}]}}"#,
        buf.len()
    )
    .into_bytes();
    while !json.len().is_multiple_of(4) {
        json.push(b' ');
    }
    let mut glb = Vec::new();
    glb.extend_from_slice(b"glTF");
    glb.extend_from_slice(&2u32.to_le_bytes());
    glb.extend_from_slice(&((12 + 8 + json.len() + 8 + buf.len()) as u32).to_le_bytes());
    glb.extend_from_slice(&(json.len() as u32).to_le_bytes());
    glb.extend_from_slice(b"JSON");
    glb.extend_from_slice(&json);
    glb.extend_from_slice(&(buf.len() as u32).to_le_bytes());
    glb.extend_from_slice(b"BIN\0");
    glb.extend_from_slice(&buf);
    glb
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
        build_if_loaded(load_mesh(&path));
    });
}
