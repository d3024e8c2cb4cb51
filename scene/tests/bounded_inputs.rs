//! Inputs are bounded before they are read: mesh files and glTF buffers must be regular
//! files under the size limit, buffer URIs stay inside the model's folder, and a glTF
//! node tree's expansion is checked against a triangle budget before it happens.

mod common;

use std::path::PathBuf;
use std::time::{Duration, Instant};

use meshlight_scene::SceneError;
use meshlight_scene::load::{
    DEFAULT_TRIANGLE_BUDGET, LoadOptions, MAX_INPUT_BYTES, load_mesh, load_mesh_with,
};
use meshlight_scene::mesh::MAX_TRIANGLES;

/// A tetrahedron's buffer: 4 positions (48 bytes) then 12 u16 indices (24).
fn tetrahedron_buffer() -> Vec<u8> {
    let (p, idx) = common::tetrahedron();
    let mut buf: Vec<u8> = bytemuck::cast_slice(&p).to_vec();
    buf.extend_from_slice(bytemuck::cast_slice(&idx));
    buf
}

/// A .gltf whose one buffer has `uri`, `nodes` placing mesh 0, and `indices` declared
/// index count.
fn gltf_text(uri: &str, nodes: &str, indices: usize) -> String {
    format!(
        r#"{{"asset":{{"version":"2.0"}},"scene":0,"scenes":[{{"nodes":[0]}}],"nodes":{nodes},
        "meshes":[{{"primitives":[{{"attributes":{{"POSITION":0}},"indices":1}}]}}],
        "buffers":[{{"byteLength":72,"uri":{uri:?}}}],
        "bufferViews":[{{"buffer":0,"byteOffset":0,"byteLength":48}},{{"buffer":0,"byteOffset":48,"byteLength":24}}],
        "accessors":[{{"bufferView":0,"componentType":5126,"count":4,"type":"VEC3"}},
        {{"bufferView":1,"componentType":5123,"count":{indices},"type":"SCALAR"}}]}}"#
    )
}

