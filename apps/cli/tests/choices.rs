//! `meshlight graph` and `meshlight render` choose the same implementation for every stage
//! of the shipped frame, for the same adapter: both compile the one pipeline file through
//! the one registry, whose `auto` orders follow the adapter class. Checked for lavapipe's
//! features (a CPU adapter) and an NVIDIA H200's (few graphics units), without either
//! device, and the choices with their reasons snapshot-tested (UPDATE_SNAPSHOTS=1
//! rewrites them).

#[path = "../../../graph/tests/support/snapshot.rs"]
mod snapshot;

use meshlight::gpu_scene::SceneData;
use meshlight::graph::{AdapterClass, CompileOptions, Plan};
use meshlight_light_clustering::ClusteringSettings;
use meshlight_testing::features::{h200, lavapipe};
use meshlight_virtual_geometry::frame_graph::frame;
use meshlight_virtual_geometry::{FrameSettings, GraphSource, scenes};
use std::fmt::Write;
use std::path::Path;

/// Each pass's implementation and why, one line a pass.
fn choices(plan: &Plan) -> Vec<String> {
    plan.passes
        .iter()
        .filter(|p| !p.name.starts_with("readback:"))
        .map(|p| {
            format!(
                "{} {}/{}: {}",
                p.name,
                p.stage,
                p.implementation_label(),
                p.decision()
                    .unwrap_or_else(|| "the only implementation named".into())
            )
        })
        .collect()
}

#[test]
fn graph_and_render_choose_the_same_for_every_stage_on_each_adapter() {
    let shipped = Path::new(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../pipelines/virtual_geometry.toml"
    ));
    let asset = meshlight::scene::build_asset(
        &meshlight::scene::procedural_mesh(6),
        &meshlight::scene::BuildOptions::default(),
        &mut |_| {},
    )
    .unwrap()
    .asset;
    let placed = scenes::field(SceneData::new(Default::default()), &asset, 4).unwrap();
    let mut snapshot = String::new();
    for (name, features, class) in [
        ("lavapipe", lavapipe(), AdapterClass::Cpu),
        ("h200", h200(), AdapterClass::FewGraphicsUnits),
    ] {
        let options = CompileOptions::new(features).with_class(class);
        // `meshlight graph --pipeline pipelines/virtual_geometry.toml`, planned so.
        let graph = meshlight_cli::graph::plan(shipped, &options).unwrap_or_else(|e| panic!("{e}"));
        // `meshlight render`'s frame (the shipped frame, with lights and shadows) for a scene.
        let settings = FrameSettings {
            clustering: Some(ClusteringSettings::new([640, 360], 8)),
            shadows: Some(meshlight_virtual_geometry::ShadowSettings::default()),
            ..FrameSettings::new(640, 360)
        };
        let render = frame(&GraphSource::Shipped, &placed.data, &settings)
            .unwrap_or_else(|e| panic!("{e}"))
            .graph
            .compile(&options)
            .unwrap_or_else(|e| panic!("{name}: {e}"))
            .plan;
        // The renderer folds the cascades' walk into the camera's (`ShadowWalk`'s
        // default); every pass it keeps chooses as the file's plan does.
        let rendered = choices(&render);
        let pass_of = |line: &String| line.split(' ').next().unwrap_or_default().to_string();
        let kept: std::collections::BTreeSet<String> = rendered.iter().map(pass_of).collect();
        let planned: Vec<String> = choices(&graph)
            .into_iter()
            .filter(|line| kept.contains(&pass_of(line)))
            .collect();
        assert_eq!(planned, rendered, "{name}");
        assert_eq!(
            choices(&graph).len(),
            rendered.len() + 1,
            "{name}: only the cascades' walk is folded"
        );
        let _ = writeln!(snapshot, "{name} ({})", class.name());
        for line in choices(&render) {
            let _ = writeln!(snapshot, "  {line}");
        }
    }
    // What the classes decide: lavapipe draws near clusters in hardware with the
    // indirect draw; the H200 skips hardware raster and writes a texture target.
    assert!(
        snapshot.contains("hw_raster hw_raster/indirect_draw (auto):"),
        "{snapshot}"
    );
    assert!(
        snapshot.contains("hw_raster/indirect_draw (auto) (skipped)"),
        "{snapshot}"
    );
    assert!(
        snapshot.contains("sw_raster sw_raster/texture (auto)"),
        "{snapshot}"
    );
    snapshot::check("choices.txt", &snapshot);
}
