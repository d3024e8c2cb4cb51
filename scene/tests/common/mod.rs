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
        panic!("{} is missing; CI must provide the shared test meshes", dir.display());
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
