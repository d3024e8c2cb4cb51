//! glTF files as `gltfpack -c` writes them: buffer views compressed with
//! `EXT_meshopt_compression` (with its filters) over attributes quantised with
//! `KHR_mesh_quantization`, and a fallback buffer with no data. The same sphere written
//! plainly and compressed loads to the same mesh (within the quantisation), and damaged
//! compressed views are refused naming the view.

mod common;

use meshlight_scene::SceneError;
use meshlight_scene::load::{GltfScene, load_gltf_scene};
use meshopt::EncodeExpMode;
use serde_json::{Value, json};

use common::generators::AttributedSphere as Sphere;

fn sphere() -> Sphere {
    Sphere::new(12, 20)
}

/// Which index encoding and normal width a compressed file uses.
#[derive(Clone, Copy)]
enum Variant {
    /// TRIANGLES mode with 32-bit indices; 8-bit octahedral normals.
    Triangles,
    /// INDICES mode with 16-bit indices; 16-bit octahedral normals.
    Indices,
}

/// Appends `bytes` to `bin` at a 4-byte boundary; returns (offset, length).
fn push(bin: &mut Vec<u8>, bytes: &[u8]) -> (usize, usize) {
    while !bin.len().is_multiple_of(4) {
        bin.push(0);
    }
    let at = bin.len();
    bin.extend_from_slice(bytes);
    (at, bytes.len())
}

/// The sphere as a compressed, quantised GLB: positions as 16-bit integers dequantised by
/// the node's scale and translation, normals octahedral, UVs exponential, indices coded.
fn compressed_glb(s: &Sphere, variant: Variant) -> (Value, Vec<u8>) {
    let n = s.positions.len();
    let (min, extent) = {
        let mut lo = [f32::MAX; 3];
        let mut hi = [f32::MIN; 3];
        for p in &s.positions {
            for k in 0..3 {
                lo[k] = lo[k].min(p[k]);
                hi[k] = hi[k].max(p[k]);
            }
        }
        (lo, (0..3).map(|k| hi[k] - lo[k]).fold(0.0f32, f32::max))
    };
    let step = extent / 65535.0;
    let quantised: Vec<[u16; 4]> = s
        .positions
        .iter()
        .map(|p| {
            let q = |k: usize| ((p[k] - min[k]) / step).round() as u16;
            [q(0), q(1), q(2), 0]
        })
        .collect();
    let unit4: Vec<[f32; 4]> = s.normals.iter().map(|v| [v[0], v[1], v[2], 0.0]).collect();
    let uvs = meshopt::encode_filter_exp::<2>(&s.uvs, 16, EncodeExpMode::Separate);

    let mut bin = Vec::new();
    let mut views = Vec::new();
    let mut view = |bin: &mut Vec<u8>,
                    encoded: Vec<u8>,
                    stride: usize,
                    count: usize,
                    mode: &str,
                    filter: &str| {
        let (offset, length) = push(bin, &encoded);
        views.push(json!({
            "buffer": 1, "byteLength": count * stride,
            "extensions": {"EXT_meshopt_compression": {
                "buffer": 0, "byteOffset": offset, "byteLength": length,
                "byteStride": stride, "count": count, "mode": mode, "filter": filter
            }}
        }));
    };
    view(
        &mut bin,
        meshopt::encode_vertex_buffer(&quantised).unwrap(),
        8,
        n,
        "ATTRIBUTES",
        "NONE",
    );
    let normal_type = match variant {
        Variant::Triangles => {
            let oct = meshopt::encode_filter_oct::<i8>(&unit4, 8);
            view(
                &mut bin,
                meshopt::encode_vertex_buffer(&oct).unwrap(),
                4,
                n,
                "ATTRIBUTES",
                "OCTAHEDRAL",
            );
            5120
        }
        Variant::Indices => {
            let oct = meshopt::encode_filter_oct::<i16>(&unit4, 12);
            view(
                &mut bin,
                meshopt::encode_vertex_buffer(&oct).unwrap(),
                8,
                n,
                "ATTRIBUTES",
                "OCTAHEDRAL",
            );
            5122
        }
    };
    view(
        &mut bin,
        meshopt::encode_vertex_buffer(&uvs).unwrap(),
        8,
        n,
        "ATTRIBUTES",
        "EXPONENTIAL",
    );
    let count = s.indices.len();
    let index_type = match variant {
        Variant::Triangles => {
            view(
                &mut bin,
                meshopt::encode_index_buffer(&s.indices, n).unwrap(),
                4,
                count,
                "TRIANGLES",
                "NONE",
            );
            5125
        }
        Variant::Indices => {
            view(
                &mut bin,
                meshopt::encode_index_sequence(&s.indices, n).unwrap(),
                2,
                count,
                "INDICES",
                "NONE",
            );
            5123
        }
    };
    while !bin.len().is_multiple_of(4) {
        bin.push(0);
    }
    let fallback_len: usize = views
        .iter()
        .map(|v| v["byteLength"].as_u64().unwrap() as usize)
        .sum();
    // The fallback views are laid end to end in the buffer nobody reads.
    let mut at = 0;
    for v in &mut views {
        v["byteOffset"] = json!(at);
        at += v["byteLength"].as_u64().unwrap() as usize;
        at = at.next_multiple_of(4);
    }
    let doc = json!({
        "asset": {"version": "2.0"},
        "extensionsUsed": ["EXT_meshopt_compression", "KHR_mesh_quantization"],
        "extensionsRequired": ["EXT_meshopt_compression", "KHR_mesh_quantization"],
        "scene": 0, "scenes": [{"nodes": [0]}],
        "nodes": [{"mesh": 0, "translation": min, "scale": [step, step, step]}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0, "NORMAL": 1, "TEXCOORD_0": 2}, "indices": 3}]}],
        "buffers": [
            {"byteLength": bin.len()},
            {"byteLength": fallback_len.next_multiple_of(4) + 16,
             "extensions": {"EXT_meshopt_compression": {"fallback": true}}}
        ],
        "bufferViews": views,
        "accessors": [
            {"bufferView": 0, "componentType": 5123, "count": n, "type": "VEC3"},
            {"bufferView": 1, "componentType": normal_type, "normalized": true, "count": n, "type": "VEC3"},
            {"bufferView": 2, "componentType": 5126, "count": n, "type": "VEC2"},
            {"bufferView": 3, "componentType": index_type, "count": count, "type": "SCALAR"}
        ]
    });
    (doc, bin)
}

