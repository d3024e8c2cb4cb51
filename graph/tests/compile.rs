//! Headless compile tests: every error kind, culling, order, lifetimes, usages, ops.

#[path = "support/fake.rs"]
mod fake;
use fake::*;
use meshlight_graph::*;

fn names(plan: &Plan, idx: &[usize]) -> Vec<String> {
    idx.iter().map(|&i| plan.passes[i].name.clone()).collect()
}

#[test]
fn order_follows_dependencies_and_declaration_order_breaks_ties() {
    let mut g = GraphBuilder::new();
    g.import_buffer("out", u32s(4), IMPORT_USAGE);
    let a = g.create_buffer("a", u32s(4));
    let b = g.create_buffer("b", u32s(4));
    g.add_pass("make_b", Fake::rw(&[], &["b"]), Bindings::new())
        .unwrap();
    g.add_pass("make_a", Fake::rw(&[], &["a"]), Bindings::new())
        .unwrap();
    let _ = (a, b);
    g.add_pass("combine", Fake::rw(&["a", "b"], &["out"]), Bindings::new())
        .unwrap();
    let plan = g.compile(&opts()).unwrap().plan;
    assert_eq!(names(&plan, &plan.order), ["make_b", "make_a", "combine"]);
    assert!(plan.culled.is_empty());
}

#[test]
fn compile_is_deterministic() {
    let build = || {
        let mut g = GraphBuilder::new();
        g.import_buffer("out", u32s(4), IMPORT_USAGE);
        for i in 0..20 {
            g.create_buffer(&format!("t{i}"), u32s(4 + i));
            g.add_pass(&format!("w{i}"), Fake::rw(&[], &[]), Bindings::new())
                .unwrap();
        }
        g.add_pass("end", Fake::rw(&[], &["out"]), Bindings::new())
            .unwrap();
        dump::to_json(&g.compile(&opts()).unwrap().plan, None)
    };
    assert_eq!(build(), build());
}

#[test]
fn passes_whose_results_reach_nothing_are_culled() {
    let mut g = GraphBuilder::new();
    g.import_buffer("out", u32s(4), IMPORT_USAGE);
    g.create_buffer("used", u32s(4));
    g.create_buffer("unused", u32s(4));
    g.add_pass("dead", Fake::rw(&[], &["unused"]), Bindings::new())
        .unwrap();
    g.add_pass("feeds", Fake::rw(&[], &["used"]), Bindings::new())
        .unwrap();
    g.add_pass("final", Fake::rw(&["used"], &["out"]), Bindings::new())
        .unwrap();
    let mut logger = Fake::rw(&["used"], &[]);
    logger.side_effect = true;
    g.add_pass("logger", logger, Bindings::new()).unwrap();
    let plan = g.compile(&opts()).unwrap().plan;
    assert_eq!(names(&plan, &plan.culled), ["dead"]);
    assert_eq!(names(&plan, &plan.order), ["feeds", "final", "logger"]);
    // A culled pass's resource is never allocated.
    let unused = plan.resource_index("unused").unwrap();
    assert!(
        plan.resources[unused].lifetime.is_none() && plan.resources[unused].pool_slot.is_none()
    );
}

#[test]
fn history_writes_are_never_culled() {
    let mut g = GraphBuilder::new();
    let h = g.history_buffer("acc", u32s(4));
    g.add_pass(
        "acc",
        Fake::rw(&["in"], &["out"]),
        Bindings::new().bind("in", h.prev).bind("out", h.current),
    )
    .unwrap();
    let plan = g.compile(&opts()).unwrap().plan;
    assert!(plan.culled.is_empty());
}

#[test]
fn cycle_reports_the_whole_path() {
    // Explicit versions (as pipeline files allow) can point forward and close a loop.
    let mut g = GraphBuilder::new();
    g.import_buffer("sink", u32s(4), IMPORT_USAGE);
    g.create_buffer("x", u32s(4));
    g.create_buffer("y", u32s(4));
    g.create_buffer("z", u32s(4));
    let y1 = g.resource_at("y", 1).unwrap();
    g.add_pass(
        "a",
        Fake::rw(&["in"], &["x", "sink"]),
        Bindings::new().bind("in", y1),
    )
    .unwrap();
    g.add_pass("b", Fake::rw(&["x"], &["z"]), Bindings::new())
        .unwrap();
    g.add_pass("c", Fake::rw(&["z"], &["y"]), Bindings::new())
        .unwrap();
    let e = compile_error(g);
    let GraphError::Cycle { path } = e else {
        panic!("expected a cycle, got {e:?}");
    };
    assert_eq!(path, ["a", "b", "c"]);
}

