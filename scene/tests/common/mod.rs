//! Helpers shared by the integration tests.
#![allow(dead_code)]

pub mod dag_checks;
pub mod damage;
pub mod generators;
pub mod gltf;

use std::path::PathBuf;

/// The project's test meshes (`assets/meshes`, with their origin and licence in its
/// README). They are part of the repository, so a missing one is a broken checkout and
/// fails the test that needs it.
pub fn shared_meshes() -> PathBuf {
    let dir = PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/../assets/meshes"));
    assert!(
        dir.is_dir(),
        "{} is missing; the test meshes are part of the repository",
        dir.display()
    );
    dir
}

pub fn shared_mesh(name: &str) -> PathBuf {
    let path = shared_meshes().join(name);
    assert!(path.is_file(), "{} is missing", path.display());
    path
}

pub const SHARED_MESHES: [&str; 5] = [
    "stanford-bunny.obj",
    "beast.obj",
    "spot.obj",
    "fandisk.obj",
    "teapot.obj",
];

/// A fresh scratch folder for one test.
pub fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("meshlight-scene-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

pub fn base64(data: &[u8]) -> String {
    const A: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut out = String::new();
    for c in data.chunks(3) {
        let b = [c[0], *c.get(1).unwrap_or(&0), *c.get(2).unwrap_or(&0)];
        let n = (b[0] as u32) << 16 | (b[1] as u32) << 8 | b[2] as u32;
        for k in 0..4 {
            if k <= c.len() {
                out.push(A[(n >> (18 - 6 * k) & 63) as usize] as char);
            } else {
                out.push('=');
            }
        }
    }
    out
}

/// A closed tetrahedron as (positions, indices).
pub fn tetrahedron() -> (Vec<[f32; 3]>, Vec<u16>) {
    (
        vec![
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.0, 0.0, 1.0],
        ],
        vec![0, 2, 1, 0, 1, 3, 0, 3, 2, 1, 2, 3],
    )
}

/// `smooth` with every triangle given its own three vertices and its face normal: a
/// mesh whose every vertex lies on a normal seam.
pub fn faceted(smooth: &meshlight_scene::Mesh) -> meshlight_scene::Mesh {
    let mut faceted = meshlight_scene::Mesh {
        source: "faceted".into(),
        ..Default::default()
    };
    for t in smooth.indices.chunks_exact(3) {
        let [a, b, c] = [t[0], t[1], t[2]].map(|i| smooth.positions[i as usize]);
        let n = (b - a).cross(c - a).normalize_or_zero();
        let base = faceted.positions.len() as u32;
        faceted.positions.extend([a, b, c]);
        faceted.normals.extend([n; 3]);
        faceted.indices.extend([base, base + 1, base + 2]);
    }
    faceted
}