fn write_glb(name: &str, doc: &Value, bin: &[u8]) -> std::path::PathBuf {
    let dir = common::scratch(&format!("gltf-compressed-{name}"));
    let path = dir.join(format!("{name}.glb"));
    std::fs::write(&path, common::gltf::glb_container(&doc.to_string(), bin)).unwrap();
    path
}

fn load(doc: &Value, bin: &[u8], name: &str) -> Result<GltfScene, SceneError> {
    load_gltf_scene(&write_glb(name, doc, bin))
}

#[test]
fn a_compressed_quantised_file_loads_as_the_plain_one() {
    let s = sphere();
    for (variant, name, normal_dot) in [
        (Variant::Triangles, "triangles", 0.995),
        (Variant::Indices, "indices", 0.9995),
    ] {
        let (doc, bin) = compressed_glb(&s, variant);
        let scene = load(&doc, &bin, name).unwrap_or_else(|e| panic!("{name}: {e}"));
        assert_eq!(scene.meshes.len(), 1, "{name}");
        assert_eq!(scene.instances.len(), 1, "{name}");
        let mesh = &scene.meshes[0].mesh;
        let transform = scene.instances[0].transform;
        // The triangle codec may start a triangle at another corner (same winding).
        let canonical = |t: &[u32]| {
            let k = (0..3).min_by_key(|&k| t[k]).unwrap();
            [t[k], t[(k + 1) % 3], t[(k + 2) % 3]]
        };
        let triangles = |i: &[u32]| i.chunks_exact(3).map(canonical).collect::<Vec<_>>();
        assert_eq!(
            triangles(&mesh.indices),
            triangles(&s.indices),
            "{name}: the same triangles, in order"
        );
        assert_eq!(mesh.positions.len(), s.positions.len(), "{name}");
        // Half a quantisation step per axis, plus rounding of the transform.
        let tolerance = 6.0 / 65535.0;
        for (i, (&got, want)) in mesh.positions.iter().zip(&s.positions).enumerate() {
            let world = transform.transform_point3(got);
            let error = (world - glam::Vec3::from(*want)).abs().max_element();
            assert!(
                error <= tolerance,
                "{name}: vertex {i} at {world}, wanted {want:?} ({error})"
            );
        }
        for (i, (&got, want)) in mesh.normals.iter().zip(&s.normals).enumerate() {
            let dot = got.normalize().dot(glam::Vec3::from(*want));
            assert!(
                dot >= normal_dot,
                "{name}: normal {i} is {got}, wanted {want:?} (dot {dot})"
            );
        }
        for (i, (got, want)) in mesh.uvs.iter().zip(&s.uvs).enumerate() {
            let error = (got[0] - want[0]).abs().max((got[1] - want[1]).abs());
            assert!(
                error <= 4.0 / 32768.0,
                "{name}: uv {i} is {got:?}, wanted {want:?}"
            );
        }
        assert_eq!(mesh.uvs.len(), s.uvs.len(), "{name}");
    }
}

