//! Loading every supported format, and a typed error naming the file for each kind of
//! bad input.

mod common;

use std::path::Path;

use meshlight_scene::load::{load_mesh, parse_obj, parse_stl};
use meshlight_scene::mesh::{MAX_TRIANGLES, Mesh};
use meshlight_scene::{BuildOptions, SceneError, build_asset, procedural_mesh};

fn build(mesh: &Mesh) -> Result<meshlight_scene::Built, SceneError> {
    build_asset(mesh, &BuildOptions::default(), &mut |_| {})
}

#[test]
fn obj_polygons_are_triangulated_and_normals_generated() {
    let text = b"v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0.5 1.5 0\nf 1 2 3 5 4\n";
    let mut mesh = parse_obj(Path::new("pentagon.obj"), text).unwrap();
    assert_eq!(mesh.triangle_count(), 3, "a pentagon is three triangles");
    assert!(mesh.normals.is_empty());
    mesh.clean().unwrap();
    for n in &mesh.normals {
        assert!(
            (n.z - 1.0).abs() < 1e-6,
            "generated normal {n} should face +z"
        );
    }
}

#[test]
fn obj_with_normals_and_uvs_keeps_them() {
    let text =
        b"v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 0 1\nvn 0 0 1\nf 1/1/1 2/2/1 3/3/1\n";
    let mesh = parse_obj(Path::new("tri.obj"), text).unwrap();
    assert_eq!(mesh.uvs, vec![[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]]);
    assert_eq!(mesh.normals.len(), 3);
}

#[test]
fn stl_ascii_and_binary_load_the_same_welded_mesh() {
    let (p, idx) = common::tetrahedron();
    let mut ascii = String::from("solid tet\n");
    let mut binary = vec![0u8; 80];
    binary.extend_from_slice(&4u32.to_le_bytes());
    for t in idx.chunks(3) {
        ascii += "facet normal 0 0 0\nouter loop\n";
        binary.extend_from_slice(&[0u8; 12]);
        for &i in t {
            let v = p[i as usize];
            ascii += &format!("vertex {} {} {}\n", v[0], v[1], v[2]);
            for c in v {
                binary.extend_from_slice(&c.to_le_bytes());
            }
        }
        ascii += "endloop\nendfacet\n";
        binary.extend_from_slice(&[0u8; 2]);
    }
    ascii += "endsolid tet\n";
    let a = parse_stl(Path::new("a.stl"), ascii.as_bytes()).unwrap();
    let b = parse_stl(Path::new("b.stl"), &binary).unwrap();
    assert_eq!(a.positions.len(), 4, "corners are welded by position");
    assert_eq!(a.triangle_count(), 4);
    assert_eq!(
        (a.positions.clone(), a.indices.clone()),
        (b.positions, b.indices)
    );
}

#[test]
fn stl_quad_facets_are_fan_triangulated() {
    let text = "solid q\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 1 1 0\nvertex 0 1 0\nendloop\nendfacet\nendsolid q\n";
    let mesh = parse_stl(Path::new("quad.stl"), text.as_bytes()).unwrap();
    assert_eq!(mesh.triangle_count(), 2);
}

fn gltf_json(buffer_uri: &str, buffer_len: usize) -> String {
    // One mesh with two primitives (the second is the first shifted by its node), used
    // by two nodes, one translated by +10 in x and one scaled by -1 (mirrored).
    format!(
        r#"{{"asset":{{"version":"2.0"}},"scene":0,"scenes":[{{"nodes":[0]}}],
        "nodes":[{{"children":[1,2]}},{{"mesh":0,"translation":[10,0,0]}},{{"mesh":0,"scale":[-1,1,1]}}],
        "meshes":[{{"primitives":[{{"attributes":{{"POSITION":0}},"indices":1}},{{"attributes":{{"POSITION":0,"TEXCOORD_0":2}},"indices":1}}]}}],
        "buffers":[{{"byteLength":{buffer_len}{buffer_uri}}}],
        "bufferViews":[{{"buffer":0,"byteOffset":0,"byteLength":48}},{{"buffer":0,"byteOffset":48,"byteLength":24}},{{"buffer":0,"byteOffset":72,"byteLength":32}}],
        "accessors":[{{"bufferView":0,"componentType":5126,"count":4,"type":"VEC3","min":[0,0,0],"max":[1,1,1]}},
                     {{"bufferView":1,"componentType":5123,"count":12,"type":"SCALAR"}},
                     {{"bufferView":2,"componentType":5126,"count":4,"type":"VEC2"}}]}}"#
    )
}

