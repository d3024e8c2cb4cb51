//! `meshlight bake` / `meshlight inspect` through their library entry points, which
//! return what the command prints as values (the command's parsing of their options and
//! its wording are tested with the command).

mod common;

use meshlight_scene::bake::{BakeOptions, BakeProgress, bake};
use meshlight_scene::inspect::inspect;
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
    let mut steps = Vec::new();
    let report = bake(&options, &mut |step| steps.push(step)).unwrap();
    let asset = MeshletAsset::load(&out).unwrap();
    assert_eq!(asset.header().quant_bits, 14);
    assert_eq!(asset.header().lod0_triangles, 16 * 12 * 12);
    assert_eq!(
        report.summary.header,
        *asset.header(),
        "the report is the file's"
    );
    assert_eq!(report.output, out);

    // Progress: the mesh's size first, then each level in turn, leaving no more
    // triangles to simplify than the one before.
    assert_eq!(
        steps.first(),
        Some(&BakeProgress::Loaded {
            triangles: 16 * 12 * 12
        })
    );
    let levels: Vec<_> = steps[1..]
        .iter()
        .map(|s| match s {
            BakeProgress::Level(p) => *p,
            other => panic!("a second {other:?}"),
        })
        .collect();
    assert!(levels.len() >= 2, "{steps:?}");
    assert!(
        levels
            .iter()
            .enumerate()
            .all(|(i, p)| p.level == i as u32 + 1),
        "{levels:?}"
    );
    assert!(levels[0].active_triangles < 16 * 12 * 12, "{levels:?}");
    assert!(
        levels
            .windows(2)
            .all(|w| w[1].active_triangles <= w[0].active_triangles),
        "{levels:?}"
    );

    let inspected = inspect(&out).unwrap();
    assert_eq!(inspected.summary, report.summary, "bake and inspect agree");
    assert!(inspected.problems.is_empty(), "{:?}", inspected.problems);
    inspected.verdict().unwrap();

    let mut bytes = std::fs::read(&out).unwrap();
    bytes.truncate(bytes.len() / 2);
    std::fs::write(&out, bytes).unwrap();
    let err = inspect(&out).unwrap_err();
    assert!(matches!(err, SceneError::AssetTruncated { .. }), "{err:?}");
}

/// The figures of the summary add up to what the header and the file say.
#[test]
fn the_asset_summary_adds_up() {
    let path = common::shared_mesh("spot.obj");
    let mesh = meshlight_scene::load::load_mesh(&path).unwrap();
    let built = meshlight_scene::build_asset(&mesh, &Default::default(), &mut |_| {}).unwrap();
    let s = meshlight_scene::asset::summary::AssetSummary::of(&built.asset);
    let h = built.asset.header();
    assert_eq!(s.levels.len(), h.level_count as usize);
    assert!(h.level_count > 2, "{h:?}");
    assert_eq!(s.levels[0].triangles, h.lod0_triangles as usize);
    assert_eq!(s.levels[0].meshlets, h.lod0_meshlets as usize);
    assert_eq!(
        s.levels.iter().map(|l| l.triangles).sum::<usize>(),
        h.total_triangles as usize
    );
    assert_eq!(s.levels[0].max_error, 0.0, "LOD 0 is the mesh itself");
    assert!(
        s.levels.windows(2).all(|w| w[0].max_error < w[1].max_error),
        "errors grow with the level: {:?}",
        s.levels
    );
    assert_eq!(s.root_meshlets, h.root_count as usize);
    assert_eq!(
        s.root_triangles as usize,
        s.levels.last().unwrap().triangles,
        "the roots are the last level here"
    );
    assert_eq!(s.hierarchy.leaves, h.group_count as usize + 1);
    assert_eq!(s.hierarchy.nodes, h.node_count as usize);
    assert!(s.hierarchy.depth >= 2, "{:?}", s.hierarchy);
    assert_eq!(s.bytes, built.asset.bytes().len());
    assert_eq!(s.size.total(), s.bytes);
    assert_eq!(s.checksum() & 0xffff_ffff, u64::from(h.checksum[0]));
    assert!(s.max_position_error > 0.0);
}

/// A valid but poor DAG (every meshlet a root) passes `inspect` with warnings;
/// a broken one is reported with its violations and fails.
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
    let poor = MeshletAsset::from_dag(&built.mesh, &dag, 16, Default::default());
    let dir = common::scratch("cli-poor");
    let path = dir.join("poor.mlasset");
    poor.save(&path).unwrap();
    let report = inspect(&path).unwrap();
    report.verdict().unwrap();
    assert!(report.problems.is_empty(), "{:?}", report.problems);
    assert!(
        report.warnings.iter().any(|w| w.contains("root meshlets")),
        "{report:?}"
    );

    // Broken: a group error below its children's. Not loadable by inspect's rules.
    let broken = meshlight_scene::damaged::error_below_child(&built).unwrap();
    let path = dir.join("broken.mlasset");
    broken.save(&path).unwrap();
    let report = inspect(&path).unwrap();
    assert!(
        report.problems.iter().any(|p| p.contains("below child")),
        "{:?}",
        report.problems
    );
    assert!(report.warnings.is_empty(), "{:?}", report.warnings);
    let err = report.verdict().unwrap_err();
    assert!(matches!(err, SceneError::AssetCorrupt { .. }), "{err:?}");
    assert_eq!(report.summary.header, *broken.header());
}

/// `bake X -o X`, by the same name, another spelling or a link: refused before anything
/// is read, and the mesh is left as it was.
#[test]
fn an_output_that_is_the_input_is_refused_and_the_mesh_kept() {
    let dir = common::scratch("bake-onto-input");
    let mesh = dir.join("tet.obj");
    let text = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n";
    std::fs::write(&mesh, text).unwrap();
    let mut outputs = vec![mesh.clone(), dir.join(".").join("tet.obj")];
    #[cfg(unix)]
    {
        let link = dir.join("link.obj");
        std::os::unix::fs::symlink(&mesh, &link).unwrap();
        outputs.push(link);
    }
    for out in outputs {
        match bake(&BakeOptions::new(&mesh, &out), &mut |_| {}) {
            Err(SceneError::InvalidOption(m)) => {
                assert!(m.contains("is the input mesh itself"), "{m}")
            }
            other => panic!("{}: expected a refusal, got {other:?}", out.display()),
        }
        assert_eq!(std::fs::read_to_string(&mesh).unwrap(), text);
    }
    // Another name beside it is fine.
    bake(
        &BakeOptions::new(&mesh, dir.join("tet.mlasset")),
        &mut |_| {},
    )
    .unwrap();
}
