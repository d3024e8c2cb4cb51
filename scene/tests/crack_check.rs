//! The crack check as loading runs it (boundary fingerprints for every group, edge by
//! edge only where a group's boundary changed) against the exhaustive one (every edge of
//! every group hashed): the same findings, in the same order, on closed, open and
//! non-manifold meshes, intact and with simplified meshlets damaged in several ways.

mod common;

use common::generators::{finned_sphere, in_memory};
use meshlight_scene::dag::Dag;
use meshlight_scene::watertight::{crack_problems, exhaustive_crack_problems};
use meshlight_scene::{BuildOptions, Built, Mesh, MeshletAsset, Terrain, build_asset};

fn build(mesh: &Mesh) -> Built {
    build_asset(mesh, &BuildOptions::default(), &mut |_| {}).unwrap()
}

/// A closed mesh, an open one and a non-manifold one.
fn meshes() -> Vec<(&'static str, Mesh)> {
    let terrain = Terrain {
        origin: glam::Vec2::new(-10.0, -10.0),
        size: 20.0,
        cells: 64,
        amplitude: 2.0,
        wavelength: 8.0,
        octaves: 3,
        seed: 5,
        uv_scale: 0.25,
        calm_centre: glam::Vec2::ZERO,
        calm_radius: 0.0,
    };
    vec![
        ("procedural", meshlight_scene::procedural_mesh(24)),
        ("terrain", terrain.mesh().unwrap()),
        (
            "finned sphere",
            in_memory("finned sphere", finned_sphere(48, 64, 7)),
        ),
    ]
}

fn rebuild(built: &Built, dag: &Dag) -> MeshletAsset {
    MeshletAsset::from_dag_on_grid(
        &built.mesh,
        dag,
        built.asset.quantization(),
        Default::default(),
    )
}

fn agree(what: &str, asset: &MeshletAsset) -> Vec<String> {
    let exhaustive = exhaustive_crack_problems(asset);
    // The fingerprints' keys are drawn anew for each check: try a few.
    for _ in 0..3 {
        assert_eq!(crack_problems(asset), exhaustive, "{what}");
    }
    exhaustive
}

#[test]
fn intact_assets_have_no_cracks_either_way() {
    for (name, mesh) in meshes() {
        let built = build(&mesh);
        assert!(agree(name, &built.asset).is_empty(), "{name}");
    }
}

/// Deterministic picks: every `step`-th simplified meshlet from `start`.
fn simplified(dag: &Dag, start: usize, step: usize) -> Vec<usize> {
    (0..dag.clusters.len())
        .filter(|&c| dag.clusters[c].level > 0 && dag.clusters[c].indices.len() > 3)
        .skip(start)
        .step_by(step)
        .collect()
}

#[test]
fn damaged_simplified_meshlets_give_the_same_findings() {
    type Damage = fn(&mut Vec<u32>);
    let damages: [(&str, Damage); 4] = [
        ("last triangle dropped", |t| {
            t.truncate(t.len() - 3);
        }),
        ("winding reversed", |t| {
            for tri in t.chunks_exact_mut(3) {
                tri.swap(1, 2);
            }
        }),
        ("first triangle's corner moved to another vertex", |t| {
            t[0] = t[t.len() - 1];
        }),
        ("triangles shifted by a corner", |t| t.rotate_left(1)),
    ];
    for (name, mesh) in meshes() {
        let built = build(&mesh);
        let mut found = 0;
        for (what, damage) in damages {
            for start in [0, 3] {
                let mut dag = built.dag.clone();
                for c in simplified(&dag, start, 7) {
                    damage(&mut dag.clusters[c].indices);
                }
                let problems = agree(&format!("{name}, {what}"), &rebuild(&built, &dag));
                found += problems.len();
            }
        }
        assert!(found > 0, "{name}: no damage was a crack");
    }
}

/// One damaged meshlet at a time, so that a group with one changed edge is compared too.
#[test]
fn one_damaged_meshlet_gives_the_same_findings() {
    for (name, mesh) in meshes() {
        let built = build(&mesh);
        for c in simplified(&built.dag, 1, 13).into_iter().take(8) {
            let mut dag = built.dag.clone();
            let t = &mut dag.clusters[c].indices;
            t.truncate(t.len() - 3);
            agree(&format!("{name}, meshlet {c}"), &rebuild(&built, &dag));
        }
    }
}
