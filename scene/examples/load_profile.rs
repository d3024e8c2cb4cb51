//! Times each part of loading an asset from the page cache: the plain load (read,
//! checksum, structure), the DAG checks on top, and the verified load as a whole, best of
//! `--repeats` runs each. The asset is the procedural 1M-triangle mesh's, `--mesh`'s, or
//! an open height field's of `2 · CELLS²` triangles, baked once into the temporary folder
//! and reused while it still loads. `--exhaustive` also times the crack check without
//! fingerprints, hashing every edge.
//!
//! `cargo run --release -p meshlight-scene --example load_profile -- [--repeats N]
//! [--mesh PATH | --terrain CELLS] [--rebake] [--exhaustive]`

use std::path::Path;
use std::time::Instant;

use meshlight_scene::{BuildOptions, DEFAULT_SEGMENTS, MeshletAsset, build_asset, procedural_mesh};

fn best<T>(repeats: usize, mut f: impl FnMut() -> T) -> f64 {
    (0..repeats)
        .map(|_| {
            let start = Instant::now();
            std::hint::black_box(f());
            start.elapsed().as_secs_f64()
        })
        .fold(f64::INFINITY, f64::min)
}

fn terrain(cells: u32) -> meshlight_scene::Terrain {
    meshlight_scene::Terrain {
        origin: glam::Vec2::new(-50.0, -50.0),
        size: 100.0,
        cells,
        amplitude: 8.0,
        wavelength: 30.0,
        octaves: 5,
        seed: 3,
        uv_scale: 0.1,
        calm_centre: glam::Vec2::ZERO,
        calm_radius: 0.0,
    }
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let repeats = args
        .iter()
        .position(|a| a == "--repeats")
        .map(|at| args[at + 1].parse().expect("--repeats N"))
        .unwrap_or(20);
    let mesh_path = args
        .iter()
        .position(|a| a == "--mesh")
        .map(|at| std::path::PathBuf::from(&args[at + 1]));
    // An open mesh: a height field of `2 · cells²` triangles.
    let terrain_cells: Option<u32> = args
        .iter()
        .position(|a| a == "--terrain")
        .map(|at| args[at + 1].parse().expect("--terrain CELLS"));
    let name = match (&mesh_path, terrain_cells) {
        (Some(p), _) => p.file_stem().unwrap().to_string_lossy().into_owned(),
        (None, Some(cells)) => format!("terrain-{cells}"),
        (None, None) => "procedural".to_owned(),
    };
    let path = std::env::temp_dir().join(format!("meshlight-load-profile-{name}.mlasset"));
    if args.iter().any(|a| a == "--rebake") || MeshletAsset::load(&path).is_err() {
        let mesh = match (&mesh_path, terrain_cells) {
            (Some(p), _) => meshlight_scene::load::load_mesh(p).expect("mesh"),
            (None, Some(cells)) => terrain(cells).mesh().expect("terrain"),
            (None, None) => procedural_mesh(DEFAULT_SEGMENTS),
        };
        let built = build_asset(&mesh, &BuildOptions::default(), &mut |_| {}).expect("bake");
        built.asset.save(&path).expect("save");
    }
    let path: &Path = &path;
    let asset = MeshletAsset::load(path).expect("load");
    let bytes = asset.bytes().len() as f64;
    let h = asset.header();
    println!(
        "{} bytes, {} meshlets, {} groups, {} triangles, {} vertices",
        bytes, h.meshlet_count, h.group_count, h.total_triangles, h.total_vertices
    );
    let report = |name: &str, seconds: f64| {
        println!(
            "{name:<24} {:>9.3} ms  {:>8.2} GB/s",
            seconds * 1e3,
            bytes / seconds / 1e9
        )
    };
    let plain = best(repeats, || MeshletAsset::load(path).unwrap());
    report("load", plain);
    report("validate", best(repeats, || asset.validate().unwrap()));
    report(
        "verify (DAG checks)",
        best(repeats, || meshlight_scene::verify::verify(&asset)),
    );
    let keys = meshlight_scene::chain_fingerprint::ChainKeys::random();
    report(
        "scan",
        best(repeats, || {
            meshlight_scene::asset::scan::scan_meshlets(&asset, &keys)
        }),
    );
    let scans = meshlight_scene::asset::scan::scan_meshlets(&asset, &keys);
    if args.iter().any(|a| a == "--exhaustive") {
        report(
            "crack check, exhaustive",
            best(repeats.min(3), || {
                meshlight_scene::watertight::exhaustive_crack_problems(&asset)
            }),
        );
    }
    report(
        "crack check",
        best(repeats, || {
            meshlight_scene::watertight::crack_problems_scanned(&asset, &scans)
        }),
    );
    let verified = best(repeats, || MeshletAsset::load_verified(path).unwrap());
    report("load_verified", verified);
    println!("verified / plain: {:.2}x", verified / plain);
}