/// [`gltf_json`] with the tetrahedron's buffer embedded as a base64 data URI.
fn embedded_gltf_json() -> String {
    let buf = common::gltf::tetrahedron_buffer();
    let uri = format!(
        r#","uri":"data:application/octet-stream;base64,{}""#,
        common::base64(&buf)
    );
    gltf_json(&uri, buf.len())
}

#[test]
fn gltf_applies_node_transforms_and_merges_primitives() {
    let dir = common::scratch("gltf");
    let path = dir.join("tet.gltf");
    std::fs::write(&path, embedded_gltf_json()).unwrap();
    let mesh = load_mesh(&path).unwrap();
    // 2 nodes × 2 primitives × 4 triangles.
    assert_eq!(mesh.triangle_count(), 16);
    let (min, max) = mesh.bounds();
    assert_eq!(min.x, -1.0, "the mirrored node reaches x = -1");
    assert_eq!(max.x, 11.0, "the translated node reaches x = 11");
    // Only one primitive has UVs, so the merged mesh has none rather than wrong ones.
    assert!(mesh.uvs.is_empty());
    // Mirroring flips winding back: every face normal of the cleaned mesh points out.
    let mut cleaned = mesh.clone();
    cleaned.clean().unwrap();
    for t in cleaned.indices.chunks(3) {
        let [a, b, c] = [t[0], t[1], t[2]].map(|i| cleaned.positions[i as usize]);
        let centre = (a + b + c) / 3.0;
        let part_centre = if centre.x > 5.0 {
            glam::Vec3::new(10.25, 0.25, 0.25)
        } else {
            glam::Vec3::new(-0.25, 0.25, 0.25)
        };
        assert!(
            (b - a).cross(c - a).dot(centre - part_centre) > 0.0,
            "inward face at {centre}"
        );
    }
}

#[test]
fn glb_loads_from_its_binary_chunk() {
    let dir = common::scratch("glb");
    let buf = common::gltf::tetrahedron_buffer();
    let glb = common::gltf::glb_container(&gltf_json("", buf.len()), &buf);
    let path = dir.join("tet.glb");
    std::fs::write(&path, glb).unwrap();
    assert_eq!(load_mesh(&path).unwrap().triangle_count(), 16);
}

#[test]
fn gltf_without_position_is_refused() {
    let dir = common::scratch("gltf-nopos");
    let json = embedded_gltf_json().replace(
        r#""attributes":{"POSITION":0}"#,
        r#""attributes":{"TEXCOORD_0":2}"#,
    );
    let path = dir.join("nopos.gltf");
    std::fs::write(&path, json).unwrap();
    let err = load_mesh(&path).unwrap_err();
    assert!(
        matches!(err, SceneError::GltfMissingPosition { primitive: 0, .. }),
        "{err:?}"
    );
    let msg = err.to_string();
    assert!(
        msg.contains("nopos.gltf") && msg.contains("POSITION"),
        "{msg}"
    );
}

#[test]
fn empty_mesh_is_refused() {
    let mesh = parse_obj(Path::new("empty.obj"), b"v 0 0 0\nv 1 0 0\nv 0 1 0\n").unwrap();
    let err = build(&mesh).unwrap_err();
    assert!(matches!(err, SceneError::EmptyMesh { .. }), "{err:?}");
    assert!(err.to_string().contains("empty.obj"));
}

/// The error every loader gives for a value that is not a finite number: typed, naming
/// the file, where in it, and the attribute; never an internal failure.
fn non_finite(err: SceneError, file: &str, location: &str, attribute: &str) {
    let msg = err.to_string();
    match &err {
        SceneError::NonFiniteAttribute {
            location: l,
            attribute: a,
            ..
        } => {
            assert_eq!(l, location, "{msg}");
            assert!(a.contains(attribute), "{msg}");
        }
        other => panic!("{file}: expected NonFiniteAttribute, got {other:?}"),
    }
    assert!(msg.contains(file) && msg.contains(location), "{msg}");
    assert!(!msg.contains("report"), "{msg}");
}

