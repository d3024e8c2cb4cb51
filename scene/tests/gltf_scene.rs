//! A glTF file kept as a scene: each mesh read once, each node that places it an
//! instance with its world transform, cameras with their nodes; the same file merged
//! into one mesh places the same triangles. Files written by the tests, so every
//! transform is known.

mod common;

use glam::{Mat4, Quat, Vec3};
use meshlight_scene::SceneError;
use meshlight_scene::load::{
    AlphaMode, CameraProjection, DEFAULT_MATERIAL, LoadOptions, load_gltf_scene,
    load_gltf_scene_with, load_mesh, load_mesh_with,
};
use meshlight_testing::gltf_writer::{GltfWriter, Node, Primitive};
use serde_json::json;

fn tetrahedron() -> Primitive {
    let (p, i) = common::tetrahedron();
    Primitive {
        positions: p,
        indices: i.into_iter().map(u32::from).collect(),
        uvs: Some(vec![[0.0, 0.0], [1.0, 0.0], [0.0, 1.0], [1.0, 1.0]]),
        ..Primitive::default()
    }
}

use common::gltf::unit_quad as quad;

struct Written {
    path: std::path::PathBuf,
    /// The world transform of each node placing the tetrahedron, in depth-first order.
    tetrahedra: Vec<Mat4>,
    quad: Mat4,
}

/// A tree: a parent turned and moved, with three children placing the tetrahedron (one
/// mirrored, one by matrix) and a grandchild placing the quad; a camera on its own
/// node; and a mesh no node places.
fn write_scene(dir: &std::path::Path) -> Written {
    let mut w = GltfWriter::new();
    let tet = w.mesh("tetrahedron", &[tetrahedron()]);
    let quad_mesh = w.mesh("quad", &[quad()]);
    w.mesh("unplaced", &[quad()]);
    let camera = w.perspective_camera("overview", 0.8, 0.05);

    let turn = Quat::from_rotation_y(0.5);
    let parent = Mat4::from_rotation_translation(turn, Vec3::new(0.0, 2.0, 0.0));
    let a = Mat4::from_translation(Vec3::new(5.0, 0.0, 0.0));
    let b = Mat4::from_scale(Vec3::new(-1.0, 1.0, 1.0));
    let c = Mat4::from_scale_rotation_translation(
        Vec3::splat(2.0),
        Quat::from_rotation_x(0.3),
        Vec3::new(0.0, 0.0, -3.0),
    );
    let q = Mat4::from_translation(Vec3::new(1.0, 1.0, 1.0));
    let n_a = w.node(Node {
        mesh: Some(tet),
        translation: Some([5.0, 0.0, 0.0]),
        ..Node::default()
    });
    let n_b = w.node(Node {
        mesh: Some(tet),
        scale: Some([-1.0, 1.0, 1.0]),
        ..Node::default()
    });
    let n_q = w.node(Node {
        mesh: Some(quad_mesh),
        translation: Some([1.0, 1.0, 1.0]),
        ..Node::default()
    });
    let n_c = w.node(Node {
        mesh: Some(tet),
        matrix: Some(c.to_cols_array()),
        children: vec![n_q],
        ..Node::default()
    });
    let root = w.node(Node {
        name: Some("parent".into()),
        rotation: Some(turn.to_array()),
        translation: Some([0.0, 2.0, 0.0]),
        children: vec![n_a, n_b, n_c],
        ..Node::default()
    });
    let cam = w.node(Node {
        camera: Some(camera),
        translation: Some([0.0, 1.0, 10.0]),
        ..Node::default()
    });
    w.scene(&[root, cam]);
    let path = dir.join("scene.glb");
    std::fs::write(&path, w.glb()).unwrap();
    Written {
        path,
        tetrahedra: vec![parent * a, parent * b, parent * c],
        quad: parent * c * q,
    }
}

fn assert_close(a: Mat4, b: Mat4, what: &str) {
    assert!(
        a.abs_diff_eq(b, 1e-5),
        "{what}: loaded {a:?}, expected {b:?}"
    );
}

