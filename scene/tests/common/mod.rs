//! Helpers shared by the integration tests.
#![allow(dead_code)]

use std::path::PathBuf;

/// The shared test meshes beside the project. Returns `None` (after saying why) when the
/// folder is absent on a developer's clone; under CI its absence fails the test.
pub fn shared_meshes() -> Option<PathBuf> {
    let dir = PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/../../shared/meshes"));
    if dir.is_dir() {
        return Some(dir);
    }
    if std::env::var("CI").is_ok_and(|v| v == "true") {
        panic!(
            "{} is missing; CI must provide the shared test meshes",
            dir.display()
        );
    }
    eprintln!(
        "did not run: the shared test meshes are not at {} (they live beside the project, not in it)",
        dir.display()
    );
    None
}

pub fn shared_mesh(name: &str) -> Option<PathBuf> {
    shared_meshes().map(|d| d.join(name))
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
