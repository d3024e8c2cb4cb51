//! The batches the executor records for each shipped pipeline, snapshot-tested with the
//! dumps that show them (no GPU: plans for two fixed feature sets). Set
//! UPDATE_SNAPSHOTS=1 to rewrite them after an intended change, then review the diff.

use meshlight::graph::{AdapterClass, CompileOptions, Plan, Recording, dump};
use std::fmt::Write;
use std::path::Path;

// The graph crate's snapshot check, shared so both crates' snapshots behave alike.
#[path = "../graph/tests/support/snapshot.rs"]
mod snapshot;
use snapshot::check;

const PIPELINES: [&str; 4] = [
    "brute_force",
    "light_clustering",
    "prefix_sum",
    "virtual_geometry",
];

/// What lavapipe (Mesa 22.3) offers through wgpu 30.
fn lavapipe() -> wgpu::Features {
    wgpu::Features::SHADER_INT64
        | wgpu::Features::SHADER_INT64_ATOMIC_MIN_MAX
        | wgpu::Features::SHADER_INT64_ATOMIC_ALL_OPS
        | wgpu::Features::SUBGROUP
        | wgpu::Features::TIMESTAMP_QUERY
        | wgpu::Features::INDIRECT_FIRST_INSTANCE
        | wgpu::Features::MULTI_DRAW_INDIRECT_COUNT
}

/// What the NVIDIA H100/H200 add that changes implementation choices.
fn nvidia() -> wgpu::Features {
    lavapipe() | wgpu::Features::TEXTURE_INT64_ATOMIC | wgpu::Features::TEXTURE_ATOMIC
}

/// The adapter class each feature set stands for: lavapipe is a CPU adapter, the H200
/// runs graphics on few units.
fn class_of(features: wgpu::Features) -> AdapterClass {
    if features.contains(wgpu::Features::TEXTURE_INT64_ATOMIC) {
        AdapterClass::FewGraphicsUnits
    } else {
        AdapterClass::Cpu
    }
}

fn plan(name: &str, features: wgpu::Features) -> Plan {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("pipelines")
        .join(format!("{name}.toml"));
    let builder = meshlight::graph::file::load_pipeline(&path, &meshlight::registry())
        .unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    builder
        .compile(&CompileOptions::new(features).with_class(class_of(features)))
        .unwrap_or_else(|e| panic!("{name}: {e}"))
        .plan
}

/// One line per batch: its label, then its passes, with why a pass needs the encoder.
fn batches(plan: &Plan) -> String {
    let mut out = String::new();
    for (b, batch) in plan.batches.iter().enumerate() {
        let _ = writeln!(out, "{}", batch.label(b));
        for &p in &batch.passes {
            let pass = &plan.passes[p];
            if pass.skipped.is_some() {
                let _ = writeln!(out, "  {} (skipped)", pass.name);
                continue;
            }
            match &pass.recording {
                Recording::Compute => {
                    let _ = writeln!(out, "  {}", pass.name);
                }
                Recording::Encoder(why) => {
                    let _ = writeln!(out, "  {} (encoder: {why})", pass.name);
                }
            }
        }
    }
    out
}

#[test]
fn every_batch_is_a_run_of_compute_passes_or_one_encoder_pass_in_plan_order() {
    for name in PIPELINES {
        for features in [lavapipe(), nvidia()] {
            let plan = plan(name, features);
            let flat: Vec<usize> = plan.batches.iter().flat_map(|b| b.passes.clone()).collect();
            assert_eq!(
                flat, plan.order,
                "{name}: batches cover the order, in order"
            );
            for b in &plan.batches {
                let compute: Vec<bool> = b
                    .passes
                    .iter()
                    .map(|&p| plan.passes[p].recording.is_compute())
                    .collect();
                assert!(
                    compute.iter().all(|&c| c == b.compute) && (b.compute || b.passes.len() == 1),
                    "{name}: {b:?}"
                );
            }
            // Two compute batches never touch: they would be one.
            assert!(
                plan.batches
                    .windows(2)
                    .all(|w| !(w[0].compute && w[1].compute)),
                "{name}"
            );
        }
    }
}

#[test]
fn batches_of_the_shipped_pipelines_match_their_snapshots() {
    for name in PIPELINES {
        check(
            &format!("{name}.lavapipe.batches.txt"),
            &batches(&plan(name, lavapipe())),
        );
        check(
            &format!("{name}.nvidia.batches.txt"),
            &batches(&plan(name, nvidia())),
        );
    }
}

#[test]
fn dumps_of_the_shipped_pipelines_show_their_batches_and_match_their_snapshots() {
    for name in PIPELINES {
        let plan = plan(name, lavapipe());
        let dot = dump::to_dot(&plan);
        assert!(dot.contains("subgraph cluster_batch0"), "{name}");
        let mermaid = dump::to_mermaid(&plan);
        assert!(mermaid.contains("subgraph batch0"), "{name}");
        let json = dump::to_json(&plan, None);
        let v: serde_json::Value = serde_json::from_str(&json).unwrap();
        assert_eq!(
            v["plan"]["batches"].as_array().map(|b| b.len()),
            Some(plan.batches.len()),
            "{name}"
        );
        let html = dump::to_html(&plan, name, None);
        assert!(html.contains("<h2>Batches</h2>"), "{name}");
        check(&format!("{name}.dot"), &dot);
        check(&format!("{name}.mmd"), &mermaid);
        check(&format!("{name}.json"), &json);
        // Stored as `.html.snap`: a golden copy of generated output, not a page of the project.
        check(&format!("{name}.html.snap"), &html);
    }
}
