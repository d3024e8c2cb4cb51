//! Prints the DAG shape of each mesh given (or of the project's test meshes): triangles
//! per level and their ratio to the level before, levels against ⌈log2(LOD-0 meshlets)⌉,
//! roots, all levels against LOD 0, and the build time.
//!
//! `cargo run --release -p meshlight-scene --example dag_report -- [MESH...]`

use std::path::PathBuf;
use std::time::Instant;

use meshlight_scene::simplify::Mode;
use meshlight_scene::verify::{level_stats, quality};
use meshlight_scene::{BuildOptions, build_asset, load::load_mesh, procedural_mesh};

fn main() {
    let mut paths: Vec<PathBuf> = std::env::args().skip(1).map(PathBuf::from).collect();
    if paths.is_empty() {
        let dir = PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/../assets/meshes"));
        let mut found: Vec<PathBuf> = std::fs::read_dir(&dir)
            .expect("assets/meshes")
            .filter_map(|e| e.ok().map(|e| e.path()))
            .filter(|p| p.extension().is_some_and(|e| e == "obj"))
            .collect();
        found.sort();
        paths = found;
        paths.push(PathBuf::from("procedural"));
    }
    for path in paths {
        let mesh = if path.as_os_str() == "procedural" {
            procedural_mesh(meshlight_scene::DEFAULT_SEGMENTS)
        } else {
            match load_mesh(&path) {
                Ok(m) => m,
                Err(e) => {
                    println!("{e}");
                    continue;
                }
            }
        };
        let start = Instant::now();
        let built = match build_asset(&mesh, &BuildOptions::default(), &mut |_| {}) {
            Ok(b) => b,
            Err(e) => {
                println!("{e}");
                continue;
            }
        };
        let seconds = start.elapsed().as_secs_f64();
        let h = built.asset.header();
        let stats = level_stats(&built.asset);
        let ratios: Vec<String> = stats
            .windows(2)
            .map(|w| {
                format!(
                    "{:.2}",
                    w[1].triangles as f64 / w[0].triangles.max(1) as f64
                )
            })
            .collect();
        let q = quality(&built.asset);
        println!(
            "{}: {} tris, {} LOD-0 meshlets, {} levels (limit {}), {} roots, all levels {:.2}x LOD 0, worst ratio {:.2}, {:.3} s, {:.2} B/tri\n  ratios {}",
            path.display(),
            h.lod0_triangles,
            h.lod0_meshlets,
            h.level_count,
            q.level_limit,
            h.root_count,
            h.total_triangles as f64 / h.lod0_triangles as f64,
            q.worst_ratio,
            seconds,
            built.asset.bytes().len() as f64 / h.lod0_triangles as f64,
            ratios.join(" ")
        );
        let modes = Mode::ALL.map(|m| built.dag.groups.iter().filter(|g| g.mode == m).count());
        println!(
            "  groups: {} regular, {} permissive, {} welded, {} sloppy",
            modes[0], modes[1], modes[2], modes[3]
        );
        let b = built.asset.size_breakdown();
        let per = |bytes: usize| bytes as f64 / h.lod0_triangles as f64;
        println!(
            "  B/tri: records {:.2} groups {:.2} positions {:.2} normals {:.2} uvs {:.2} indices {:.2}; grid {} bits; {:.2} vertices/tri",
            per(b.meshlet_records),
            per(b.groups),
            per(b.positions),
            per(b.normals),
            per(b.uvs),
            per(b.indices),
            h.quant_bits,
            h.total_vertices as f64 / h.total_triangles as f64
        );
        for w in &q.warnings {
            println!("  warning: {w}");
        }
    }
}