/// A model folder holding `model.gltf` (buffer `uri`) and `mesh.bin`, next to a folder
/// `outside` holding `secret.bin`: both buffers are valid tetrahedra.
fn model(name: &str, uri: &str) -> (PathBuf, PathBuf) {
    let dir = common::scratch(&format!("bounded-{name}"));
    let folder = dir.join("model");
    let outside = dir.join("outside");
    std::fs::create_dir_all(folder.join("buffers")).unwrap();
    std::fs::create_dir_all(&outside).unwrap();
    std::fs::write(folder.join("mesh.bin"), tetrahedron_buffer()).unwrap();
    std::fs::write(folder.join("buffers/mesh.bin"), tetrahedron_buffer()).unwrap();
    std::fs::write(outside.join("secret.bin"), tetrahedron_buffer()).unwrap();
    let path = folder.join("model.gltf");
    std::fs::write(&path, gltf_text(uri, r#"[{"mesh":0}]"#, 12)).unwrap();
    (path, dir)
}

fn refused_uri(name: &str, uri: &str, needle: &str) {
    let (path, _) = model(name, uri);
    let err = load_mesh(&path).unwrap_err();
    let msg = err.to_string();
    assert!(matches!(err, SceneError::Gltf { .. }), "{name}: {err:?}");
    assert!(
        msg.contains("model.gltf") && msg.contains("buffer 0"),
        "{msg}"
    );
    assert!(
        msg.contains(needle),
        "{name}: {needle:?} missing from: {msg}"
    );
}

#[test]
fn buffer_uris_inside_the_model_folder_load() {
    for uri in [
        "mesh.bin",
        "./mesh.bin",
        "buffers/mesh.bin",
        "buffers%2Fmesh.bin",
    ] {
        let (path, _) = model("inside", uri);
        let mesh = load_mesh(&path).unwrap_or_else(|e| panic!("{uri}: {e}"));
        assert_eq!(mesh.triangle_count(), 4);
    }
}

#[test]
fn buffer_uris_outside_the_model_folder_are_refused() {
    let (_, dir) = model("absolute-target", "mesh.bin");
    let secret = dir.join("outside/secret.bin");
    refused_uri("absolute", secret.to_str().unwrap(), "absolute path");
    refused_uri("hostname", "/etc/hostname", "absolute path");
    refused_uri("file-scheme", "file:///etc/hostname", "URI scheme");
    refused_uri("dotdot", "../outside/secret.bin", "`..`");
    refused_uri("dotdot-inner", "buffers/../../outside/secret.bin", "`..`");
    refused_uri("dotdot-escaped", "%2E%2E/outside/secret.bin", "`..`");
}

#[cfg(unix)]
#[test]
fn links_out_of_the_model_folder_and_devices_are_refused() {
    let (path, dir) = model("link", "link.bin");
    std::os::unix::fs::symlink(dir.join("outside/secret.bin"), dir.join("model/link.bin")).unwrap();
    let msg = load_mesh(&path).unwrap_err().to_string();
    assert!(msg.contains("outside the model's folder"), "{msg}");

    // A device file inside the folder (a link to /dev/zero) leads outside it too; named
    // directly as a mesh, it is refused from its metadata, without reading.
    let (path, dir) = model("zero", "zero.bin");
    std::os::unix::fs::symlink("/dev/zero", dir.join("model/zero.bin")).unwrap();
    assert!(load_mesh(&path).is_err());
    let zero = dir.join("zero.obj");
    std::os::unix::fs::symlink("/dev/zero", &zero).unwrap();
    let start = Instant::now();
    let err = load_mesh(&zero).unwrap_err();
    assert!(start.elapsed() < Duration::from_secs(5));
    assert!(
        matches!(
            err,
            SceneError::NotARegularFile {
                kind: "a character device",
                ..
            }
        ),
        "{err:?}"
    );
    assert!(err.to_string().contains("zero.obj"), "{err}");
}

#[test]
fn buffers_and_meshes_must_be_regular_files() {
    // A folder named like a buffer, inside the model's folder.
    let (path, _) = model("folder", "buffers");
    let msg = load_mesh(&path).unwrap_err().to_string();
    assert!(msg.contains("not a regular file"), "{msg}");
    let dir = common::scratch("bounded-folder-mesh");
    let folder = dir.join("folder.stl");
    std::fs::create_dir_all(&folder).unwrap();
    let err = load_mesh(&folder).unwrap_err();
    assert!(
        matches!(
            err,
            SceneError::NotARegularFile {
                kind: "a directory",
                ..
            }
        ),
        "{err:?}"
    );
}

/// A sparse file just past the limit: refused from its size, not by reading 2 GiB.
#[test]
fn inputs_past_the_size_limit_are_refused_before_reading() {
    let dir = common::scratch("bounded-size");
    for name in ["huge.stl", "huge.obj", "huge.glb"] {
        let path = dir.join(name);
        let file = std::fs::File::create(&path).unwrap();
        file.set_len(MAX_INPUT_BYTES + 1).unwrap();
        let start = Instant::now();
        let err = load_mesh(&path).unwrap_err();
        assert!(start.elapsed() < Duration::from_secs(5));
        match &err {
            SceneError::FileTooLarge { size, limit, .. } => {
                assert_eq!((*size, *limit), (MAX_INPUT_BYTES + 1, MAX_INPUT_BYTES));
            }
            other => panic!("{name}: {other:?}"),
        }
        assert!(err.to_string().contains(name), "{err}");
        std::fs::remove_file(&path).unwrap();
    }
    // The same for a buffer a glTF names.
    let (path, dir) = model("huge-buffer", "huge.bin");
    let file = std::fs::File::create(dir.join("model/huge.bin")).unwrap();
    file.set_len(MAX_INPUT_BYTES + 1).unwrap();
    let msg = load_mesh(&path).unwrap_err().to_string();
    assert!(
        msg.contains("huge.bin") && msg.contains("more than"),
        "{msg}"
    );
}

/// Node `i` lists node `i + 1` twice: the last node (with the mesh) is reached by
/// 2^(levels - 1) paths.
fn doubling_tree(levels: usize) -> String {
    let nodes: Vec<String> = (0..levels)
        .map(|i| match i + 1 < levels {
            true => format!(r#"{{"children":[{0},{0}]}}"#, i + 1),
            false => r#"{"mesh":0}"#.to_owned(),
        })
        .collect();
    format!("[{}]", nodes.join(","))
}

#[test]
fn node_tree_expansion_is_checked_against_the_triangle_budget_first() {
    let dir = common::scratch("bounded-budget");
    std::fs::write(dir.join("mesh.bin"), tetrahedron_buffer()).unwrap();
    // 2^13 instances of a mesh declaring 2,000 triangles: 16.4 million, over the
    // default budget, refused from the declared counts before a byte is expanded.
    let path = dir.join("instanced.gltf");
    std::fs::write(&path, gltf_text("mesh.bin", &doubling_tree(14), 6000)).unwrap();
    let err = load_mesh(&path).unwrap_err();
    match &err {
        SceneError::TriangleBudget { count, budget, .. } => {
            assert_eq!((*count, *budget), (8192 * 2000, DEFAULT_TRIANGLE_BUDGET));
        }
        other => panic!("{other:?}"),
    }
    let msg = err.to_string();
    for needle in ["instanced.gltf", "16384000", "8388608", "--max-triangles"] {
        assert!(msg.contains(needle), "{needle:?} missing from: {msg}");
    }
    // Raised, the budget lets the expansion go ahead (and the file's own short index
    // buffer is what stops it).
    let raised = LoadOptions {
        max_triangles: 1 << 25,
        ..LoadOptions::default()
    };
    let err = load_mesh_with(&path, &raised).unwrap_err();
    assert!(matches!(err, SceneError::Gltf { .. }), "{err:?}");
    // Within the budget, a valid instanced scene loads.
    std::fs::write(&path, gltf_text("mesh.bin", &doubling_tree(4), 12)).unwrap();
    assert_eq!(load_mesh(&path).unwrap().triangle_count(), 8 * 4);
    let small = LoadOptions {
        max_triangles: 31,
        ..LoadOptions::default()
    };
    let err = load_mesh_with(&path, &small).unwrap_err();
    assert!(
        matches!(
            err,
            SceneError::TriangleBudget {
                count: 32,
                budget: 31,
                ..
            }
        ),
        "{err:?}"
    );
    let err = load_mesh_with(
        &path,
        &LoadOptions {
            max_triangles: MAX_TRIANGLES + 1,
            ..LoadOptions::default()
        },
    )
    .unwrap_err();
    assert!(matches!(err, SceneError::InvalidOption(_)), "{err:?}");
}