#[test]
fn read_of_a_transient_nothing_writes_is_an_error() {
    let mut g = GraphBuilder::new();
    g.import_buffer("out", u32s(4), IMPORT_USAGE);
    g.create_buffer("never_written", u32s(4));
    g.add_pass(
        "reader",
        Fake::rw(&["never_written"], &["out"]),
        Bindings::new(),
    )
    .unwrap();
    let_compile_error!(g => GraphError::ReadWithoutWriter { pass, resource, .. });
    assert_eq!(
        (pass.as_str(), resource.as_str()),
        ("reader", "never_written")
    );
}

#[test]
fn stale_handle_is_an_error_naming_the_writer() {
    let mut g = GraphBuilder::new();
    g.import_buffer("out", u32s(4), IMPORT_USAGE);
    let t0 = g.create_buffer("t", u32s(4));
    let t1 = g
        .add_pass(
            "first",
            Fake::rw(&[], &["t"]),
            Bindings::new().bind("t", t0),
        )
        .unwrap()
        .buffer("t")
        .unwrap();
    g.add_pass(
        "second",
        Fake::rw(&[], &["t"]),
        Bindings::new().bind("t", t1),
    )
    .unwrap();
    g.add_pass(
        "late",
        Fake::rw(&["t"], &["out"]),
        Bindings::new().bind("t", t1),
    )
    .unwrap();
    let_compile_error!(g => GraphError::StaleVersion { pass, resource, given, current, writer, .. });
    assert_eq!(
        (
            pass.as_str(),
            resource.as_str(),
            given,
            current,
            writer.as_str()
        ),
        ("late", "t", 1, 2, "second")
    );
}

#[test]
fn element_and_kind_mismatches_are_errors() {
    let mut g = GraphBuilder::new();
    g.import_buffer("out", BufferDesc::array(Element::F32, 4), IMPORT_USAGE);
    g.add_pass("writer", Fake::rw(&[], &["out"]), Bindings::new())
        .unwrap();
    let_compile_error!(g => GraphError::DescriptorMismatch { pass, slot, expected, found, .. });
    assert_eq!((pass.as_str(), slot.as_str()), ("writer", "out"));
    assert!(
        expected.contains("u32") && found.contains("f32"),
        "{expected} / {found}"
    );

    let mut g = GraphBuilder::new();
    g.import_texture(
        "out",
        TextureDesc::d2(wgpu::TextureFormat::R32Uint, 4, 4),
        wgpu::TextureUsages::STORAGE_BINDING,
    );
    g.add_pass("writer", Fake::rw(&[], &["out"]), Bindings::new())
        .unwrap();
    let_compile_error!(g => GraphError::DescriptorMismatch { .. });

    let mut g = GraphBuilder::new();
    g.import_texture(
        "img",
        TextureDesc::d2(wgpu::TextureFormat::Rgba8Unorm, 4, 4),
        wgpu::TextureUsages::all(),
    );
    let slot = Slot::texture(
        "img",
        Access::StorageWrite,
        Some(wgpu::TextureFormat::R32Float),
        "",
    );
    g.add_pass("writer", Fake::new("t", vec![slot]), Bindings::new())
        .unwrap();
    let_compile_error!(g => GraphError::DescriptorMismatch { expected, found, .. });
    assert_eq!(
        (expected.as_str(), found.as_str()),
        ("a r32float texture", "a rgba8unorm texture")
    );
}

#[test]
fn usage_the_import_does_not_allow_is_an_error() {
    let mut g = GraphBuilder::new();
    g.import_buffer("out", u32s(4), wgpu::BufferUsages::COPY_SRC);
    g.add_pass("writer", Fake::rw(&[], &["out"]), Bindings::new())
        .unwrap();
    let_compile_error!(g => GraphError::UsageNotAllowed { resource, reason, .. });
    assert_eq!(resource, "out");
    assert!(reason.contains("STORAGE"), "{reason}");
    // A buffer in an indirect slot is fine; a texture there is not.
    let mut g = GraphBuilder::new();
    g.import_texture(
        "args",
        TextureDesc::d2(wgpu::TextureFormat::R32Uint, 4, 4),
        wgpu::TextureUsages::all(),
    );
    g.import_buffer("out", u32s(4), IMPORT_USAGE);
    let slots = vec![
        Slot {
            name: "args",
            access: Access::Indirect,
            also: Vec::new(),
            kind: SlotKind::Texture { format: None },
            doc: "",
            optional: false,
        },
        Slot::buffer("out", Access::StorageWrite, Element::U32, ""),
    ];
    g.add_pass("draw", Fake::new("t", slots), Bindings::new())
        .unwrap();
    let_compile_error!(g => GraphError::UsageNotAllowed { .. });
}

