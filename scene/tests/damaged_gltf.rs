//! Damaged glTF files: each class that used to kill the process (stack overflow, memory
//! exhaustion, a panic inside the glTF crate) is now a typed error naming what is wrong.

mod common;

use std::path::PathBuf;

use meshlight_scene::SceneError;
use meshlight_scene::load::load_mesh;
use meshlight_scene::mesh::MAX_TRIANGLES;

/// A glTF with the given `nodes`, scene roots, primitive JSON and accessor list.
fn gltf(nodes: &str, roots: &str, primitive: &str, accessors: &str) -> String {
    let buf = common::gltf::tetrahedron_buffer();
    format!(
        r#"{{"asset":{{"version":"2.0"}},"scene":0,"scenes":[{{"nodes":{roots}}}],
        "nodes":{nodes},
        "meshes":[{{"primitives":[{primitive}]}}],
        "buffers":[{{"byteLength":{},"uri":"data:application/octet-stream;base64,{}"}}],
        "bufferViews":[{{"buffer":0,"byteOffset":0,"byteLength":48}},{{"buffer":0,"byteOffset":48,"byteLength":24}},{{"buffer":0,"byteOffset":72,"byteLength":32}}],
        "accessors":{accessors}}}"#,
        buf.len(),
        common::base64(&buf)
    )
}

const PRIMITIVE: &str = r#"{"attributes":{"POSITION":0,"TEXCOORD_0":2},"indices":1}"#;
const ACCESSORS: &str = r#"[{"bufferView":0,"componentType":5126,"count":4,"type":"VEC3"},
    {"bufferView":1,"componentType":5123,"count":12,"type":"SCALAR"},
    {"bufferView":2,"componentType":5126,"count":4,"type":"VEC2"}]"#;
const ONE_NODE: &str = r#"[{"mesh":0}]"#;

fn write(name: &str, text: &str) -> PathBuf {
    let dir = common::scratch(&format!("damaged-gltf-{name}"));
    let path = dir.join(name);
    std::fs::write(&path, text).unwrap();
    path
}

/// Loads and expects a `Gltf` error whose message holds every one of `needles`.
fn refused(name: &str, text: &str, needles: &[&str]) -> String {
    let err = load_mesh(&write(name, text)).unwrap_err();
    let msg = err.to_string();
    assert!(matches!(err, SceneError::Gltf { .. }), "{name}: {err:?}");
    assert!(
        msg.contains(name),
        "{name}: the error names the file: {msg}"
    );
    for n in needles {
        assert!(msg.contains(n), "{name}: {n:?} missing from: {msg}");
    }
    msg
}

#[test]
fn the_undamaged_file_loads() {
    let mesh = load_mesh(&write(
        "ok.gltf",
        &gltf(ONE_NODE, "[0]", PRIMITIVE, ACCESSORS),
    ))
    .unwrap();
    assert_eq!(mesh.triangle_count(), 4);
    assert_eq!(mesh.uvs.len(), 4);
}

#[test]
fn node_cycles_are_refused() {
    // A node that is its own child, and a loop through two nodes.
    refused(
        "self.gltf",
        &gltf(
            r#"[{"mesh":0,"children":[0]}]"#,
            "[0]",
            PRIMITIVE,
            ACCESSORS,
        ),
        &["node 0 is its own descendant", "children"],
    );
    refused(
        "loop.gltf",
        &gltf(
            r#"[{"children":[1]},{"mesh":0,"children":[0]}]"#,
            "[0]",
            PRIMITIVE,
            ACCESSORS,
        ),
        &["own descendant"],
    );
    // A chain far deeper than any stack: walked without recursion, and loads.
    let chain = node_chain(200_000, |next| next.to_string());
    let text = gltf(&chain, "[0]", PRIMITIVE, ACCESSORS);
    assert_eq!(
        load_mesh(&write("deep.gltf", &text))
            .unwrap()
            .triangle_count(),
        4
    );
}

