//! glTF files with `KHR_draco_mesh_compression` primitives. Spot compressed by Google's
//! C++ encoder (`tests/data/spot-draco.glb`, written by `make_draco_spot.py`) loads to
//! what that encoder's own decoder reads back; a sphere compressed by `draco-core`'s
//! encoder loads to the sphere (within the quantisation), beside a plain primitive and
//! sharing its stream between two primitives; damaged extension objects and streams are
//! refused naming the primitive, and flipped bytes never panic.

mod common;

use std::path::PathBuf;

use draco_core::{
    DataType, EncoderBuffer, EncoderOptions, FaceIndex, GeometryAttributeType, MeshEncoder,
    PointAttribute, PointIndex,
};
use glam::Vec3;
use meshlight_scene::load::{GltfScene, load_gltf_scene};
use serde_json::{Value, json};

fn data(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data")
        .join(name)
}

/// The C++ encoder's file loads to exactly what the C++ decoder read from the same
/// stream: its counts, and sums of every attribute and of every face's corners (which
/// ties the faces to the points).
#[test]
fn a_file_from_the_reference_encoder_loads_as_its_decoder_reads_it() {
    let expected: Value =
        serde_json::from_str(&std::fs::read_to_string(data("spot-draco.json")).unwrap()).unwrap();
    let scene = load_gltf_scene(&data("spot-draco.glb")).unwrap();
    assert_eq!(scene.meshes.len(), 1);
    let mesh = &scene.meshes[0].mesh;
    assert_eq!(
        mesh.positions.len() as u64,
        expected["points"].as_u64().unwrap()
    );
    assert_eq!(
        (mesh.indices.len() / 3) as u64,
        expected["faces"].as_u64().unwrap()
    );
    let want = |key: &str| -> Vec<f64> {
        expected[key]
            .as_array()
            .unwrap()
            .iter()
            .map(|v| v.as_f64().unwrap())
            .collect()
    };
    let close = |what: &str, got: &[f64], want: &[f64], tolerance: f64| {
        for (k, (g, w)) in got.iter().zip(want).enumerate() {
            assert!(
                (g - w).abs() <= tolerance,
                "{what}[{k}]: {g} here, {w} from the reference decoder"
            );
        }
    };
    let sum3 = |values: &mut dyn Iterator<Item = Vec3>| {
        values.fold([0.0f64; 3], |s, v| {
            [s[0] + v.x as f64, s[1] + v.y as f64, s[2] + v.z as f64]
        })
    };
    // Sums over thousands of f32 values: a few ulps each.
    close(
        "position sum",
        &sum3(&mut mesh.positions.iter().copied()),
        &want("position_sum"),
        1e-3,
    );
    close(
        "corner position sum",
        &sum3(&mut mesh.indices.iter().map(|&i| mesh.positions[i as usize])),
        &want("corner_position_sum"),
        1e-3,
    );
    // The loader normalises normals; the reference sum is of the decoder's unit
    // octahedral normals, which differ from unit length by less than 1e-6.
    close(
        "normal sum",
        &sum3(&mut mesh.normals.iter().copied()),
        &want("normal_sum"),
        1e-2,
    );
    let uv = mesh
        .uvs
        .iter()
        .fold([0.0f64; 2], |s, t| [s[0] + t[0] as f64, s[1] + t[1] as f64]);
    close("uv sum", &uv, &want("uv_sum"), 1e-3);
    let (lo, hi) = mesh.positions.iter().fold(
        (Vec3::splat(f32::MAX), Vec3::splat(f32::MIN)),
        |(lo, hi), &p| (lo.min(p), hi.max(p)),
    );
    close("min", &lo.to_array().map(f64::from), &want("min"), 1e-6);
    close("max", &hi.to_array().map(f64::from), &want("max"), 1e-6);
}

use common::generators::AttributedSphere as Sphere;

fn sphere() -> Sphere {
    Sphere::new(10, 16)
}

