//! The DAG checks every built mesh must pass: the structural invariants `verify`
//! checks, LOD 0 holding exactly the input triangles, and the quality targets.

use meshlight_scene::Built;
use meshlight_scene::dag::Dag;
use meshlight_scene::simplify::Mode;
use meshlight_scene::verify::{expected_levels, quality, verify};

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

/// Every structural invariant ([`check_structure`]) and the quality targets.
pub fn check(name: &str, built: &Built) {
    check_structure(name, built);
    check_quality(name, built);
}

/// The invariants that make a DAG draw correctly (those `verify` checks, crack-freedom
/// included), and LOD 0 holding exactly the input triangles.
pub fn check_structure(name: &str, built: &Built) {
    if let Err(e) = built.asset.validate() {
        panic!("{name}: {} {}", e.field, e.problem);
    }
    let problems = verify(&built.asset);
    assert!(problems.is_empty(), "{name}: {problems:#?}");
    assert_eq!(
        canonical(&lod0_indices(&built.dag)),
        canonical(&built.mesh.indices),
        "{name}: LOD-0 meshlets must hold exactly the input triangles"
    );
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
}

/// The quality targets: levels that halve, a shallow DAG, 1 to 3 roots.
pub fn check_quality(name: &str, built: &Built) {
    let h = built.asset.header();
    // The quality targets: every level ≤ 0.55× the one before (the last step to the
    // root aside), levels ≤ ⌈log2(LOD-0 meshlets)⌉ + 2, 1 to 3 roots, all levels
    // ≤ 2.1× LOD 0.
    assert!(
        (1..=3).contains(&h.root_count),
        "{name}: {} roots",
        h.root_count
    );
    let q = quality(&built.asset);
    assert!(q.warnings.is_empty(), "{name}: {:#?}", q.warnings);
    assert!(
        q.worst_ratio <= 0.55 && q.total_ratio <= 2.1,
        "{name}: {q:?}"
    );
    assert!(h.level_count <= q.level_limit, "{name}: {q:?}");
    let modes = Mode::ALL.map(|m| built.dag.groups.iter().filter(|g| g.mode == m).count());
    println!(
        "{name}: {} triangles, {} LOD-0 meshlets, {} levels (expected {:.1}, limit {}), \
         root {} meshlets, worst level ratio {:.2}, all levels {:.2}x LOD 0, groups \
         regular/permissive/welded/sloppy {modes:?}",
        h.lod0_triangles,
        h.lod0_meshlets,
        h.level_count,
        expected_levels(h.lod0_meshlets),
        q.level_limit,
        h.root_count,
        q.worst_ratio,
        q.total_ratio
    );
}