#[test]
fn a_scene_keeps_each_mesh_once_and_every_node_as_an_instance() {
    let dir = common::scratch("gltf-scene");
    let written = write_scene(&dir);
    let scene = load_gltf_scene(&written.path).unwrap();

    // Two meshes placed (the third is not): each read once, in its own space.
    let names: Vec<&str> = scene.meshes.iter().map(|m| m.name.as_str()).collect();
    assert_eq!(names, ["tetrahedron", "quad"]);
    assert_eq!(scene.meshes[0].mesh.triangle_count(), 4);
    assert_eq!(scene.meshes[0].mesh.positions[1], Vec3::X, "untransformed");
    assert_eq!(scene.meshes[1].mesh.triangle_count(), 2);

    // Four instances in depth-first order, at their world transforms.
    let tetrahedra: Vec<_> = scene.instances.iter().filter(|i| i.mesh == 0).collect();
    assert_eq!(tetrahedra.len(), 3);
    for (i, expected) in tetrahedra.iter().zip(&written.tetrahedra) {
        assert_close(i.transform, *expected, "a tetrahedron");
    }
    let quads: Vec<_> = scene.instances.iter().filter(|i| i.mesh == 1).collect();
    assert_eq!(quads.len(), 1);
    assert_close(
        quads[0].transform,
        written.quad,
        "the quad under the matrix node",
    );

    // The camera, where its node puts it.
    assert_eq!(scene.cameras.len(), 1);
    let camera = &scene.cameras[0];
    assert_eq!(camera.name, "overview");
    assert_close(
        camera.transform,
        Mat4::from_translation(Vec3::new(0.0, 1.0, 10.0)),
        "the camera",
    );
    assert_eq!(
        camera.projection,
        CameraProjection::Perspective {
            yfov: 0.8,
            znear: 0.05,
            aspect_ratio: None
        }
    );

    // Merged into one mesh, the same file places the same triangles at the same places.
    let merged = load_mesh(&written.path).unwrap();
    assert_eq!(merged.triangle_count(), 3 * 4 + 2);
    let placed: Vec<Vec3> = scene
        .instances
        .iter()
        .flat_map(|i| {
            let m = &scene.meshes[i.mesh].mesh;
            m.positions
                .iter()
                .map(move |&p| i.transform.transform_point3(p))
        })
        .collect();
    assert_eq!(placed.len(), merged.positions.len());
    for (p, q) in placed.iter().zip(&merged.positions) {
        assert!(p.abs_diff_eq(*q, 1e-5), "{p} vs {q}");
    }
}

/// The triangle budget bounds what would be baked: the distinct meshes of a scene, not
/// its instances; merged into one mesh, every copy counts.
#[test]
fn the_triangle_budget_counts_distinct_meshes_of_a_scene_and_every_copy_when_merged() {
    let dir = common::scratch("gltf-scene-budget");
    let mut w = GltfWriter::new();
    let tet = w.mesh("tetrahedron", &[tetrahedron()]);
    let nodes: Vec<usize> = (0..1000)
        .map(|i| {
            w.node(Node {
                mesh: Some(tet),
                translation: Some([i as f32 * 2.0, 0.0, 0.0]),
                ..Node::default()
            })
        })
        .collect();
    w.scene(&nodes);
    let path = dir.join("copies.glb");
    std::fs::write(&path, w.glb()).unwrap();
    let options = LoadOptions {
        max_triangles: 100,
        ..LoadOptions::default()
    };
    let scene = load_gltf_scene_with(&path, &options).unwrap();
    assert_eq!((scene.meshes.len(), scene.instances.len()), (1, 1000));
    match load_mesh_with(&path, &options) {
        Err(SceneError::TriangleBudget { count, budget, .. }) => {
            assert_eq!((count, budget), (4000, 100));
        }
        other => panic!("expected the triangle budget, got {other:?}"),
    }
    let tight = LoadOptions {
        max_triangles: 3,
        ..LoadOptions::default()
    };
    assert!(matches!(
        load_gltf_scene_with(&path, &tight),
        Err(SceneError::TriangleBudget { count: 4, .. })
    ));
}

