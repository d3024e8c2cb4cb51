//! `meshlight bake DIR -o OUTDIR`: every mesh under a directory baked, the tree mirrored,
//! the same bytes whatever the number of jobs, up-to-date outputs skipped, refusals
//! reported per file.

mod common;

use common::{meshlight, scratch};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::Output;

/// Three of the project's meshes in a small tree, and a text file that is not a mesh.
fn library(dir: &Path) -> PathBuf {
    let lib = dir.join("lib");
    for (mesh, to) in [
        ("spot.obj", "characters/spot.obj"),
        ("teapot.obj", "props/kitchen/teapot.obj"),
        ("fandisk.obj", "props/fandisk.obj"),
    ] {
        let to = lib.join(to);
        std::fs::create_dir_all(to.parent().unwrap()).unwrap();
        std::fs::copy(
            Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/../.."))
                .join("assets/meshes")
                .join(mesh),
            to,
        )
        .unwrap();
    }
    std::fs::write(lib.join("props/README.txt"), "not a mesh").unwrap();
    lib
}

/// Every file under `dir` (relative path → bytes).
fn tree(dir: &Path) -> BTreeMap<PathBuf, Vec<u8>> {
    let mut files = BTreeMap::new();
    let mut pending = vec![dir.to_path_buf()];
    while let Some(d) = pending.pop() {
        for entry in std::fs::read_dir(&d).unwrap() {
            let path = entry.unwrap().path();
            if path.is_dir() {
                pending.push(path);
            } else {
                let bytes = std::fs::read(&path).unwrap();
                files.insert(path.strip_prefix(dir).unwrap().to_path_buf(), bytes);
            }
        }
    }
    files
}

fn bake(lib: &Path, out: &Path, extra: &[&str]) -> (Output, String) {
    let mut args = vec!["bake", lib.to_str().unwrap(), "-o", out.to_str().unwrap()];
    args.extend_from_slice(extra);
    let output = meshlight(&args);
    let stdout = String::from_utf8_lossy(&output.stdout).into_owned();
    (output, stdout)
}

/// The status column of the table's row for `file`.
fn status<'a>(table: &'a str, file: &str) -> &'a str {
    let row = table
        .lines()
        .find(|l| l.starts_with(file))
        .unwrap_or_else(|| panic!("no row for {file}:\n{table}"));
    let at = row.find(" s  ").expect("a time column") + 4;
    &row[at..]
}