/// `levels` nodes, each but the last listing node `i + 1` as `children(i + 1)` says;
/// the last holds the mesh.
fn node_chain(levels: usize, children: impl Fn(usize) -> String) -> String {
    let nodes: Vec<String> = (0..levels)
        .map(|i| {
            if i + 1 < levels {
                format!(r#"{{"children":[{}]}}"#, children(i + 1))
            } else {
                r#"{"mesh":0}"#.to_owned()
            }
        })
        .collect();
    format!("[{}]", nodes.join(","))
}

/// Node `i` lists node `i + 1` twice, so the last node (with the mesh) is reached by
/// 2^(levels - 1) paths.
fn doubling_tree(levels: usize) -> String {
    node_chain(levels, |next| format!("{next},{next}"))
}

#[test]
fn instance_blow_up_is_refused_before_expanding() {
    // 2^30 instances of the mesh: refused from the tree's shape, in no time and memory.
    refused(
        "blowup.gltf",
        &gltf(&doubling_tree(31), "[0]", PRIMITIVE, ACCESSORS),
        &["node instances", "shared"],
    );
    // Few enough instances, but too many triangles as the accessors declare them.
    let huge_indices = ACCESSORS.replace(r#""count":12"#, r#""count":6000000"#);
    let err = load_mesh(&write(
        "triangles.gltf",
        &gltf(&doubling_tree(6), "[0]", PRIMITIVE, &huge_indices),
    ))
    .unwrap_err();
    match &err {
        SceneError::TooLarge {
            what, limit, count, ..
        } => {
            assert_eq!((*what, *limit), ("triangles", MAX_TRIANGLES));
            assert_eq!(*count, 32 * 2_000_000);
        }
        other => panic!("{other:?}"),
    }
    assert!(err.to_string().contains("triangles.gltf"));
}

#[test]
fn accessor_types_are_checked_before_reading() {
    let with = |accessor: usize, from: &str, to: &str| {
        let list: Vec<&str> = ACCESSORS.split("},").collect();
        let mut list: Vec<String> = list.iter().map(|s| s.to_string()).collect();
        list[accessor] = list[accessor].replace(from, to);
        list.join("},")
    };
    let float_indices = with(1, "5123", "5126");
    refused(
        "float-indices.gltf",
        &gltf(ONE_NODE, "[0]", PRIMITIVE, &float_indices),
        &[
            "indices accessor 1",
            "F32",
            "UNSIGNED_BYTE, UNSIGNED_SHORT or UNSIGNED_INT",
        ],
    );
    let signed_indices = with(1, "5123", "5122");
    refused(
        "signed-indices.gltf",
        &gltf(ONE_NODE, "[0]", PRIMITIVE, &signed_indices),
        &["indices accessor 1", "I16"],
    );
    let int_uvs = with(2, "5126", "5125");
    refused(
        "int-uvs.gltf",
        &gltf(ONE_NODE, "[0]", PRIMITIVE, &int_uvs),
        &["TEXCOORD_0 accessor 2", "U32"],
    );
    let vec2_positions = with(0, "VEC3", "VEC2");
    refused(
        "vec2-positions.gltf",
        &gltf(ONE_NODE, "[0]", PRIMITIVE, &vec2_positions),
        &["POSITION accessor 0", "VEC3 of FLOAT"],
    );
}

#[test]
fn references_past_their_lists_are_refused() {
    let primitive = PRIMITIVE.replace(r#""TEXCOORD_0":2"#, r#""TEXCOORD_0":99"#);
    refused(
        "attribute.gltf",
        &gltf(ONE_NODE, "[0]", &primitive, ACCESSORS),
        &["accessor 99", "only 3 accessors"],
    );
    let primitive = PRIMITIVE.replace(r#""indices":1"#, r#""indices":7"#);
    refused(
        "indices.gltf",
        &gltf(ONE_NODE, "[0]", &primitive, ACCESSORS),
        &["accessor 7"],
    );
    refused(
        "child.gltf",
        &gltf(
            r#"[{"mesh":0,"children":[5]}]"#,
            "[0]",
            PRIMITIVE,
            ACCESSORS,
        ),
        &["node 0 lists node 5", "only 1 nodes"],
    );
    refused(
        "mesh.gltf",
        &gltf(r#"[{"mesh":3}]"#, "[0]", PRIMITIVE, ACCESSORS),
        &["mesh 3"],
    );
    let view = ACCESSORS.replacen(r#""bufferView":0"#, r#""bufferView":9"#, 1);
    refused(
        "view.gltf",
        &gltf(ONE_NODE, "[0]", PRIMITIVE, &view),
        &["buffer view 9"],
    );
    // More elements than the buffer view holds.
    let count = ACCESSORS.replacen(r#""count":4"#, r#""count":400"#, 1);
    refused(
        "count.gltf",
        &gltf(ONE_NODE, "[0]", PRIMITIVE, &count),
        &["POSITION accessor 0", "400 elements"],
    );
}

#[test]
fn glb_header_lengths_are_checked_before_parsing() {
    // A GLB whose header claims fewer bytes than the header itself (overflowed inside the
    // glTF crate), more bytes than the file has, or that stops inside the header.
    let mut glb = b"glTF".to_vec();
    glb.extend_from_slice(&2u32.to_le_bytes());
    for (name, length, extra) in [
        ("short.glb", 0u32, 8usize),
        ("long.glb", 4096, 8),
        ("cut.glb", 0, 0),
    ] {
        let mut bytes = glb.clone();
        if extra > 0 {
            bytes.extend_from_slice(&length.to_le_bytes());
            bytes.extend_from_slice(&vec![0u8; extra]);
        }
        let dir = common::scratch(&format!("glb-{name}"));
        let path = dir.join(name);
        std::fs::write(&path, bytes).unwrap();
        let err = load_mesh(&path).unwrap_err();
        assert!(matches!(err, SceneError::Gltf { .. }), "{name}: {err:?}");
        assert!(err.to_string().contains("truncated"), "{name}: {err}");
    }
}

/// A tetrahedron with normals whose `poison` (0 = POSITION, 2 = TEXCOORD_0, 3 = NORMAL)
/// accessor holds one NaN or infinity in element 2.
fn poisoned(poison: usize, value: f32) -> String {
    let (mut p, idx) = common::tetrahedron();
    let mut uvs: [[f32; 2]; 4] = [[0.0, 0.0], [1.0, 0.0], [0.0, 1.0], [1.0, 1.0]];
    let mut normals = [[0.0f32, 0.0, 1.0]; 4];
    match poison {
        0 => p[2][1] = value,
        2 => uvs[2][0] = value,
        _ => normals[2][2] = value,
    }
    let mut buf: Vec<u8> = bytemuck::cast_slice(&p).to_vec();
    buf.extend_from_slice(bytemuck::cast_slice(&idx));
    buf.extend_from_slice(bytemuck::cast_slice(&uvs));
    buf.extend_from_slice(bytemuck::cast_slice(&normals));
    format!(
        r#"{{"asset":{{"version":"2.0"}},"scene":0,"scenes":[{{"nodes":[0]}}],"nodes":[{{"mesh":0}}],
        "meshes":[{{"name":"tet","primitives":[{{"attributes":{{"POSITION":0,"TEXCOORD_0":2,"NORMAL":3}},"indices":1}}]}}],
        "buffers":[{{"byteLength":{},"uri":"data:application/octet-stream;base64,{}"}}],
        "bufferViews":[{{"buffer":0,"byteOffset":0,"byteLength":48}},{{"buffer":0,"byteOffset":48,"byteLength":24}},
        {{"buffer":0,"byteOffset":72,"byteLength":32}},{{"buffer":0,"byteOffset":104,"byteLength":48}}],
        "accessors":[{{"bufferView":0,"componentType":5126,"count":4,"type":"VEC3"}},
        {{"bufferView":1,"componentType":5123,"count":12,"type":"SCALAR"}},
        {{"bufferView":2,"componentType":5126,"count":4,"type":"VEC2"}},
        {{"bufferView":3,"componentType":5126,"count":4,"type":"VEC3"}}]}}"#,
        buf.len(),
        common::base64(&buf)
    )
}

#[test]
fn non_finite_accessor_values_are_refused_naming_the_accessor() {
    assert!(load_mesh(&write("fine.gltf", &poisoned(0, 0.5))).is_ok());
    for (accessor, role) in [(0, "POSITION"), (2, "TEXCOORD_0"), (3, "NORMAL")] {
        for value in [f32::NAN, f32::INFINITY, f32::NEG_INFINITY] {
            let name = format!("{role}.gltf");
            let err = load_mesh(&write(&name, &poisoned(accessor, value))).unwrap_err();
            let msg = err.to_string();
            assert!(
                matches!(err, SceneError::NonFiniteAttribute { .. }),
                "{role}: {err:?}"
            );
            for needle in [
                name.as_str(),
                role,
                &format!("accessor {accessor}, element 2"),
                "mesh \"tet\" primitive 0",
            ] {
                assert!(msg.contains(needle), "{needle:?} missing from: {msg}");
            }
            assert!(!msg.contains("report"), "{msg}");
        }
    }
}

/// A file that requires an extension the loader does not read (a Basis Universal texture
/// has no PNG or JPEG) is refused naming the extension and a way out,
/// before any accessor is read; an extension only used, not required, loads.
#[test]
fn a_required_extension_that_is_not_read_is_named_with_a_way_out() {
    let with = |used: &str, required: &str| {
        gltf(ONE_NODE, "[0]", PRIMITIVE, ACCESSORS).replacen(
            r#""asset":{"version":"2.0"},"#,
            &format!(
                r#""asset":{{"version":"2.0"}},"extensionsUsed":{used},"extensionsRequired":{required},"#
            ),
            1,
        )
    };
    for (extension, way_out) in [
        ("EXT_texture_webp", "PNG or JPEG"),
        ("KHR_texture_basisu", "PNG or JPEG"),
        ("EXT_made_up", "export the scene again"),
    ] {
        let list = format!(r#"["{extension}"]"#);
        refused(
            &format!("{extension}.gltf"),
            &with(&list, &list),
            &[extension, "does not read", way_out],
        );
    }
    let used = with(r#"["KHR_texture_transform"]"#, "[]");
    assert_eq!(
        load_mesh(&write("used.gltf", &used))
            .unwrap()
            .triangle_count(),
        4
    );
}
