//! Vertex colours from glTF (`COLOR_0` as normalized bytes and as floats, RGB and RGBA,
//! white where a primitive has none) and from OBJ (`v x y z r g b`, read as sRGB), and
//! damaged colour accessors refused naming `COLOR_0`.

mod common;

use meshlight_scene::load::{load_gltf_scene, load_mesh, parse_obj};
use meshlight_testing::gltf_writer::{Colors, GltfWriter, Node, Primitive};
use serde_json::{Value, json};

fn quad(colors: Option<Colors>) -> Primitive {
    Primitive {
        colors,
        ..common::gltf::unit_quad()
    }
}

fn write(name: &str, bytes: &[u8]) -> std::path::PathBuf {
    let dir = common::scratch(&format!("vertex-colors-{name}"));
    let path = dir.join(format!("{name}.glb"));
    std::fs::write(&path, bytes).unwrap();
    path
}

/// One mesh of two primitives: byte RGBA colours, then none (white).
fn two_primitive_file() -> GltfWriter {
    let mut w = GltfWriter::new();
    let red = w.material(json!({"name": "red"}));
    let plain = w.material(json!({"name": "plain"}));
    let coloured = Primitive {
        material: Some(red),
        ..quad(Some(Colors::Rgba8(vec![
            [255, 0, 0, 255],
            [0, 255, 0, 128],
            [0, 0, 255, 0],
            [255, 255, 255, 255],
        ])))
    };
    let uncoloured = Primitive {
        material: Some(plain),
        ..quad(None)
    };
    let mesh = w.mesh("quads", &[coloured, uncoloured]);
    let node = w.node(Node {
        mesh: Some(mesh),
        ..Node::default()
    });
    w.scene(&[node]);
    w
}

#[test]
fn gltf_colours_load_as_linear_rgba_with_white_where_a_primitive_has_none() {
    let path = write("bytes", &two_primitive_file().glb());
    let scene = load_gltf_scene(&path).unwrap();
    let mesh = &scene.meshes[0].mesh;
    assert_eq!(mesh.colors.len(), 8, "every vertex of both primitives");
    let close = |got: [f32; 4], want: [f32; 4]| (0..4).all(|k| (got[k] - want[k]).abs() < 1e-6);
    let want = [
        [1.0, 0.0, 0.0, 1.0],
        [0.0, 1.0, 0.0, 128.0 / 255.0],
        [0.0, 0.0, 1.0, 0.0],
        [1.0; 4],
        [1.0; 4],
        [1.0; 4],
        [1.0; 4],
        [1.0; 4],
    ];
    for (k, (&got, want)) in mesh.colors.iter().zip(want).enumerate() {
        assert!(close(got, want), "vertex {k}: {got:?}, wanted {want:?}");
    }
    // Baked, the asset keeps them (its round trip is checked in `asset.rs`).
    let built = meshlight_scene::build_asset(
        &scene.meshes[0].mesh,
        &meshlight_scene::BuildOptions::default(),
        &mut |_| {},
    )
    .unwrap();
    assert!(built.asset.header().has_colors());
}

#[test]
fn float_rgb_colours_take_alpha_one_and_are_clamped() {
    let mut w = GltfWriter::new();
    let mesh = w.mesh(
        "quad",
        &[quad(Some(Colors::RgbFloat(vec![
            [0.25, 0.5, 0.75],
            [1.5, -0.5, 0.0],
            [0.0, 0.0, 0.0],
            [1.0, 1.0, 1.0],
        ])))],
    );
    let node = w.node(Node {
        mesh: Some(mesh),
        ..Node::default()
    });
    w.scene(&[node]);
    let scene = load_gltf_scene(&write("floats", &w.glb())).unwrap();
    let colors = &scene.meshes[0].mesh.colors;
    assert_eq!(colors[0], [0.25, 0.5, 0.75, 1.0]);
    assert_eq!(colors[1], [1.0, 0.0, 0.0, 1.0], "clamped to 0..1");
}

/// `w`'s document with `edit` applied to its first primitive's `COLOR_0` accessor.
fn with_color_accessor(w: &GltfWriter, edit: impl Fn(&mut Value)) -> Vec<u8> {
    let mut doc = w.json();
    let a = doc["meshes"][0]["primitives"][0]["attributes"]["COLOR_0"]
        .as_u64()
        .unwrap() as usize;
    edit(&mut doc["accessors"][a]);
    let bin = w.glb();
    // The writer's GLB holds its buffer after the JSON chunk: take it back out.
    let json_len = u32::from_le_bytes(bin[12..16].try_into().unwrap()) as usize;
    let bin_chunk = &bin[20 + json_len + 8..];
    meshlight_testing::gltf_writer::glb_container(&doc.to_string(), bin_chunk)
}

#[test]
fn damaged_colour_accessors_are_refused_naming_colour_0() {
    let w = two_primitive_file();
    for (name, edit, needles) in [
        (
            "vec2",
            Box::new(|a: &mut Value| a["type"] = json!("VEC2")) as Box<dyn Fn(&mut Value)>,
            &["COLOR_0", "Vec2"][..],
        ),
        (
            "not-normalized",
            Box::new(|a: &mut Value| a["normalized"] = json!(false)),
            &["COLOR_0", "normalized"][..],
        ),
        (
            "count",
            Box::new(|a: &mut Value| a["count"] = json!(3)),
            &["COLOR_0 has 3 elements, POSITION 4"][..],
        ),
    ] {
        let path = write(name, &with_color_accessor(&w, edit));
        let e = load_gltf_scene(&path)
            .err()
            .unwrap_or_else(|| panic!("{name}: a damaged colour accessor loaded"))
            .to_string();
        for needle in needles {
            assert!(e.contains(needle), "{name}: {e:?} does not say {needle:?}");
        }
    }
}

#[test]
fn obj_vertex_colours_are_read_as_srgb() {
    let obj = "v 0 0 0 1 0 0\nv 1 0 0 0 0.5 0\nv 0 1 0 0 0 1\nf 1 2 3\n";
    let mesh = parse_obj(std::path::Path::new("coloured.obj"), obj.as_bytes()).unwrap();
    assert_eq!(mesh.colors.len(), 3);
    assert_eq!(mesh.colors[0], [1.0, 0.0, 0.0, 1.0]);
    let half = meshlight_scene::texture::srgb_to_linear(0.5);
    assert!((half - 0.214).abs() < 1e-3, "{half}");
    assert_eq!(mesh.colors[1], [0.0, half, 0.0, 1.0]);
    // Without colours on every vertex line, none.
    let plain = "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";
    let mesh = parse_obj(std::path::Path::new("plain.obj"), plain.as_bytes()).unwrap();
    assert!(mesh.colors.is_empty());
    // Through the file loader too.
    let dir = common::scratch("vertex-colors-obj");
    let path = dir.join("coloured.obj");
    std::fs::write(&path, obj).unwrap();
    assert_eq!(load_mesh(&path).unwrap().colors.len(), 3);
}