#[test]
fn a_directory_bakes_to_the_same_bytes_with_one_and_two_jobs() {
    let dir = scratch("jobs");
    let lib = library(&dir);
    let (one, two) = (dir.join("one"), dir.join("two"));
    for (out, jobs) in [(&one, "1"), (&two, "2")] {
        let (o, table) = bake(&lib, out, &["--jobs", jobs]);
        assert!(
            o.status.success(),
            "{table}{}",
            String::from_utf8_lossy(&o.stderr)
        );
        for file in [
            "characters/spot.obj",
            "props/fandisk.obj",
            "props/kitchen/teapot.obj",
        ] {
            assert_eq!(status(&table, file), "baked", "{table}");
        }
        assert!(
            table.contains(&format!("with {jobs} job(s): 3 baked")),
            "{table}"
        );
    }
    let (a, b) = (tree(&one), tree(&two));
    let names: Vec<_> = a.keys().map(|p| p.to_str().unwrap()).collect();
    assert_eq!(
        names,
        [
            "characters/spot.mlasset",
            "characters/spot.mlasset.key",
            "props/fandisk.mlasset",
            "props/fandisk.mlasset.key",
            "props/kitchen/teapot.mlasset",
            "props/kitchen/teapot.mlasset.key",
        ]
    );
    assert!(a == b, "the outputs differ between 1 and 2 jobs");
    // Each is what a single-file bake writes, and inspect accepts it.
    let single = dir.join("single.mlasset");
    let o = meshlight(&[
        "bake",
        lib.join("props/fandisk.obj").to_str().unwrap(),
        "-o",
        single.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert_eq!(
        std::fs::read(&single).unwrap(),
        a[Path::new("props/fandisk.mlasset")]
    );
    let o = meshlight(&[
        "inspect",
        one.join("characters/spot.mlasset").to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stdout));
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn up_to_date_outputs_are_skipped_and_changed_or_damaged_ones_baked_again() {
    let dir = scratch("up-to-date");
    let lib = library(&dir);
    let out = dir.join("out");
    let (o, table) = bake(&lib, &out, &["--jobs", "2"]);
    assert!(o.status.success(), "{table}");
    let first = tree(&out);

    let (o, table) = bake(&lib, &out, &[]);
    assert!(o.status.success(), "{table}");
    assert!(table.contains("0 baked, 3 up to date"), "{table}");
    assert_eq!(tree(&out), first);

    // A changed input (its bytes, so its key) is baked again; the others are not.
    let teapot = lib.join("props/kitchen/teapot.obj");
    let mut text = std::fs::read_to_string(&teapot).unwrap();
    text.push_str("\n# touched\n");
    std::fs::write(&teapot, text).unwrap();
    // A damaged output is baked again, whatever its stamp says.
    let spot = out.join("characters/spot.mlasset");
    let mut bytes = std::fs::read(&spot).unwrap();
    let n = bytes.len();
    bytes[n / 2] ^= 0x40;
    std::fs::write(&spot, bytes).unwrap();
    let (o, table) = bake(&lib, &out, &[]);
    assert!(o.status.success(), "{table}");
    assert_eq!(
        status(&table, "props/kitchen/teapot.obj"),
        "baked",
        "{table}"
    );
    assert_eq!(status(&table, "characters/spot.obj"), "baked", "{table}");
    assert_eq!(status(&table, "props/fandisk.obj"), "up to date", "{table}");
    let again = tree(&out);
    assert_eq!(
        again[Path::new("characters/spot.mlasset")],
        first[Path::new("characters/spot.mlasset")],
        "the damaged output is restored"
    );
    assert_ne!(
        again[Path::new("props/kitchen/teapot.mlasset.key")],
        first[Path::new("props/kitchen/teapot.mlasset.key")],
        "the changed input has a new key"
    );

    // Other build options are another key: everything is baked again.
    let (o, table) = bake(&lib, &out, &["--grouping", "metis"]);
    assert!(o.status.success(), "{table}");
    assert!(table.contains("3 baked, 0 up to date"), "{table}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_refused_mesh_is_named_in_the_table_and_fails_the_command() {
    let dir = scratch("refused");
    let lib = library(&dir);
    std::fs::write(lib.join("props/broken.obj"), "v 0 0 0\nf 1 2 3\n").unwrap();
    let out = dir.join("out");
    let (o, table) = bake(&lib, &out, &[]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{table}{err}");
    assert!(err.contains("1 of 4 meshes were not baked"), "{err}");
    let row = status(&table, "props/broken.obj");
    assert!(
        row.starts_with("refused: ") && row.contains("broken.obj") && row.contains("line 2"),
        "{table}"
    );
    assert_eq!(status(&table, "characters/spot.obj"), "baked", "{table}");
    assert!(out.join("characters/spot.mlasset").is_file());
    assert!(!out.join("props/broken.mlasset").exists());
    assert!(!out.join("props/broken.mlasset.key").exists());
    // A directory with no meshes is an error, not an empty table.
    let empty = dir.join("empty");
    std::fs::create_dir_all(&empty).unwrap();
    let (o, _) = bake(&empty, &out, &[]);
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        !o.status.success() && err.contains("holds no mesh files"),
        "{err}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// A `.gltf` of a wavy `n × n` grid whose positions and indices are in `grid.bin` beside
/// it; `shift` moves an inner vertex along x (inside the bounds the `.gltf` declares),
/// so that only the `.bin` changes.
fn write_gltf_grid(dir: &Path, n: u32, shift: f32) {
    let mut bin: Vec<u8> = Vec::new();
    let (mut min, mut max) = ([f32::MAX; 3], [f32::MIN; 3]);
    for y in 0..n {
        for x in 0..n {
            let mut p = [x as f32, ((x * 7 + y * 3) % 5) as f32 * 0.1, y as f32];
            if (x, y) == (n / 2, n / 2) {
                p[0] += shift;
            }
            for k in 0..3 {
                min[k] = min[k].min(p[k]);
                max[k] = max[k].max(p[k]);
                bin.extend(p[k].to_le_bytes());
            }
        }
    }
    let positions = bin.len();
    let mut indices = 0;
    for y in 0..n - 1 {
        for x in 0..n - 1 {
            let i = y * n + x;
            for v in [i, i + n, i + 1, i + 1, i + n, i + n + 1] {
                bin.extend(v.to_le_bytes());
                indices += 1;
            }
        }
    }
    std::fs::write(dir.join("grid.bin"), &bin).unwrap();
    let gltf = format!(
        r#"{{"asset":{{"version":"2.0"}},"scene":0,"scenes":[{{"nodes":[0]}}],"nodes":[{{"mesh":0}}],
"meshes":[{{"primitives":[{{"attributes":{{"POSITION":0}},"indices":1}}]}}],
"buffers":[{{"uri":"grid.bin","byteLength":{len}}}],
"bufferViews":[{{"buffer":0,"byteOffset":0,"byteLength":{positions}}},{{"buffer":0,"byteOffset":{positions},"byteLength":{index_bytes}}}],
"accessors":[{{"bufferView":0,"componentType":5126,"count":{count},"type":"VEC3","min":{min:?},"max":{max:?}}},
{{"bufferView":1,"componentType":5125,"count":{indices},"type":"SCALAR"}}]}}"#,
        len = bin.len(),
        index_bytes = bin.len() - positions,
        count = n * n,
    );
    std::fs::write(dir.join("grid.gltf"), gltf).unwrap();
}

/// A `.gltf` is up to date only while the buffer file it names is unchanged too.
#[test]
fn a_gltf_is_baked_again_when_only_its_buffer_file_changed() {
    let dir = scratch("gltf");
    let lib = dir.join("lib");
    std::fs::create_dir_all(&lib).unwrap();
    write_gltf_grid(&lib, 24, 0.0);
    let out = dir.join("out");
    let (o, table) = bake(&lib, &out, &[]);
    assert!(
        o.status.success(),
        "{table}{}",
        String::from_utf8_lossy(&o.stderr)
    );
    assert_eq!(status(&table, "grid.gltf"), "baked", "{table}");
    let first = std::fs::read(out.join("grid.mlasset")).unwrap();
    let (_, table) = bake(&lib, &out, &[]);
    assert_eq!(status(&table, "grid.gltf"), "up to date", "{table}");
    let gltf_before = std::fs::read(lib.join("grid.gltf")).unwrap();
    write_gltf_grid(&lib, 24, 0.4);
    assert_eq!(std::fs::read(lib.join("grid.gltf")).unwrap(), gltf_before);
    let (o, table) = bake(&lib, &out, &[]);
    assert!(o.status.success(), "{table}");
    assert_eq!(status(&table, "grid.gltf"), "baked", "{table}");
    assert_ne!(std::fs::read(out.join("grid.mlasset")).unwrap(), first);
    let _ = std::fs::remove_dir_all(&dir);
}