/// The sphere as a Draco stream: positions (unique id 0, 16 bits), normals (1, 12 bits),
/// UVs (2, 14 bits).
fn encode(s: &Sphere) -> Vec<u8> {
    let n = s.positions.len();
    let mut mesh = draco_core::Mesh::new();
    let mut add = |ty: GeometryAttributeType, components: u8, values: &[f32]| {
        let mut a = PointAttribute::new();
        a.init(ty, components, DataType::Float32, false, n);
        let bytes: Vec<u8> = values.iter().flat_map(|v| v.to_le_bytes()).collect();
        a.buffer_mut().write(0, &bytes);
        mesh.add_attribute(a)
    };
    add(
        GeometryAttributeType::Position,
        3,
        s.positions.as_flattened(),
    );
    add(GeometryAttributeType::Normal, 3, s.normals.as_flattened());
    add(GeometryAttributeType::TexCoord, 2, s.uvs.as_flattened());
    mesh.set_num_points(n);
    mesh.set_num_faces(s.indices.len() / 3);
    for (f, t) in s.indices.chunks_exact(3).enumerate() {
        mesh.set_face(
            FaceIndex(f as u32),
            [PointIndex(t[0]), PointIndex(t[1]), PointIndex(t[2])],
        );
    }
    let mut options = EncoderOptions::new();
    options.set_attribute_int(0, "quantization_bits", 16);
    options.set_attribute_int(1, "quantization_bits", 12);
    options.set_attribute_int(2, "quantization_bits", 14);
    let mut encoder = MeshEncoder::new();
    encoder.set_mesh(mesh);
    let mut out = EncoderBuffer::new();
    encoder.encode(&options, &mut out).unwrap();
    out.data().to_vec()
}

/// A GLB whose mesh 0 has two primitives over the one Draco stream `drc` (materials 0
/// and 1, their own accessors 0–3 and 4–7) and whose mesh 1 is a plain triangle.
fn glb(s: &Sphere, drc: &[u8]) -> (Value, Vec<u8>) {
    let n = s.positions.len();
    let count = s.indices.len();
    let mut bin = drc.to_vec();
    while !bin.len().is_multiple_of(4) {
        bin.push(0);
    }
    let plain_at = bin.len();
    for p in [[0.0f32, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]] {
        for v in p {
            bin.extend_from_slice(&v.to_le_bytes());
        }
    }
    let draco = json!({"KHR_draco_mesh_compression": {
        "bufferView": 0, "attributes": {"POSITION": 0, "NORMAL": 1, "TEXCOORD_0": 2}}});
    let accessors = |base: usize| {
        vec![
            json!({"componentType": 5126, "count": n, "type": "VEC3"}),
            json!({"componentType": 5126, "count": n, "type": "VEC3"}),
            json!({"componentType": 5126, "count": n, "type": "VEC2"}),
            json!({"componentType": 5125, "count": count, "type": "SCALAR", "name": format!("indices {base}")}),
        ]
    };
    let mut all = accessors(0);
    all.extend(accessors(4));
    all.push(json!({"bufferView": 1, "componentType": 5126, "count": 3, "type": "VEC3"}));
    let primitive = |base: usize, material: usize| {
        json!({"attributes": {"POSITION": base, "NORMAL": base + 1, "TEXCOORD_0": base + 2},
               "indices": base + 3, "material": material, "extensions": draco})
    };
    let doc = json!({
        "asset": {"version": "2.0"},
        "extensionsUsed": ["KHR_draco_mesh_compression"],
        "extensionsRequired": ["KHR_draco_mesh_compression"],
        "scene": 0, "scenes": [{"nodes": [0, 1]}],
        "nodes": [{"mesh": 0}, {"mesh": 1, "translation": [0, 20, 0]}],
        "materials": [{"name": "a"}, {"name": "b"}],
        "meshes": [
            {"name": "sphere", "primitives": [primitive(0, 0), primitive(4, 1)]},
            {"name": "plain", "primitives": [{"attributes": {"POSITION": 8}}]}
        ],
        "buffers": [{"byteLength": bin.len()}],
        "bufferViews": [
            {"buffer": 0, "byteOffset": 0, "byteLength": drc.len()},
            {"buffer": 0, "byteOffset": plain_at, "byteLength": 36}
        ],
        "accessors": all
    });
    (doc, bin)
}

fn load(name: &str, doc: &Value, bin: &[u8]) -> Result<GltfScene, String> {
    let dir = common::scratch(&format!("gltf-draco-{name}"));
    let path = dir.join(format!("{name}.glb"));
    std::fs::write(&path, common::gltf::glb_container(&doc.to_string(), bin)).unwrap();
    load_gltf_scene(&path).map_err(|e| e.to_string())
}