#[test]
fn non_finite_obj_values_are_refused_with_their_line() {
    let face = "f 1/1/1 2/2/1 3/3/1\n";
    for bad in ["nan", "inf", "-inf", "1e39", "NaN"] {
        let v = format!("v 0 0 0\nv 1 {bad} 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 0 1\nvn 0 0 1\n{face}");
        let err = parse_obj(Path::new("v.obj"), v.as_bytes()).unwrap_err();
        non_finite(err, "v.obj", "line 2", "`v`");
        let vt = format!("v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 0 {bad}\nvn 0 0 1\n{face}");
        let err = parse_obj(Path::new("vt.obj"), vt.as_bytes()).unwrap_err();
        non_finite(err, "vt.obj", "line 6", "`vt`");
        let vn = format!("v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 0 1\nvn 0 {bad} 1\n{face}");
        let err = parse_obj(Path::new("vn.obj"), vn.as_bytes()).unwrap_err();
        non_finite(err, "vn.obj", "line 7", "`vn`");
    }
}

#[test]
fn non_finite_stl_corners_are_refused() {
    for bad in ["nan", "inf", "-1e39"] {
        let ascii = format!(
            "solid s\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 0 {bad} 0\n\
             endloop\nendfacet\nendsolid s\n"
        );
        let err = parse_stl(Path::new("a.stl"), ascii.as_bytes()).unwrap_err();
        non_finite(err, "a.stl", "line 6", "position");
    }
    let mut binary = vec![0u8; 80];
    binary.extend_from_slice(&2u32.to_le_bytes());
    for t in 0..2 {
        binary.extend_from_slice(&[0u8; 12]);
        for (k, corner) in [[0.0f32, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]
            .iter()
            .enumerate()
        {
            let mut c = *corner;
            if t == 1 && k == 2 {
                c[2] = f32::NAN;
            }
            binary.extend_from_slice(bytemuck::cast_slice(&c));
        }
        binary.extend_from_slice(&[0u8; 2]);
    }
    let err = parse_stl(Path::new("b.stl"), &binary).unwrap_err();
    non_finite(err, "b.stl", "triangle 1, corner 2", "position");
}

/// A mesh built in memory has no file lines: the vertex is named instead.
#[test]
fn non_finite_positions_and_uvs_in_memory_are_refused() {
    let mut mesh = procedural_mesh(8);
    mesh.positions[1].y = f32::NAN;
    let err = build(&mesh).unwrap_err();
    assert!(
        matches!(err, SceneError::NonFinitePosition { vertex: 1, .. }),
        "{err:?}"
    );
    let mut mesh = procedural_mesh(8);
    mesh.uvs = vec![[0.5, 0.5]; mesh.positions.len()];
    mesh.uvs[7][1] = f32::INFINITY;
    non_finite(
        build(&mesh).unwrap_err(),
        "procedural",
        "vertex 7",
        "texture",
    );
}

/// Parses `text` as the OBJ file `name`, expects an `Obj` error naming the file, and
/// returns its message.
fn obj_refused(name: &str, text: &str) -> String {
    let err = parse_obj(Path::new(name), text.as_bytes()).unwrap_err();
    assert!(matches!(err, SceneError::Obj { .. }), "{err:?}");
    let msg = err.to_string();
    assert!(msg.contains(name), "{msg}");
    msg
}

#[test]
fn indices_out_of_range_are_refused() {
    let msg = obj_refused("oob.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n");
    assert!(msg.contains("vertex index"), "{msg}");

    let mut mesh = procedural_mesh(8);
    mesh.indices[7] = mesh.positions.len() as u32 + 5;
    let err = build(&mesh).unwrap_err();
    assert!(
        matches!(err, SceneError::IndexOutOfRange { triangle: 2, .. }),
        "{err:?}"
    );
}

#[test]
fn degenerate_triangles_are_dropped_and_counted() {
    let mut mesh = procedural_mesh(8);
    let n = mesh.triangle_count();
    mesh.indices.extend_from_slice(&[0, 0, 1]); // repeated index
    let a = mesh.positions.len() as u32;
    mesh.positions
        .extend([glam::Vec3::ZERO, glam::Vec3::X, glam::Vec3::X * 2.0]); // collinear
    mesh.normals.extend([glam::Vec3::Z; 3]);
    mesh.indices.extend_from_slice(&[a, a + 1, a + 2]);
    let built = build(&mesh).unwrap();
    assert_eq!(built.clean.dropped_degenerate, 2);
    assert_eq!(built.asset.header().dropped_degenerate, 2);
    assert_eq!(built.asset.header().lod0_triangles as usize, n);
}

#[test]
fn open_non_manifold_mesh_still_builds() {
    let path = common::shared_mesh("teapot.obj");
    let built = build(&load_mesh(&path).unwrap()).unwrap();
    assert!(meshlight_scene::verify::verify(&built.asset).is_empty());
}

#[test]
fn oversized_meshes_are_refused_up_front() {
    // A binary STL header claiming more triangles than the format holds is refused from
    // its 84 bytes, before anything is allocated.
    let mut stl = vec![0u8; 80];
    stl.extend_from_slice(&(MAX_TRIANGLES as u32 + 1).to_le_bytes());
    let err = parse_stl(Path::new("huge.stl"), &stl).unwrap_err();
    match &err {
        SceneError::TooLarge { limit, what, .. } => {
            assert_eq!((*limit, *what), (MAX_TRIANGLES, "triangles"));
        }
        other => panic!("{other:?}"),
    }
    assert!(err.to_string().contains("huge.stl") && err.to_string().contains("split the mesh"));
    assert!(Mesh::check_limits("m", 3, MAX_TRIANGLES).is_ok());
}

#[test]
fn unreadable_files_name_the_path() {
    let err = load_mesh(Path::new("/nonexistent/dir/mesh.obj")).unwrap_err();
    assert!(matches!(err, SceneError::Io { .. }), "{err:?}");
    assert!(err.to_string().contains("/nonexistent/dir/mesh.obj"));
    let err = load_mesh(Path::new("mesh.ply")).unwrap_err();
    assert!(
        matches!(err, SceneError::UnsupportedFormat { .. }),
        "{err:?}"
    );
}

#[test]
fn truncated_stl_is_refused() {
    let err = parse_stl(
        Path::new("t.stl"),
        b"solid x\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\n",
    )
    .unwrap_err();
    assert!(matches!(err, SceneError::Stl { .. }), "{err:?}");
    let mut binary = vec![0u8; 80];
    binary.extend_from_slice(&10u32.to_le_bytes());
    binary.extend_from_slice(&[0u8; 100]);
    let err = parse_stl(Path::new("t.stl"), &binary).unwrap_err();
    assert!(err.to_string().contains("truncated"), "{err}");
}

#[test]
fn gltf_reads_buffers_from_files_beside_it() {
    let dir = common::scratch("gltf-bin");
    let buf = common::gltf::tetrahedron_buffer();
    std::fs::write(dir.join("tet data.bin"), &buf).unwrap();
    let path = dir.join("tet.gltf");
    std::fs::write(&path, gltf_json(r#","uri":"tet%20data.bin""#, buf.len())).unwrap();
    assert_eq!(load_mesh(&path).unwrap().triangle_count(), 16);

    std::fs::remove_file(dir.join("tet data.bin")).unwrap();
    let err = load_mesh(&path).unwrap_err();
    assert!(matches!(err, SceneError::Gltf { .. }), "{err:?}");
    assert!(err.to_string().contains("beside the .gltf"), "{err}");

    // A buffer shorter than it says.
    std::fs::write(dir.join("tet data.bin"), &buf[..40]).unwrap();
    let err = load_mesh(&path).unwrap_err();
    assert!(err.to_string().contains("byteLength"), "{err}");
}

#[test]
fn obj_face_indices_past_either_end_are_refused() {
    // A relative index before the first texture coordinate (overflowed inside tobj),
    // and an absurdly large one.
    for (text, what) in [
        (
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nf 1/-11 2/1 3/1\n",
            "texture coordinate index -11",
        ),
        (
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 1\nf 1//9223372036854775807 2//1 3//1\n",
            "normal index 9223372036854775807",
        ),
        ("v 0 0 0\nv 1 0 0\nf 1 2 -3\n", "vertex index -3"),
    ] {
        let msg = obj_refused("bad-face.obj", text);
        assert!(msg.contains(what), "{msg}");
    }
    // Relative indices within range still load.
    let mesh = parse_obj(
        Path::new("rel.obj"),
        b"v 0 0 0\nv 1 0 0\nv 0 1 0\nf -3 -2 -1\n",
    )
    .unwrap();
    assert_eq!(mesh.triangle_count(), 1);
}
