//! An OBJ file's `.mtl`: `Kd` and `map_Kd` per `usemtl`, slots in order of first use,
//! and every way the material file or its texture can be unusable reported as a warning
//! naming the file, with the geometry still drawn.

use meshlight_scene::load::{load_obj, load_obj_scene, names_material_library};
use meshlight_testing::gltf_writer::png_bytes;
use std::path::{Path, PathBuf};

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("meshlight-obj-mtl-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// Two quads, the first in `usemtl first`, the second in `usemtl second`.
const TWO_QUADS: &str = "mtllib quads.mtl
v 0 0 0
v 1 0 0
v 1 1 0
v 0 1 0
v 2 0 0
v 3 0 0
v 3 1 0
v 2 1 0
vt 0 0
vt 1 0
vt 1 1
vt 0 1
usemtl second
f 5/1 6/2 7/3 8/4
usemtl first
f 1/1 2/2 3/3 4/4
";

/// A 2 × 2 texture whose top row is red and bottom row blue.
fn two_rows() -> Vec<u8> {
    let (red, blue) = ([255, 0, 0, 255], [0, 0, 255, 255]);
    png_bytes(2, 2, &[red, red, blue, blue].concat())
}

/// A file of a case: its name and bytes.
type File<'a> = (&'a str, &'a [u8]);

fn write(dir: &Path, files: &[File]) -> PathBuf {
    for (name, bytes) in files {
        std::fs::write(dir.join(name), bytes).unwrap();
    }
    dir.join("quads.obj")
}

#[test]
fn usemtl_gives_slots_in_order_of_first_use_with_their_colours_and_textures() {
    let dir = scratch("two");
    let mtl = "newmtl first\nKd 0.2 0.4 0.6\nmap_Kd rows.png\nnewmtl second\nKd 0.9 0.1 0.1\n";
    let path = write(
        &dir,
        &[
            ("quads.obj", TWO_QUADS.as_bytes()),
            ("quads.mtl", mtl.as_bytes()),
            ("rows.png", &two_rows()),
        ],
    );
    let scene = load_obj_scene(&path).unwrap();
    assert!(scene.warnings.is_empty(), "{:?}", scene.warnings);
    let names: Vec<&str> = scene.materials.iter().map(|m| m.name.as_str()).collect();
    assert_eq!(names, ["second", "first"], "in order of first use");
    assert_eq!(scene.mesh.materials, [0, 0, 1, 1]);
    assert_eq!(scene.materials[0].diffuse, [0.9, 0.1, 0.1]);
    assert!(scene.materials[0].diffuse_texture.is_none());
    assert_eq!(scene.materials[1].diffuse, [0.2, 0.4, 0.6]);
    // Flipped: OBJ's V runs up the image, so the bottom row (blue) comes first.
    let texture = scene.materials[1].diffuse_texture.as_ref().unwrap();
    assert_eq!(texture.texel(0, 0), [0, 0, 255, 255]);
    assert_eq!(texture.texel(1, 1), [255, 0, 0, 255]);
    // The geometry-only loader sees the same triangles, in one slot.
    let plain = load_obj(&path).unwrap();
    assert_eq!(plain.positions, scene.mesh.positions);
    assert_eq!(plain.indices, scene.mesh.indices);
    assert!(plain.materials.is_empty());
    assert!(names_material_library(TWO_QUADS.as_bytes()));
    assert!(!names_material_library(
        b"v 0 0 0\n# mtllib in a comment\nusemtl x\n"
    ));
}

#[test]
fn an_unusable_material_file_or_texture_is_a_warning_naming_it() {
    let cases: [(&str, &[File], &str); 5] = [
        ("no-mtl", &[], "quads.mtl"),
        (
            "missing-texture",
            &[("quads.mtl", b"newmtl first\nmap_Kd gone.png\n")],
            "gone.png",
        ),
        (
            "outside",
            &[("quads.mtl", b"newmtl first\nmap_Kd ../outside.png\n")],
            "leaves the model's folder",
        ),
        (
            "corrupt",
            &[
                ("quads.mtl", b"newmtl first\nmap_Kd bad.png\n"),
                ("bad.png", b"\x89PNG\r\n\x1a\nnot really"),
            ],
            "bad.png",
        ),
        (
            "not-an-image",
            &[
                ("quads.mtl", b"newmtl first\nmap_Kd notes.png\n"),
                ("notes.png", b"just some text"),
            ],
            "not PNG or JPEG",
        ),
    ];
    for (name, files, says) in cases {
        let dir = scratch(name);
        let mut all: Vec<File> = vec![("quads.obj", TWO_QUADS.as_bytes())];
        all.extend_from_slice(files);
        let path = write(&dir, &all);
        let scene = load_obj_scene(&path).unwrap_or_else(|e| panic!("{name}: {e}"));
        let joined = scene.warnings.join("\n");
        assert!(joined.contains(says), "{name}: {joined}");
        assert!(
            joined.contains("quads.obj"),
            "{name}: names the model: {joined}"
        );
        assert_eq!(
            scene.mesh.triangle_count(),
            4,
            "{name}: the geometry is kept"
        );
        assert!(
            scene.materials.iter().all(|m| m.diffuse_texture.is_none()),
            "{name}"
        );
    }
}