#[test]
fn writing_last_frames_history_is_an_error() {
    let mut g = GraphBuilder::new();
    let h = g.history_buffer("acc", u32s(4));
    g.add_pass(
        "bad",
        Fake::rw(&[], &["out"]),
        Bindings::new().bind("out", h.prev),
    )
    .unwrap();
    let_compile_error!(g => GraphError::ReadOnlyResource { .. });
}

#[test]
fn duplicate_names_are_errors() {
    let mut g = GraphBuilder::new();
    g.create_buffer("x", u32s(4));
    g.create_buffer("x", u32s(4));
    let_compile_error!(g => GraphError::DuplicateName { what, name });
    assert_eq!((what, name.as_str()), ("resource", "x"));
    let mut g = GraphBuilder::new();
    g.create_buffer("x", u32s(4));
    g.add_pass("p", Fake::rw(&[], &["x"]), Bindings::new())
        .unwrap();
    assert!(matches!(
        g.add_pass("p", Fake::rw(&[], &["x"]), Bindings::new()),
        Err(GraphError::DuplicateName { what: "pass", .. })
    ));
}

#[test]
fn required_feature_missing_on_the_adapter_is_an_error() {
    let mut g = GraphBuilder::new();
    g.import_buffer("out", u32s(4), IMPORT_USAGE);
    let mut p = Fake::rw(&[], &["out"]);
    p.required = wgpu::Features::TEXTURE_INT64_ATOMIC;
    g.add_pass("raster", p, Bindings::new()).unwrap();
    let_compile_error!(g => GraphError::MissingFeature { pass, features, .. });
    assert_eq!(
        (pass.as_str(), features.as_str()),
        ("raster", "TEXTURE_INT64_ATOMIC")
    );
}

#[test]
fn unknown_and_unbound_slots_are_errors() {
    let mut g = GraphBuilder::new();
    let x = g.create_buffer("x", u32s(4));
    match g.add_pass(
        "p",
        Fake::rw(&[], &["out"]),
        Bindings::new().bind("outt", x),
    ) {
        Err(GraphError::UnknownSlot {
            slot, available, ..
        }) => assert_eq!((slot.as_str(), available.as_str()), ("outt", "out")),
        other => panic!("{:?}", other.err()),
    }
    assert!(matches!(
        g.add_pass("p", Fake::rw(&[], &["out"]), Bindings::new()),
        Err(GraphError::UnboundSlot { .. })
    ));
    // Asking a pass for an output it does not write names the pass and what it writes.
    let out = g
        .add_pass("q", Fake::rw(&[], &["out"]), Bindings::new().bind("out", x))
        .unwrap();
    match out.buffer("outt") {
        Err(e @ GraphError::NotWritten { .. }) => assert_eq!(
            e.to_string(),
            "pass `q` writes no slot `outt`, so it has no output of that name; it writes: out"
        ),
        other => panic!("{other:?}"),
    }
}

#[test]
fn lifetimes_pool_slots_and_bytes_saved() {
    // a → b → c → out: a and c never overlap, so they share a slot.
    let mut g = GraphBuilder::new();
    g.import_buffer("out", u32s(1024), IMPORT_USAGE);
    g.create_buffer("a", u32s(1024));
    g.create_buffer("b", u32s(1024));
    g.create_buffer("c", u32s(1024));
    g.add_pass("p1", Fake::rw(&[], &["a"]), Bindings::new())
        .unwrap();
    g.add_pass("p2", Fake::rw(&["a"], &["b"]), Bindings::new())
        .unwrap();
    g.add_pass("p3", Fake::rw(&["b"], &["c"]), Bindings::new())
        .unwrap();
    g.add_pass("p4", Fake::rw(&["c"], &["out"]), Bindings::new())
        .unwrap();
    let plan = g.compile(&opts()).unwrap().plan;
    let slot = |n: &str| {
        plan.resources[plan.resource_index(n).unwrap()]
            .pool_slot
            .unwrap()
    };
    let life = |n: &str| {
        plan.resources[plan.resource_index(n).unwrap()]
            .lifetime
            .unwrap()
    };
    assert_eq!((life("a").first, life("a").last), (0, 1));
    assert_eq!((life("c").first, life("c").last), (2, 3));
    assert_eq!(slot("a"), slot("c"));
    assert_ne!(slot("a"), slot("b"));
    assert_eq!(plan.bytes_without_reuse, 3 * 4096);
    assert_eq!(plan.bytes_with_reuse, 2 * 4096);
}

