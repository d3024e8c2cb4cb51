//! The builder scenario's table (our build against `clod_build` in the same run, bytes
//! per LOD-0 triangle, load speed) for the meshes given, or the bunny and the
//! procedural mesh: what `meshlight bench --scenario builder` prints, without building
//! the renderer.
//!
//! `cargo run --release -p meshlight-bench --example builder_table -- [--repeats N] [MESH...]`

use std::path::PathBuf;

use meshlight::scene::{DEFAULT_SEGMENTS, load::load_mesh, procedural_mesh};
use meshlight_bench::builder::{builder_scenario, format_table};

fn main() {
    let mut args: Vec<String> = std::env::args().skip(1).collect();
    let mut repeats = 5;
    if let Some(at) = args.iter().position(|a| a == "--repeats") {
        repeats = args[at + 1].parse().expect("--repeats N");
        args.drain(at..at + 2);
    }
    let mut meshes = Vec::new();
    let paths: Vec<PathBuf> = if args.is_empty() {
        vec![PathBuf::from(concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../../assets/meshes/stanford-bunny.obj"
        ))]
    } else {
        args.iter().map(PathBuf::from).collect()
    };
    for p in &paths {
        let name = p.file_stem().unwrap().to_string_lossy().into_owned();
        meshes.push((name, load_mesh(p).expect("mesh")));
    }
    if args.is_empty() {
        meshes.push(("procedural 1M".into(), procedural_mesh(DEFAULT_SEGMENTS)));
    }
    let scratch = std::env::temp_dir();
    let rows: Vec<_> = meshes
        .iter()
        .map(|(name, mesh)| builder_scenario(name, mesh, repeats, &scratch).expect("build"))
        .collect();
    print!("{}", format_table(&rows));
}
