//! `meshlight bake` / `meshlight inspect` through their library entry points (the
//! command line's parsing of their options is tested with the command).

mod common;

use meshlight_scene::bake::{BakeOptions, run_bake, run_inspect};
use meshlight_scene::{Grouping, MeshletAsset, SceneError};

#[test]
fn bake_then_inspect_the_procedural_mesh() {
    let dir = common::scratch("cli");
    let out = dir.join("knot.mlasset");
    let options = BakeOptions {
        segments: 12,
        grouping: Grouping::Partition,
        position_bits: "14".parse().unwrap(),
        ..BakeOptions::new("procedural", &out)
    };
    run_bake(&options).unwrap();
    let asset = MeshletAsset::load(&out).unwrap();
    assert_eq!(asset.header().quant_bits, 14);
    assert_eq!(asset.header().lod0_triangles, 16 * 12 * 12);
    run_inspect(&out).unwrap();

    let mut bytes = std::fs::read(&out).unwrap();
    bytes.truncate(bytes.len() / 2);
    std::fs::write(&out, bytes).unwrap();
    let err = run_inspect(&out).unwrap_err();
    assert!(matches!(err, SceneError::AssetTruncated { .. }), "{err:?}");
}

#[test]
fn bake_summary_reports_levels_fill_and_size() {
    let path = common::shared_mesh("spot.obj");
    let mesh = meshlight_scene::load::load_mesh(&path).unwrap();
    let built = meshlight_scene::build_asset(&mesh, &Default::default(), &mut |_| {}).unwrap();
    let text = meshlight_scene::bake::bake_summary(&path, "spot.mlasset".as_ref(), &built, 0.0);
    for needle in [
        "level  meshlets  triangles",
        "levels:",
        "root:",
        "meshlet fill",
        "bytes per LOD-0 triangle",
        "build time",
        "input triangles/s",
    ] {
        assert!(text.contains(needle), "missing {needle:?} in\n{text}");
    }
}

/// A valid but poor DAG (every meshlet a root) passes `inspect` with warnings, exit 0;
/// `bake` refuses to write what its own checks reject.
#[test]
fn inspect_warns_on_poor_dags_and_fails_only_on_broken_ones() {
    let built = meshlight_scene::build_asset(
        &meshlight_scene::procedural_mesh(12),
        &Default::default(),
        &mut |_| {},
    )
    .unwrap();
    let mut dag = built.dag.clone();
    dag.groups.clear();
    for c in &mut dag.clusters {
        c.parent_group = meshlight_scene::dag::NO_GROUP;
        c.source_group = meshlight_scene::dag::NO_GROUP;
        c.level = 0;
    }
    dag.level_count = 1;
    let poor = MeshletAsset::from_dag(&built.mesh, &dag, 16, 0);
    let q = meshlight_scene::verify::quality(&poor);
    assert!(
        q.warnings.iter().any(|w| w.contains("root meshlets")),
        "{q:?}"
    );
    let dir = common::scratch("cli-poor");
    let path = dir.join("poor.mlasset");
    poor.save(&path).unwrap();
    run_inspect(&path).unwrap();

    // Broken: a group error below its children's. Not loadable by inspect's rules.
    let broken = meshlight_scene::damaged::error_below_child(&built).unwrap();
    let path = dir.join("broken.mlasset");
    broken.save(&path).unwrap();
    let err = run_inspect(&path).unwrap_err();
    assert!(matches!(err, SceneError::AssetCorrupt { .. }), "{err:?}");
}
