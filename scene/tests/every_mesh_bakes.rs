//! Ordinary meshes the builder once refused ("a crack in some LOD cut … please report
//! this"), each generated the way exporters write it and baked through the loaders: it
//! must bake, load back through every check `inspect` runs, and meet the DAG invariants
//! and quality targets.

mod common;

use std::path::{Path, PathBuf};

use common::dag_checks::{check, check_structure};
use common::generators::{
    ScanFlaws, Sphere, finned_sphere, glb, in_memory, scan_figure, soup_stl, spheres_obj,
};
use meshlight_scene::bake::{BakeOptions, bake};
use meshlight_scene::inspect::inspect;
use meshlight_scene::load::load_mesh;
use meshlight_scene::{BuildOptions, Built, Grouping, Mesh, build_asset, procedural_mesh};

const GROUPINGS: [Grouping; 2] = [Grouping::Partition, Grouping::Metis];

fn write(dir: &Path, name: &str, bytes: &[u8]) -> PathBuf {
    let path = dir.join(name);
    std::fs::write(&path, bytes).unwrap();
    path
}

fn build(mesh: &Mesh, grouping: Grouping) -> Built {
    let options = BuildOptions {
        grouping,
        ..BuildOptions::default()
    };
    build_asset(mesh, &options, &mut |_| {}).unwrap_or_else(|e| panic!("{}: {e}", mesh.source))
}

/// Bakes `path` with both groupings through `meshlight bake`, inspects the result, and
/// checks the DAG of an in-memory build of the same file.
fn bakes(dir: &Path, path: &Path) {
    let name = path.file_name().unwrap().to_string_lossy().into_owned();
    let mesh = load_mesh(path).unwrap_or_else(|e| panic!("{name}: {e}"));
    for grouping in GROUPINGS {
        let output = dir.join(format!("{name}.{grouping:?}.mlasset"));
        let args = BakeOptions {
            grouping,
            segments: 8,
            ..BakeOptions::new(path, &output)
        };
        bake(&args, &mut |_| {}).unwrap_or_else(|e| panic!("{name} ({grouping:?}): {e}"));
        inspect(&output)
            .and_then(|report| report.verdict())
            .unwrap_or_else(|e| panic!("{name}: {e}"));
        check(&format!("{name} ({grouping:?})"), &build(&mesh, grouping));
    }
}

/// Every 48 × 32 and larger sphere written at full precision was refused.
#[test]
fn full_precision_spheres() {
    let dir = common::scratch("full-precision-spheres");
    for (rings, segments) in [(16, 24), (32, 48), (64, 96), (128, 160)] {
        let path = write(
            &dir,
            &format!("sphere-{segments}x{rings}.obj"),
            Sphere::unit(rings, segments).obj().as_bytes(),
        );
        bakes(&dir, &path);
    }
}

#[test]
fn tiny_and_huge_meshes() {
    let dir = common::scratch("tiny-and-huge");
    for scale in [1e-10, 1e10] {
        let sphere = Sphere {
            radius: scale,
            ..Sphere::unit(32, 48)
        };
        bakes(
            &dir,
            &write(
                &dir,
                &format!("sphere-{scale:e}.obj"),
                sphere.obj().as_bytes(),
            ),
        );
    }
    for scale in [1e-10f32, 1e10] {
        let mut mesh = procedural_mesh(24);
        mesh.source = format!("procedural × {scale:e}");
        for p in &mut mesh.positions {
            *p *= scale;
        }
        for grouping in GROUPINGS {
            check(
                &format!("{} ({grouping:?})", mesh.source),
                &build(&mesh, grouping),
            );
        }
    }
}