/// Each triangle as its three corners' positions rounded to the quantisation, starting
/// from its least corner (the codec may rotate a triangle; it keeps the winding).
fn triangle_set(positions: &[[f32; 3]], indices: &[u32], step: f32) -> Vec<[[i64; 3]; 3]> {
    let q = |i: u32| positions[i as usize].map(|v| (v / step).round() as i64);
    let mut out: Vec<[[i64; 3]; 3]> = indices
        .chunks_exact(3)
        .map(|t| {
            let c = [q(t[0]), q(t[1]), q(t[2])];
            let k = (0..3).min_by_key(|&k| c[k]).unwrap();
            [c[k], c[(k + 1) % 3], c[(k + 2) % 3]]
        })
        .collect();
    out.sort();
    out
}

#[test]
fn a_sphere_compressed_by_draco_core_loads_as_the_sphere() {
    let s = sphere();
    let drc = encode(&s);
    let (doc, bin) = glb(&s, &drc);
    let scene = load("sphere", &doc, &bin).unwrap();
    assert_eq!(scene.meshes.len(), 2, "the Draco mesh and the plain one");
    let sphere = scene
        .meshes
        .iter()
        .find(|m| m.mesh.source.contains("sphere"))
        .unwrap();
    let mesh = &sphere.mesh;
    assert_eq!(
        mesh.indices.len(),
        2 * s.indices.len(),
        "two primitives over one stream"
    );
    assert_eq!(mesh.materials.len(), 2 * s.indices.len() / 3);
    assert!(
        mesh.materials[..s.indices.len() / 3]
            .iter()
            .all(|&m| m != mesh.materials[s.indices.len() / 3]),
        "the two primitives keep their own materials"
    );
    // 16-bit positions over a 6-unit box: a step of 1e-4; compare on a coarser grid.
    let step = 1e-2;
    let positions: Vec<[f32; 3]> = mesh.positions.iter().map(|p| p.to_array()).collect();
    let half = mesh.indices.len() / 2;
    let got = triangle_set(&positions, &mesh.indices[..half], step);
    let want = triangle_set(&s.positions, &s.indices, step);
    let differ = got.iter().zip(&want).filter(|(g, w)| g != w).count();
    // Rounding to the coarse grid may split a corner lying near a cell border.
    assert!(
        differ <= want.len() / 50,
        "{differ} of {} triangles differ",
        want.len()
    );
    // Every decoded vertex lies on the sphere, its normal points out, its UV is the
    // sphere's UV at that point (within the quantisation).
    let centre = Vec3::new(10.0, -2.0, 5.0);
    for (i, &p) in mesh.positions.iter().enumerate() {
        let r = (p - centre).length();
        assert!((r - 3.0).abs() < 1e-3, "vertex {i} at radius {r}");
        let n = mesh.normals[i];
        assert!(n.dot((p - centre) / r) > 0.999, "normal {i} is {n}, at {p}");
        let u = (p - centre) / 3.0;
        let v = 2.0 * (1.0 - u.z);
        assert!(
            (mesh.uvs[i][1] - v).abs() < 1e-3,
            "uv {i}: {:?}",
            mesh.uvs[i]
        );
    }
}

/// What a damaged file is refused with: every piece of `needles`.
fn refused(name: &str, doc: &Value, bin: &[u8], needles: &[&str]) {
    match load(name, doc, bin) {
        Ok(_) => panic!("{name}: a damaged file loaded"),
        Err(e) => {
            for needle in needles {
                assert!(e.contains(needle), "{name}: {e:?} does not say {needle:?}");
            }
        }
    }
}

fn ext(doc: &mut Value, primitive: usize) -> &mut Value {
    &mut doc["meshes"][0]["primitives"][primitive]["extensions"]["KHR_draco_mesh_compression"]
}

