//! The batches the executor records for each shipped pipeline, snapshot-tested with the
//! dumps that show them (no GPU: plans for two fixed feature sets). Set
//! UPDATE_SNAPSHOTS=1 to rewrite them after an intended change, then review the diff.

use meshlight::graph::{AdapterClass, CompileOptions, Plan, Recording, dump};
use meshlight_testing::features::{h200, lavapipe};
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
        for features in [lavapipe(), h200()] {
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
            &batches(&plan(name, h200())),
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

/// A box of the SVG drawing: its pass, where it is, and the two lines of text it holds.
struct DrawnBox {
    pass: String,
    class: String,
    rect: [f64; 4],
    name: String,
    label: String,
    batch: String,
}

fn attribute(s: &str, name: &str) -> String {
    let key = format!(" {name}=\"");
    let at = s.find(&key).unwrap_or_else(|| panic!("no {name} in {s}")) + key.len();
    s[at..].split('"').next().unwrap().to_string()
}

/// The texts of one box, in order: the name, the stage and implementation, the batch.
fn texts(g: &str) -> Vec<String> {
    g.split("<text ")
        .skip(1)
        .map(|t| {
            t.split('>')
                .nth(1)
                .unwrap()
                .split("</text")
                .next()
                .unwrap()
                .to_string()
        })
        .collect()
}

fn drawn_boxes(svg: &str) -> Vec<DrawnBox> {
    svg.lines()
        .filter(|l| l.starts_with("<g class=\"pass"))
        .map(|g| {
            let rect = ["x", "y", "width", "height"].map(|a| {
                attribute(&g[g.find("<rect").unwrap()..], a)
                    .parse()
                    .unwrap()
            });
            let t = texts(g);
            DrawnBox {
                pass: attribute(g, "data-pass"),
                class: attribute(g, "class"),
                rect,
                name: t[0].clone(),
                label: t[1].clone(),
                batch: t[2].clone(),
            }
        })
        .collect()
}

/// Points along an edge's path (`M`, `H`, `V` and `C` commands, as the drawing writes
/// them): every corner, and a point a pixel apart along straight runs and curves.
fn path_points(d: &str) -> Vec<(f64, f64)> {
    let mut points = vec![];
    let mut at = (0.0, 0.0);
    let pair = |t: &str| -> (f64, f64) {
        let (x, y) = t.split_once(',').unwrap();
        (x.parse().unwrap(), y.parse().unwrap())
    };
    let mut tokens = d.split_whitespace();
    while let Some(t) = tokens.next() {
        let (cmd, rest) = t.split_at(1);
        let line = |from: (f64, f64), to: (f64, f64), points: &mut Vec<(f64, f64)>| {
            let n = ((to.0 - from.0).abs() + (to.1 - from.1).abs())
                .ceil()
                .max(1.0) as usize;
            for i in 0..=n {
                let f = i as f64 / n as f64;
                points.push((from.0 + (to.0 - from.0) * f, from.1 + (to.1 - from.1) * f));
            }
        };
        match cmd {
            "M" => {
                at = pair(rest);
                points.push(at);
            }
            "H" => {
                let to = (rest.parse().unwrap(), at.1);
                line(at, to, &mut points);
                at = to;
            }
            "V" => {
                let to = (at.0, rest.parse().unwrap());
                line(at, to, &mut points);
                at = to;
            }
            "C" => {
                let c1 = pair(rest);
                let c2 = pair(tokens.next().unwrap());
                let to = pair(tokens.next().unwrap());
                for i in 0..=256 {
                    let f = i as f64 / 256.0;
                    let g = 1.0 - f;
                    let bez = |a: f64, b: f64, c: f64, e: f64| {
                        g * g * g * a + 3.0 * g * g * f * b + 3.0 * g * f * f * c + f * f * f * e
                    };
                    points.push((bez(at.0, c1.0, c2.0, to.0), bez(at.1, c1.1, c2.1, to.1)));
                }
                at = to;
            }
            other => panic!("unexpected path command {other} in {d}"),
        }
    }
    points
}

/// The drawing of every shipped pipeline, on both feature sets: each box holds its text
/// (at a generous 0.6 em a character), no edge passes through any box (its own included:
/// it leaves one box's bottom edge and enters the other's top), and a pass the adapter's
/// class skips is drawn grey and says so.
#[test]
fn svg_boxes_hold_their_text_and_no_edge_crosses_a_box() {
    let mut skipped_seen = 0;
    for name in PIPELINES {
        for features in [lavapipe(), h200()] {
            let plan = plan(name, features);
            let svg = dump::to_svg(&plan);
            let boxes = drawn_boxes(&svg);
            assert_eq!(boxes.len(), plan.order.len() + plan.culled.len(), "{name}");
            for b in &boxes {
                let [_, _, w, _] = b.rect;
                let chars = |s: &str| s.chars().count() as f64;
                let top = chars(&b.name) * 7.2 + chars(&b.batch) * 6.0 + 7.0 + 6.0 + 6.0;
                let bottom = chars(&b.label) * 6.0 + 7.0 + 4.0;
                assert!(
                    top <= w && bottom <= w,
                    "{name}: {} ({} / {}) in a box {w} wide",
                    b.pass,
                    b.name,
                    b.label
                );
            }
            let mut edges = 0;
            for line in svg.lines().filter(|l| l.starts_with("<path d=\"")) {
                edges += 1;
                let d = attribute(line, "d");
                for (x, y) in path_points(&d) {
                    for b in &boxes {
                        let [bx, by, bw, bh] = b.rect;
                        assert!(
                            !(x > bx + 0.5
                                && x < bx + bw - 0.5
                                && y > by + 0.5
                                && y < by + bh - 0.5),
                            "{name}: the edge {} passes through {} at ({x}, {y})",
                            line.split("<title>").nth(1).unwrap_or(line),
                            b.pass
                        );
                    }
                }
            }
            let pairs: std::collections::BTreeSet<(usize, usize)> =
                plan.edges.iter().map(|e| (e.from, e.to)).collect();
            assert_eq!(
                edges,
                pairs.len(),
                "{name}: an arrow per pair of dependent passes"
            );
            for &p in &plan.order {
                let pass = &plan.passes[p];
                let drawn = boxes.iter().find(|b| b.pass == pass.name).unwrap();
                if pass.skipped.is_some() {
                    skipped_seen += 1;
                    assert_eq!(drawn.class, "pass skipped", "{name}: {}", pass.name);
                    assert!(drawn.label.ends_with("(skipped)"), "{}", drawn.label);
                } else {
                    assert_eq!(drawn.class, "pass", "{name}: {}", pass.name);
                }
            }
        }
    }
    assert!(
        skipped_seen > 0,
        "some shipped pipeline skips a pass on some class"
    );
}