/// The builder works at unit scale: a sphere scaled by a power of two (every coordinate
/// scaled exactly) gives the unit sphere's DAG, group for group, with every error scaled
/// alike; one written at radius 1e-10 or 1e10 (its coordinates rounded differently, which
/// moves some partitions and collapses) the same levels and roots, each level within 2%
/// of the unit sphere's triangles, and its largest error within a quarter, scaled (it
/// was 1.86× at 1e-10 while areas and squared distances underflowed).
#[test]
fn scale_does_not_change_the_dag() {
    let dir = common::scratch("scale-free");
    let root_error = |b: &Built| b.dag.groups.iter().map(|g| g.lod.error).fold(0.0, f32::max);
    for grouping in GROUPINGS {
        let sphere = |radius: f64| {
            let sphere = Sphere {
                radius,
                ..Sphere::unit(32, 48)
            };
            let name = format!("sphere-{radius:e}.obj");
            load_mesh(&write(&dir, &name, sphere.obj().as_bytes())).unwrap()
        };
        let unit_mesh = sphere(1.0);
        let unit = build(&unit_mesh, grouping);
        for exponent in [-33, 33] {
            let factor = 2f32.powi(exponent);
            let mut mesh = unit_mesh.clone();
            for p in &mut mesh.positions {
                *p *= factor;
            }
            let scaled = build(&mesh, grouping);
            let groups = |b: &Built, factor: f32| -> Vec<_> {
                b.dag
                    .groups
                    .iter()
                    .map(|g| (g.level, g.children.clone(), g.lod.error / factor))
                    .collect()
            };
            assert_eq!(
                groups(&scaled, factor),
                groups(&unit, 1.0),
                "{grouping:?}: groups (level, children, error) at scale 2^{exponent}"
            );
        }
        for scale in [1e-10, 1e10] {
            let scaled = build(&sphere(scale), grouping);
            let (a, b) = (scaled.dag.level_stats(), unit.dag.level_stats());
            assert_eq!(a.len(), b.len(), "{grouping:?}: levels at scale {scale:e}");
            assert_eq!(
                scaled.dag.roots().count(),
                unit.dag.roots().count(),
                "{grouping:?}: roots at scale {scale:e}"
            );
            for (level, (a, b)) in a.iter().zip(&b).enumerate() {
                assert!(
                    a.0.abs_diff(b.0) as f64 <= 0.02 * b.0 as f64,
                    "{grouping:?}: level {level} holds {} triangles at scale {scale:e}, {} at 1",
                    a.0,
                    b.0
                );
            }
            let ratio = root_error(&scaled) as f64 / (root_error(&unit) as f64 * scale);
            assert!(
                (0.8..=1.25).contains(&ratio),
                "{grouping:?}: the largest error at scale {scale:e} is {ratio}× the unit \
                 sphere's, scaled"
            );
        }
    }
}

#[test]
fn identical_and_duplicated_faces() {
    let dir = common::scratch("identical-faces");
    let mut obj = String::from("v 0 0 0\nv 1 0 0\nv 0 1 0\n");
    for _ in 0..100_000 {
        obj += "f 1 2 3\n";
    }
    bakes(&dir, &write(&dir, "identical.obj", obj.as_bytes()));

    let mut mesh = procedural_mesh(24);
    mesh.source = "procedural, every face ×10".into();
    let once = mesh.indices.clone();
    mesh.indices = once.chunks_exact(3).flat_map(|t| t.repeat(10)).collect();
    for grouping in GROUPINGS {
        let built = build(&mesh, grouping);
        assert_eq!(
            built.mesh.indices.len(),
            once.len(),
            "the copies are dropped"
        );
        check(&format!("{} ({grouping:?})", mesh.source), &built);
    }
}

#[test]
fn unwelded_triangle_soup() {
    let dir = common::scratch("soup");
    let triangles = Sphere::unit(48, 64).triangles();
    bakes(&dir, &write(&dir, "soup.stl", &soup_stl(&triangles)));
}

#[test]
fn shells_far_apart_and_many_shells() {
    let dir = common::scratch("shells");
    let far = spheres_obj(&[
        Sphere::unit(32, 48),
        Sphere {
            centre: [1e4, 0.0, 0.0],
            ..Sphere::unit(32, 48)
        },
    ]);
    bakes(&dir, &write(&dir, "far.obj", far.as_bytes()));

    let many: Vec<Sphere> = (0..60u32)
        .map(|i| {
            let h = |k| common::generators::hash01(i, k) as f64;
            Sphere {
                rings: 8 + (h(4) * 8.0) as u32,
                segments: 12 + (h(5) * 12.0) as u32,
                radius: 0.05 + 0.2 * h(6),
                centre: [h(1) * 10.0, h(2) * 10.0, h(3) * 10.0],
            }
        })
        .collect();
    bakes(
        &dir,
        &write(&dir, "many.obj", spheres_obj(&many).as_bytes()),
    );
}

/// A raw scan of a figure written as STL: an irregular triangulation with noise, small
/// holes, floating specks and a few triangles wound the other way. One group's smallest
/// result moved a border its regular result kept; taking that group as stuck left a
/// level at 0.34× and the next at 0.95×.
#[test]
fn a_scanned_figure_with_holes_specks_and_flipped_triangles() {
    let dir = common::scratch("scanned-figure");
    let flaws = ScanFlaws {
        noise: 0.5,
        holes: 0.05,
        specks: 2000,
        flipped: 0.02,
    };
    let (p, i) = scan_figure(200, 400, flaws);
    let triangles: Vec<[[f32; 3]; 3]> = i
        .chunks_exact(3)
        .map(|t| [0, 1, 2].map(|k| p[t[k] as usize]))
        .collect();
    let path = write(&dir, "figure.stl", &soup_stl(&triangles));
    bakes(&dir, &path);
    let built = build(&load_mesh(&path).unwrap(), Grouping::default());
    assert_eq!(built.dag.fallbacks.unsimplified, 0);
}

