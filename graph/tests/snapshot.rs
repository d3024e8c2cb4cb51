//! Snapshot tests of the dumps of a sample graph. Set UPDATE_SNAPSHOTS=1 to rewrite them
//! after an intended change, then review the diff.

#[path = "support/fake.rs"]
mod fake;
#[path = "support/snapshot.rs"]
mod snapshot;
use fake::*;
use meshlight_graph::*;
use snapshot::check;

fn sample() -> Plan {
    let mut g = GraphBuilder::new();
    g.import_buffer("scene", u32s(256), IMPORT_USAGE);
    g.import_texture(
        "output",
        TextureDesc::d2(wgpu::TextureFormat::Rgba8Unorm, 64, 64),
        wgpu::TextureUsages::STORAGE_BINDING | wgpu::TextureUsages::COPY_SRC,
    );
    let depth = g.history_buffer("depth \"pyramid\"", u32s(64));
    g.create_buffer("clusters", u32s(1024));
    g.create_buffer("visible", u32s(1024));
    g.create_buffer("debug", u32s(16));
    g.add_pass("fill", Fake::rw(&["scene"], &["clusters"]), Bindings::new())
        .unwrap();
    g.add_pass(
        "cull",
        Fake::rw(&["clusters", "prev"], &["visible"]),
        Bindings::new().bind("prev", depth.prev),
    )
    .unwrap();
    let mut raster = Fake::rw(&["visible"], &["depth"]);
    raster.scratch = Some(4096);
    g.add_pass(
        "raster <sw>",
        raster,
        Bindings::new().bind("depth", depth.current),
    )
    .unwrap();
    let slots = vec![
        Slot::buffer("visible", Access::StorageRead, Element::U32, ""),
        Slot::texture("output", Access::StorageWrite, None, ""),
    ];
    g.add_pass("resolve", Fake::new("resolve", slots), Bindings::new())
        .unwrap();
    g.add_pass(
        "debug_view",
        Fake::rw(&["clusters"], &["debug"]),
        Bindings::new(),
    )
    .unwrap();
    g.compile(&CompileOptions::new(wgpu::Features::empty()))
        .unwrap()
        .plan
}

#[test]
fn dot_dump_matches_snapshot() {
    let dot = dump::to_dot(&sample());
    assert!(
        dot.contains("(culled)")
            && dot.contains("peripheries=2")
            && dot.contains("depth \\\"pyramid\\\"")
    );
    check("sample.dot", &dot);
}

#[test]
fn json_dump_matches_snapshot() {
    let json = dump::to_json(&sample(), None);
    let v: serde_json::Value = serde_json::from_str(&json).unwrap();
    assert_eq!(v["plan"]["culled"], serde_json::json!([4]));
    check("sample.json", &json);
}

#[test]
fn mermaid_dump_matches_snapshot() {
    check("sample.mmd", &dump::to_mermaid(&sample()));
}

#[test]
fn html_dump_is_self_contained_and_matches_snapshot() {
    let html = dump::to_html(&sample(), "sample", None);
    assert!(!html.contains("http://") && !html.contains("https://") && !html.contains("<script"));
    assert!(html.contains("raster &lt;sw&gt;"));
    // Stored as `.html.snap`: a golden copy of generated output, not a page of the project.
    check("sample.html.snap", &html);
}

/// The drawing: every pass once (the culled one dashed, named culled), each below every
/// pass it depends on, and an arrow per pair of dependent passes carrying the resources'
/// names; standalone, it is an SVG document.
#[test]
fn svg_draws_every_pass_below_what_it_depends_on() {
    let plan = sample();
    let svg = dump::to_svg(&plan);
    assert!(
        svg.starts_with("<svg xmlns=\"http://www.w3.org/2000/svg\""),
        "{svg}"
    );
    let rank = |name: &str| -> u32 {
        let key = format!(
            "data-pass=\"{}\" data-rank=\"",
            name.replace('<', "&lt;").replace('>', "&gt;")
        );
        assert_eq!(svg.matches(&key).count(), 1, "{name} drawn once");
        let at = svg.find(&key).unwrap() + key.len();
        svg[at..].split('"').next().unwrap().parse().unwrap()
    };
    for e in &plan.edges {
        let (from, to) = (&plan.passes[e.from].name, &plan.passes[e.to].name);
        assert!(rank(from) < rank(to), "{from} → {to}");
        assert!(svg.contains(&format!(
            "<title>{} → {}: ",
            from.replace('<', "&lt;").replace('>', "&gt;"),
            to.replace('<', "&lt;").replace('>', "&gt;")
        )));
    }
    assert!(svg.contains("class=\"pass culled\" data-pass=\"debug_view\""));
    assert_eq!(svg.matches("<g class=\"pass").count(), plan.passes.len());
    // The page embeds the same drawing, without the namespace.
    let html = dump::to_html(&plan, "sample", None);
    assert!(html.contains("<h2>Graph</h2>\n<svg width="), "{html}");
}