fn refused(camera: serde_json::Value) -> String {
    let dir = common::scratch("gltf-scene-camera");
    let mut w = GltfWriter::new();
    let tet = w.mesh("tetrahedron", &[tetrahedron()]);
    let c = w.raw_camera(camera);
    let a = w.node(Node {
        mesh: Some(tet),
        ..Node::default()
    });
    let b = w.node(Node {
        camera: Some(c),
        ..Node::default()
    });
    w.scene(&[a, b]);
    let path = dir.join("camera.glb");
    std::fs::write(&path, w.glb()).unwrap();
    match load_gltf_scene(&path) {
        Err(e @ SceneError::Gltf { .. }) => e.to_string(),
        other => panic!("expected a glTF error, got {other:?}"),
    }
}

#[test]
fn cameras_that_cannot_project_are_refused_by_name() {
    let e = refused(json!({"name": "wide", "type": "perspective",
        "perspective": {"yfov": 4.0, "znear": 0.1}}));
    assert!(
        e.contains("camera \"wide\"") && e.contains("yfov is 4"),
        "{e}"
    );
    let e = refused(json!({"type": "perspective", "perspective": {"yfov": 0.8, "znear": 0.0}}));
    assert!(
        e.contains("camera \"#0\"") && e.contains("znear is 0"),
        "{e}"
    );
    let e = refused(json!({"type": "orthographic",
        "orthographic": {"xmag": 1.0, "ymag": 1.0, "znear": 5.0, "zfar": 1.0}}));
    assert!(e.contains("znear < zfar"), "{e}");
    let e = refused(json!({"type": "perspective"}));
    assert!(e.contains("not \"perspective\" or \"orthographic\""), "{e}");
}

#[test]
fn a_node_naming_a_missing_camera_is_refused() {
    let dir = common::scratch("gltf-scene-missing-camera");
    let mut w = GltfWriter::new();
    let tet = w.mesh("tetrahedron", &[tetrahedron()]);
    let a = w.node(Node {
        mesh: Some(tet),
        camera: Some(3),
        ..Node::default()
    });
    w.scene(&[a]);
    let path = dir.join("camera.glb");
    std::fs::write(&path, w.glb()).unwrap();
    let e = load_gltf_scene(&path).unwrap_err().to_string();
    assert!(
        e.contains("camera 3") && e.contains("only 0 cameras"),
        "{e}"
    );
}

/// One mesh of five primitives, each its own material (the fifth none: glTF's default).
fn five_materials(materials: &[serde_json::Value]) -> (GltfWriter, usize) {
    let mut w = GltfWriter::new();
    let ids: Vec<usize> = materials.iter().map(|m| w.material(m.clone())).collect();
    let primitives: Vec<Primitive> = (0..5)
        .map(|k| {
            let mut p = quad();
            for v in &mut p.positions {
                v[0] += k as f32 * 2.0;
            }
            p.material = ids.get(k).copied();
            p
        })
        .collect();
    let mesh = w.mesh("five", &primitives);
    let node = w.node(Node {
        mesh: Some(mesh),
        ..Node::default()
    });
    w.scene(&[node]);
    (w, mesh)
}

