//! The DAG invariants on every shared test mesh and on the procedural mesh.

mod common;

use meshlight_scene::dag::Dag;
use meshlight_scene::verify::{expected_levels, verify};
use meshlight_scene::{
    BuildOptions, Built, Grouping, Mesh, build_asset, load::load_mesh, procedural_mesh,
};

fn build(mesh: &Mesh, grouping: Grouping) -> Built {
    let options = BuildOptions {
        grouping,
        ..BuildOptions::default()
    };
    build_asset(mesh, &options, &mut |_| {}).unwrap()
}

/// Triangles as sorted-rotation triples, so that reordering inside meshlets is allowed
/// but any lost, duplicated or re-wound triangle is not.
fn canonical(indices: &[u32]) -> Vec<[u32; 3]> {
    let mut tris: Vec<[u32; 3]> = indices
        .chunks_exact(3)
        .map(|t| {
            let r = (0..3).min_by_key(|&k| t[k]).unwrap();
            [t[r], t[(r + 1) % 3], t[(r + 2) % 3]]
        })
        .collect();
    tris.sort_unstable();
    tris
}

fn lod0_indices(dag: &Dag) -> Vec<u32> {
    dag.clusters
        .iter()
        .filter(|c| c.level == 0)
        .flat_map(|c| c.indices.iter().copied())
        .collect()
}

fn check(name: &str, built: &Built) {
    let problems = verify(&built.asset);
    assert!(problems.is_empty(), "{name}: {problems:#?}");
    assert_eq!(
        canonical(&lod0_indices(&built.dag)),
        canonical(&built.mesh.indices),
        "{name}: LOD-0 meshlets must hold exactly the input triangles"
    );
    let h = built.asset.header();
    for c in &built.dag.clusters {
        assert!(
            c.triangle_count() <= 128 && c.triangle_count() > 0,
            "{name}: meshlet of {} triangles",
            c.triangle_count()
        );
    }
    // Directly, not only through verify(): the DAG itself satisfies the group rules.
    for g in &built.dag.groups {
        for &c in &g.children {
            let child = &built.dag.clusters[c as usize];
            assert!(
                g.lod.error >= child.lod.error,
                "{name}: group error below a child's"
            );
            assert!(
                meshlight_scene::bounds::contains(
                    (g.lod.center, g.lod.radius),
                    (child.lod.center, child.lod.radius)
                ),
                "{name}: group sphere does not contain a child's"
            );
        }
    }
    assert!(
        (1..=3).contains(&h.root_count),
        "{name}: {} roots",
        h.root_count
    );
    let expected = expected_levels(h.lod0_meshlets);
    assert!(
        (h.level_count as f32 - expected).abs() <= 2.0,
        "{name}: {} levels, log2(LOD-0 meshlets) + 1 = {expected:.1}",
        h.level_count
    );
    println!(
        "{name}: {} triangles, {} LOD-0 meshlets, {} levels, root {} meshlets",
        h.lod0_triangles, h.lod0_meshlets, h.level_count, h.root_count
    );
}

#[test]
fn invariants_hold_on_every_shared_mesh() {
    let Some(dir) = common::shared_meshes() else {
        return;
    };
    for name in common::SHARED_MESHES {
        let mesh = load_mesh(&dir.join(name)).unwrap();
        check(name, &build(&mesh, Grouping::Metis));
    }
}

#[test]
fn invariants_hold_with_meshopt_partitioning() {
    let Some(path) = common::shared_mesh("stanford-bunny.obj") else {
        return;
    };
    let mesh = load_mesh(&path).unwrap();
    let metis = build(&mesh, Grouping::Metis);
    let partition = build(&mesh, Grouping::Partition);
    check("bunny (partition_clusters)", &partition);
    assert_ne!(
        metis.dag.groups, partition.dag.groups,
        "the grouping option must change the groups"
    );
}

/// The full default mesh (1M triangles): the size the renderer starts with.
#[test]
fn invariants_hold_on_the_procedural_mesh() {
    let mesh = procedural_mesh(meshlight_scene::DEFAULT_SEGMENTS);
    assert!(mesh.triangle_count() >= 1_000_000);
    check("procedural", &build(&mesh, Grouping::Metis));
}

/// The checker finds broken DAGs: it is what `meshlight inspect` relies on.
#[test]
fn verify_reports_broken_invariants() {
    let mesh = procedural_mesh(16);
    let built = build(&mesh, Grouping::Metis);
    let rebuild = |dag: &Dag| meshlight_scene::MeshletAsset::from_dag(&built.mesh, dag, 16, 0);
    assert!(verify(&rebuild(&built.dag)).is_empty());

    let mut dag = built.dag.clone();
    let child = dag.groups[0].children[0] as usize;
    dag.clusters[child].lod.error = dag.groups[0].lod.error * 2.0 + 1.0;
    let problems = verify(&rebuild(&dag));
    assert!(
        problems.iter().any(|p| p.contains("below child")),
        "{problems:?}"
    );

    let mut dag = built.dag.clone();
    dag.groups[0].lod.radius *= 0.5;
    let problems = verify(&rebuild(&dag));
    assert!(
        problems.iter().any(|p| p.contains("does not contain")),
        "{problems:?}"
    );

    let mut dag = built.dag.clone();
    for c in &mut dag.clusters {
        c.parent_group = meshlight_scene::dag::NO_GROUP;
        c.parent = meshlight_scene::bounds::LodBounds::ROOT_PARENT;
    }
    let problems = verify(&rebuild(&dag));
    assert!(
        problems.iter().any(|p| p.contains("root meshlets")),
        "{problems:?}"
    );
}