/// Each damaged field of a compressed view is refused naming the view and the field.
/// View `view`'s `EXT_meshopt_compression` object in `doc`.
fn ext(doc: &mut Value, view: usize) -> &mut Value {
    &mut doc["bufferViews"][view]["extensions"]["EXT_meshopt_compression"]
}

#[test]
fn damaged_compressed_views_are_refused_naming_the_view() {
    let s = sphere();
    let (doc, bin) = compressed_glb(&s, Variant::Triangles);
    type Edit = Box<dyn Fn(&mut Value)>;
    let cases: Vec<(&str, Edit, &[&str])> = vec![
        (
            "truncated",
            Box::new(move |d| {
                let e = ext(d, 0);
                e["byteLength"] = json!(e["byteLength"].as_u64().unwrap() / 2);
            }),
            &["buffer view 0", "does not decode"],
        ),
        (
            "mode",
            Box::new(move |d| ext(d, 3)["mode"] = json!("STRIPS")),
            &["buffer view 3", "STRIPS"],
        ),
        (
            "stride",
            Box::new(move |d| ext(d, 0)["byteStride"] = json!(6)),
            &["buffer view 0", "byteStride 6"],
        ),
        (
            "buffer",
            Box::new(move |d| ext(d, 2)["buffer"] = json!(7)),
            &["buffer view 2", "buffer 7"],
        ),
        (
            "outside",
            Box::new(move |d| ext(d, 2)["byteOffset"] = json!(1u64 << 40)),
            &["buffer view 2", "outside buffer 0"],
        ),
        (
            "huge",
            Box::new(move |d| ext(d, 0)["count"] = json!(1u64 << 36)),
            &["buffer view 0", "input limit"],
        ),
        (
            "filter",
            Box::new(move |d| ext(d, 1)["filter"] = json!("QUATERNION")),
            &["buffer view 1", "\"QUATERNION\"", "byteStride 4"],
        ),
        (
            "missing",
            Box::new(move |d| {
                ext(d, 1).as_object_mut().unwrap().remove("count");
            }),
            &["buffer view 1", "no count"],
        ),
        (
            "triangles",
            Box::new(move |d| ext(d, 3)["count"] = json!(10)),
            &["buffer view 3", "whole number of triangles"],
        ),
    ];
    for (name, edit, needles) in cases {
        let mut damaged = doc.clone();
        edit(&mut damaged);
        let err = load(&damaged, &bin, &format!("damaged-{name}")).expect_err(name);
        let msg = err.to_string();
        assert!(matches!(err, SceneError::Gltf { .. }), "{name}: {err:?}");
        for needle in needles {
            assert!(
                msg.contains(needle),
                "{name}: {needle:?} missing from: {msg}"
            );
        }
    }
}

/// Random damage to the compressed bytes decodes to an error or to values the loader's
/// checks accept (a flipped bit may still decode), never to a panic or a read outside
/// the streams.
#[test]
fn flipped_bytes_in_compressed_streams_never_panic() {
    let s = sphere();
    let (doc, bin) = compressed_glb(&s, Variant::Indices);
    let mut state = 0x9e37_79b9u32;
    let (mut refused, mut loaded) = (0, 0);
    for round in 0..300 {
        let mut damaged = bin.clone();
        for _ in 0..1 + round % 4 {
            state ^= state << 13;
            state ^= state >> 17;
            state ^= state << 5;
            let at = state as usize % damaged.len();
            damaged[at] ^= 1 << (state >> 29);
        }
        match load(&doc, &damaged, "flipped") {
            Ok(scene) => {
                let mesh = &scene.meshes[0].mesh;
                assert!(
                    mesh.indices
                        .iter()
                        .all(|&i| (i as usize) < mesh.positions.len())
                );
                loaded += 1;
            }
            Err(_) => refused += 1,
        }
    }
    assert!(refused > 0, "some damage must be caught ({loaded} loaded)");
}