/// Like a scanned statue: non-manifold edges (≥ 1%), open borders, and written as GLB.
#[test]
fn fins_with_non_manifold_edges_and_open_borders() {
    let dir = common::scratch("fins");
    let (positions, indices) = finned_sphere(96, 128, 40);
    let triangles = indices.len() / 3;
    let fins = positions.len() - (95 * 128 + 2);
    // Each fin makes one edge of the closed sphere's 3/2 × triangles non-manifold.
    let edges = (triangles - fins) * 3 / 2;
    assert!(fins * 100 >= edges, "{fins} fins for {edges} edges");
    bakes(&dir, &write(&dir, "fins.glb", &glb(&positions, &indices)));
}

/// Both repairs on one mesh: fins on every second edge make groups whose first result
/// cracks (simplified again with their border triangles locked) and, with METIS
/// grouping, one that cracks even then (kept unsimplified; its children are the cut
/// there). The repaired DAG meets every structural check (with half its triangles
/// finned, levels shrink to only 0.64×, short of the quality target). Should the builder stop needing the
/// second repair here, this test wants a mesh that still does.
#[test]
fn cracking_groups_are_repaired_locally() {
    let mesh = in_memory("fins on every second edge", finned_sphere(64, 96, 2));
    let built = build(&mesh, Grouping::Metis);
    check_structure("fins on every second edge (Metis)", &built);
    assert!(built.fallbacks.relocked > 0, "{:?}", built.fallbacks);
    assert!(built.fallbacks.unsimplified > 0, "{:?}", built.fallbacks);
    assert_eq!(built.fallback_groups as usize, built.fallbacks.unsimplified);
    assert_eq!(built.dag.fallbacks, built.fallbacks);
    // The count reaches the report `meshlight bake` prints.
    let report = meshlight_scene::bake::BakeReport::new(
        Path::new("fins.obj"),
        Path::new("fins.mlasset"),
        &built,
        Default::default(),
    );
    assert_eq!(report.fallbacks, built.fallbacks);
}

/// Positions the weld leaves apart but the position grid merges: without welding the
/// full-precision sphere's pole and seam copies meet only on the grid, so the mesh is
/// snapped to the grid and built again, and the asset has no crack.
#[test]
fn points_merged_by_the_grid_are_built_as_one() {
    let dir = common::scratch("snap");
    let path = write(&dir, "sphere.obj", Sphere::unit(32, 48).obj().as_bytes());
    let mesh = load_mesh(&path).unwrap();
    for grouping in GROUPINGS {
        let options = BuildOptions {
            grouping,
            weld_tolerance: 0.0,
            ..BuildOptions::default()
        };
        let built = build_asset(&mesh, &options, &mut |_| {}).unwrap();
        assert!(built.snapped_to_grid);
        assert_eq!(built.clean.welded_vertices, 0);
        check(&format!("unwelded sphere ({grouping:?})"), &built);
    }
    let welded = build(&mesh, Grouping::default());
    assert!(!welded.snapped_to_grid && welded.clean.welded_vertices > 0);
}

#[test]
fn weld_tolerance_outside_its_range_is_refused() {
    for bad in [-1e-6, 0.5, f32::NAN] {
        let options = BuildOptions {
            weld_tolerance: bad,
            ..BuildOptions::default()
        };
        let err = build_asset(&procedural_mesh(8), &options, &mut |_| {}).unwrap_err();
        assert!(err.to_string().contains("weld tolerance"), "{err}");
    }
}

/// Welding, duplicate dropping, snapping and the repairs are deterministic: the same
/// bytes on every run and with any thread count.
#[test]
fn repaired_builds_are_byte_identical_whatever_the_thread_count() {
    let fins = in_memory("fins", finned_sphere(64, 96, 2));
    let dir = common::scratch("deterministic");
    let sphere = load_mesh(&write(&dir, "s.obj", Sphere::unit(32, 48).obj().as_bytes())).unwrap();
    for mesh in [&fins, &sphere] {
        let bytes = |threads: usize| {
            rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap()
                .install(|| build(mesh, Grouping::Metis).asset.bytes().to_vec())
        };
        let one = bytes(1);
        assert_eq!(one, bytes(2), "{}", mesh.source);
        assert_eq!(one, bytes(2), "{}", mesh.source);
    }
}