#[test]
fn usages_and_render_target_ops_are_derived() {
    let mut g = GraphBuilder::new();
    g.import_texture(
        "final",
        TextureDesc::d2(wgpu::TextureFormat::Rgba8Unorm, 8, 8),
        wgpu::TextureUsages::all(),
    );
    g.create_texture(
        "color",
        TextureDesc::d2(wgpu::TextureFormat::Rgba8Unorm, 8, 8),
    );
    g.create_texture(
        "scratch_target",
        TextureDesc::d2(wgpu::TextureFormat::R8Unorm, 8, 8),
    );
    let rt = |n: &'static str| Slot::texture(n, Access::RenderTarget, None, "");
    g.add_pass(
        "draw",
        Fake::new("draw", vec![rt("color"), rt("scratch_target")]),
        Bindings::new(),
    )
    .unwrap();
    g.add_pass(
        "draw_more",
        Fake::new("draw", vec![rt("color")]),
        Bindings::new(),
    )
    .unwrap();
    let read = Slot::texture("color", Access::Sampled, None, "");
    let write = Slot::texture("final", Access::StorageWrite, None, "");
    g.add_pass(
        "post",
        Fake::new("post", vec![read, write]),
        Bindings::new(),
    )
    .unwrap();
    let plan = g.compile(&opts()).unwrap().plan;
    let ops = |pass: &str, slot: &str| {
        let p = &plan.passes[plan.pass_index(pass).unwrap()];
        p.slots
            .iter()
            .find(|s| s.slot == slot)
            .unwrap()
            .ops
            .unwrap()
    };
    use meshlight_graph::{LoadOp, StoreOp};
    assert_eq!(
        (ops("draw", "color").load, ops("draw", "color").store),
        (LoadOp::Clear, StoreOp::Store)
    );
    assert_eq!(
        (
            ops("draw", "scratch_target").load,
            ops("draw", "scratch_target").store
        ),
        (LoadOp::Clear, StoreOp::Discard)
    );
    assert_eq!(
        (
            ops("draw_more", "color").load,
            ops("draw_more", "color").store
        ),
        (LoadOp::Load, StoreOp::Store)
    );
    let color = &plan.resources[plan.resource_index("color").unwrap()];
    assert_eq!(
        color.texture_usage,
        wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::TEXTURE_BINDING
    );
}

#[test]
fn one_resource_in_a_read_and_a_write_slot_of_one_pass_is_an_error() {
    let mut g = GraphBuilder::new();
    g.import_buffer("out", u32s(4), IMPORT_USAGE);
    g.add_pass(
        "p",
        Fake::rw(&["in"], &["w"]),
        Bindings::new()
            .bind_named("in", "out")
            .bind_named("w", "out"),
    )
    .unwrap();
    let_compile_error!(g => GraphError::UsageNotAllowed { pass, resource, reason, .. });
    assert_eq!((pass.as_str(), resource.as_str()), ("p", "out"));
    assert!(reason.contains("another slot"), "{reason}");
}

/// A buffer of no elements is refused at compile, naming the resource and the size
/// parameter to raise, rather than surfacing later as wgpu's refusal of the binding.
#[test]
fn a_buffer_of_no_elements_is_refused_naming_its_parameter() {
    let build = |count: BufferDesc| {
        let mut g = GraphBuilder::new();
        g.size_param("clusters", 0);
        g.create_buffer("list", count);
        g.add_pass("fill", Fake::rw(&[], &["list"]), Bindings::new())
            .unwrap();
        g.export(g.resource("list").unwrap());
        g.compile(&CompileOptions::new(wgpu::Features::empty()))
    };
    match build(BufferDesc::array_param(Element::U32, "clusters")) {
        Err(e @ GraphError::EmptyBuffer { .. }) => {
            let m = e.to_string();
            assert!(
                m.contains("`list`") && m.contains("`clusters` (now 0) at least 1"),
                "{m}"
            );
        }
        other => panic!("expected EmptyBuffer, got {:?}", other.err()),
    }
    match build(u32s(0)) {
        Err(e @ GraphError::EmptyBuffer { param: None, .. }) => {
            assert!(e.to_string().contains("a count of at least 1"), "{e}");
        }
        other => panic!("expected EmptyBuffer, got {:?}", other.err()),
    }
    assert!(build(u32s(1)).is_ok());
    // An import declared with no elements binds the caller's buffer, whatever its size
    // (an empty input of a scan, say): not refused.
    let mut g = GraphBuilder::new();
    let input = g.import_buffer("input", u32s(0), wgpu::BufferUsages::STORAGE);
    g.add_pass(
        "read",
        Fake::rw(&["in"], &[]),
        Bindings::new().bind("in", input),
    )
    .unwrap();
    assert!(
        g.compile(&CompileOptions::new(wgpu::Features::empty()))
            .is_ok()
    );
}
