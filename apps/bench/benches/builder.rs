//! Build throughput and asset load speed. Prints a comparison table against
//! meshoptimizer's `clod_build` first (best of 3 per scenario), then lets criterion time
//! the builds and the load.

use std::path::PathBuf;

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use meshlight::scene::load::load_mesh;
use meshlight::scene::{
    BuildOptions, DEFAULT_SEGMENTS, Mesh, MeshletAsset, build_asset, procedural_mesh,
};
use meshlight_bench::builder::{builder_scenario, format_table};

fn meshes() -> Vec<(String, Mesh)> {
    let mut out = Vec::new();
    let bunny = PathBuf::from(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../assets/meshes/stanford-bunny.obj"
    ));
    let mesh = load_mesh(&bunny).expect("the bunny is part of the repository");
    out.push(("bunny".to_owned(), mesh));
    out.push((
        "procedural 1M".to_owned(),
        procedural_mesh(DEFAULT_SEGMENTS),
    ));
    out
}

fn bench(c: &mut Criterion) {
    let meshes = meshes();
    let scratch = std::env::temp_dir();
    let rows: Vec<_> = meshes
        .iter()
        .map(|(name, mesh)| builder_scenario(name, mesh, 3, &scratch).unwrap())
        .collect();
    eprintln!("\n{}", format_table(&rows));

    let mut group = c.benchmark_group("build");
    group.sample_size(10);
    for (name, mesh) in &meshes {
        group.throughput(Throughput::Elements(mesh.triangle_count() as u64));
        group.bench_function(name, |b| {
            b.iter(|| build_asset(mesh, &BuildOptions::default(), &mut |_| {}).unwrap())
        });
    }
    group.finish();

    let (_, mesh) = meshes.last().unwrap();
    let asset = build_asset(mesh, &BuildOptions::default(), &mut |_| {})
        .unwrap()
        .asset;
    let path = scratch.join("meshlight-bench-load.mlasset");
    asset.save(&path).unwrap();
    let mut group = c.benchmark_group("load");
    group.throughput(Throughput::Bytes(asset.bytes().len() as u64));
    group.bench_function("procedural 1M from page cache", |b| {
        b.iter(|| MeshletAsset::load(&path).unwrap())
    });
    group.finish();
    let _ = std::fs::remove_file(&path);
}

criterion_group!(benches, bench);
criterion_main!(benches);