#[test]
fn damaged_draco_primitives_are_refused_naming_the_primitive() {
    let s = sphere();
    let drc = encode(&s);
    let (doc, bin) = glb(&s, &drc);
    type Edit = Box<dyn Fn(&mut Value, &mut Vec<u8>)>;
    let cases: Vec<(&str, Edit, &[&str])> = vec![
        (
            "no-view",
            Box::new(|d, _| {
                ext(d, 0).as_object_mut().unwrap().remove("bufferView");
            }),
            &["primitive 0", "no bufferView"],
        ),
        (
            "view-range",
            Box::new(|d, _| ext(d, 1)["bufferView"] = json!(9)),
            &["primitive 1", "bufferView is 9", "only 2"],
        ),
        (
            "view-outside",
            Box::new(|d, _| d["bufferViews"][0]["byteLength"] = json!(1u64 << 40)),
            &["primitive 0", "lies outside buffer 0"],
        ),
        (
            "no-attributes",
            Box::new(|d, _| {
                ext(d, 0).as_object_mut().unwrap().remove("attributes");
            }),
            &["primitive 0", "no attributes"],
        ),
        (
            "attribute-id",
            Box::new(|d, _| ext(d, 0)["attributes"]["NORMAL"] = json!(7)),
            &["primitive 0", "NORMAL is Draco attribute 7"],
        ),
        (
            "attribute-not-id",
            Box::new(|d, _| ext(d, 0)["attributes"]["NORMAL"] = json!("one")),
            &[
                "primitive 0",
                "attribute NORMAL",
                "not a Draco attribute id",
            ],
        ),
        (
            "count",
            Box::new(|d, _| d["accessors"][0]["count"] = json!(5)),
            &["primitive 0", "accessor 0 declares 5 elements"],
        ),
        (
            "index-count",
            Box::new(|d, _| d["accessors"][7]["count"] = json!(6)),
            &["primitive 1", "accessor 7 declares 6 elements"],
        ),
        (
            "components",
            Box::new(|d, _| d["accessors"][2]["type"] = json!("VEC3")),
            &["primitive 0", "accessor 2 declares 3 components", "has 2"],
        ),
        (
            "no-indices",
            Box::new(|d, _| {
                d["meshes"][0]["primitives"][0]
                    .as_object_mut()
                    .unwrap()
                    .remove("indices");
            }),
            &["primitive 0", "no indices"],
        ),
        (
            "shared-accessor",
            Box::new(|d, _| {
                // Primitive 1's NORMAL is primitive 0's POSITION accessor.
                d["meshes"][0]["primitives"][1]["attributes"]["NORMAL"] = json!(0);
            }),
            &[
                "primitive 1",
                "accessor 0",
                "another Draco stream or attribute",
            ],
        ),
        (
            "truncated",
            Box::new(|d, _| {
                let len = d["bufferViews"][0]["byteLength"].as_u64().unwrap();
                d["bufferViews"][0]["byteLength"] = json!(len / 2);
            }),
            &["primitive 0", "Draco"],
        ),
        (
            "not-draco",
            Box::new(|_, b| b[..5].copy_from_slice(b"PLAIN")),
            &["primitive 0", "Draco stream does not decode"],
        ),
    ];
    for (name, edit, needles) in cases {
        let (mut d, mut b) = (doc.clone(), bin.clone());
        edit(&mut d, &mut b);
        refused(name, &d, &b, needles);
    }
}

/// Flipped and cut bytes anywhere in the stream: an error or a mesh that passes the
/// loader's checks, never a panic or an abort. `MESHLIGHT_FUZZ_CASES=N` sets the cases
/// (default 600).
#[test]
fn flipped_stream_bytes_never_panic() {
    let s = sphere();
    let drc = encode(&s);
    let (doc, bin) = glb(&s, &drc);
    let mut refused = 0;
    let cases: u32 = std::env::var("MESHLIGHT_FUZZ_CASES")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(600);
    for case in 0..cases {
        let mut b = bin.clone();
        let at = (common::generators::hash01(case, 1) * drc.len() as f32) as usize % drc.len();
        let flips = 1 + (case % 4) as usize;
        for k in 0..flips {
            let i = (at + k * 7) % drc.len();
            b[i] ^= 1 << ((case as usize + k) % 8);
        }
        let mut d = doc.clone();
        if case % 5 == 0 {
            d["bufferViews"][0]["byteLength"] = json!(at.max(1));
        }
        if load(&format!("flip-{}", case % 8), &d, &b).is_err() {
            refused += 1;
        }
    }
    eprintln!("{refused} of {cases} damaged streams refused");
    assert!(
        refused > cases / 4,
        "only {refused} of {cases} damaged streams refused"
    );
}