#[test]
fn materials_are_read_with_their_factors_and_each_triangle_keeps_its_primitives() {
    let materials = [
        json!({"name": "red", "pbrMetallicRoughness": {"baseColorFactor": [1.0, 0.0, 0.0, 1.0], "metallicFactor": 0.0, "roughnessFactor": 0.4}}),
        json!({"name": "gold", "pbrMetallicRoughness": {"baseColorFactor": [1.0, 0.8, 0.3, 1.0], "metallicFactor": 1.0, "roughnessFactor": 0.2}}),
        json!({"name": "leaves", "alphaMode": "MASK", "alphaCutoff": 0.3, "doubleSided": true}),
        json!({"name": "lamp", "emissiveFactor": [2.0, 1.5, 0.5], "alphaMode": "BLEND"}),
    ];
    let (w, _) = five_materials(&materials);
    let dir = common::scratch("gltf-materials");
    let path = dir.join("five.glb");
    std::fs::write(&path, w.glb()).unwrap();
    let scene = load_gltf_scene(&path).unwrap();
    assert_eq!(scene.materials.len(), 4);
    let red = &scene.materials[0];
    assert_eq!(
        (red.name.as_str(), red.base_color),
        ("red", [1.0, 0.0, 0.0, 1.0])
    );
    assert_eq!((red.metallic, red.roughness), (0.0, 0.4));
    assert_eq!(scene.materials[1].metallic, 1.0);
    let leaves = &scene.materials[2];
    assert_eq!(leaves.alpha, AlphaMode::Mask { cutoff: 0.3 });
    assert!(leaves.double_sided);
    // Unset factors take glTF's defaults.
    assert_eq!(
        (leaves.base_color, leaves.metallic, leaves.roughness),
        ([1.0; 4], 1.0, 1.0)
    );
    assert_eq!(scene.materials[3].emissive, [2.0, 1.5, 0.5]);
    assert_eq!(scene.materials[3].alpha, AlphaMode::Blend);
    // Two triangles per primitive, each with its primitive's slot, each slot with
    // its primitive's material.
    let m = &scene.meshes[0];
    assert_eq!(m.mesh.triangle_count(), 10);
    assert_eq!(m.mesh.materials, [0, 0, 1, 1, 2, 2, 3, 3, 4, 4]);
    assert_eq!(m.materials, [0, 1, 2, 3, DEFAULT_MATERIAL]);
}

fn refused_material(material: serde_json::Value) -> String {
    let (w, _) = five_materials(&[material]);
    let dir = common::scratch("gltf-bad-material");
    let path = dir.join("bad.glb");
    std::fs::write(&path, w.glb()).unwrap();
    match load_gltf_scene(&path) {
        Err(e @ SceneError::Gltf { .. }) => e.to_string(),
        other => panic!("expected a glTF error, got {other:?}"),
    }
}

#[test]
fn materials_out_of_range_are_refused_naming_the_material_and_the_value() {
    let e = refused_material(
        json!({"name": "hot", "pbrMetallicRoughness": {"baseColorFactor": [1.5, 0.0, 0.0, 1.0]}}),
    );
    assert!(
        e.contains("material \"hot\"") && e.contains("baseColorFactor[0] is 1.5"),
        "{e}"
    );
    let e = refused_material(json!({"pbrMetallicRoughness": {"roughnessFactor": -0.25}}));
    assert!(
        e.contains("material \"#0\"") && e.contains("roughnessFactor is -0.25"),
        "{e}"
    );
    let e = refused_material(json!({"emissiveFactor": [-1.0, 0.0, 0.0]}));
    assert!(e.contains("emissiveFactor holds -1"), "{e}");
    let e = refused_material(json!({"alphaMode": "MASK", "alphaCutoff": -0.5}));
    assert!(e.contains("alphaCutoff is -0.5"), "{e}");
    let e = refused_material(json!({"alphaMode": "GLASS"}));
    assert!(e.contains("not OPAQUE, MASK or BLEND"), "{e}");
    let e = refused_material(json!({"pbrMetallicRoughness": {"baseColorTexture": {"index": 2}}}));
    assert!(
        e.contains("base colour texture is texture 2") && e.contains("only 0 textures"),
        "{e}"
    );
    let e = refused_material(json!({"normalTexture": {"index": 0}}));
    assert!(e.contains("normal texture is texture 0"), "{e}");
}

#[test]
fn a_primitive_naming_a_missing_material_is_refused() {
    let mut w = GltfWriter::new();
    let mut p = quad();
    p.material = Some(7);
    let mesh = w.mesh("quad", &[p]);
    let node = w.node(Node {
        mesh: Some(mesh),
        ..Node::default()
    });
    w.scene(&[node]);
    let dir = common::scratch("gltf-missing-material");
    let path = dir.join("missing.glb");
    std::fs::write(&path, w.glb()).unwrap();
    let e = load_gltf_scene(&path).unwrap_err().to_string();
    assert!(
        e.contains("mesh \"quad\" primitive 0")
            && e.contains("material is 7")
            && e.contains("only 0 materials"),
        "{e}"
    );
}
