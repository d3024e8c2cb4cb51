//! A pipeline changed through its methods, as a renderer applies its settings to the
//! file that is its frame: parameters, implementations, stage parameters, added and
//! bound resources, removed passes with what only they made, derived mip counts and
//! passes skipped on an adapter class. All headless.

#[path = "support/fake.rs"]
mod fake;
use fake::*;
use meshlight_graph::file::{EntryKind, Params, Pipeline, Registry, ResourceEntry};
use meshlight_graph::*;

/// A pass of stage `stage` reading `inputs` and writing `outputs` (u32 buffers), with
/// `extra` an optional slot it reads where bound.
fn rw(
    stage: &'static str,
    inputs: &'static [&'static str],
    outputs: &'static [&'static str],
    extra: Option<&'static str>,
) -> Fake {
    let mut slots = Fake::rw(inputs, outputs).implementation().contract.slots;
    if let Some(e) = extra {
        slots.push(Slot::read(e, Element::U32, "").optional());
    }
    Fake::new(stage, slots)
}

fn registry() -> Registry {
    let mut r = Registry::new();
    r.register("make", "one", |_: &Params| {
        Ok(rw("make", &[], &["a"], None))
    });
    r.register("extra", "one", |_: &Params| {
        Ok(rw("extra", &["a"], &["side"], None))
    });
    r.register("use", "one", |p: &Params| {
        p.only(&["k"])?;
        Ok(rw("use", &["a"], &["out"], Some("side")))
    });
    r.register("use", "two", |_: &Params| {
        Ok(rw("use", &["a"], &["out"], Some("side")))
    });
    r
}

const FILE: &str = r#"
[params]
n = 16
side = 8

[[resource]]
name = "a"
kind = "transient"
buffer = { element = "u32", count_param = "n" }

[[resource]]
name = "side_list"
kind = "transient"
buffer = { element = "u32", count_param = "side" }

[[resource]]
name = "out"
kind = "exported"
buffer = { element = "u32", count_param = "n" }

[[resource]]
name = "unused"
kind = "imported"
buffer = { element = "u32", count = 4 }
usage = ["STORAGE"]

[[pass]]
name = "make"
stage = "make"
implementation = "one"

[[pass]]
name = "extra"
stage = "extra"
implementation = "one"
bind = { side = "side_list" }

[[pass]]
name = "use"
stage = "use"
implementation = "one"
bind = { side = "side_list" }
"#;

fn pipeline() -> Pipeline {
    Pipeline::parse(FILE, "edit.toml").unwrap()
}

fn plan(p: &Pipeline) -> Plan {
    p.build(&registry())
        .unwrap_or_else(|e| panic!("{e}"))
        .compile(&opts())
        .unwrap_or_else(|e| panic!("{e}"))
        .plan
}

fn bound(plan: &Plan, pass: &str, slot: &str) -> Option<String> {
    let p = &plan.passes[plan.pass_index(pass).unwrap()];
    p.slots
        .iter()
        .find(|s| s.slot == slot)
        .map(|s| plan.resources[s.resource].info.name.clone())
}

#[test]
fn parameters_implementations_and_stage_parameters_change_through_methods() {
    let mut p = pipeline();
    p.set_param("n", 64).unwrap();
    let err = p.set_param("m", 1).unwrap_err();
    assert!(err.to_string().contains("`m`") && err.to_string().contains("[params]"));
    assert_eq!(p.set_implementation("use", "two"), 1);
    assert_eq!(p.set_implementation("nothing", "two"), 0);
    let plan = plan(&p);
    assert_eq!(
        plan.passes[plan.pass_index("use").unwrap()].implementation,
        "fake"
    );
    let a = &plan.resources[plan.resource_index("a").unwrap()];
    assert_eq!(a.info.desc.bytes(), 64 * 4);
    // A stage parameter the implementation refuses is the pass's error.
    let mut q = pipeline();
    assert_eq!(q.set_stage_param("use", "j", 1), 1);
    match q.build(&registry()).err() {
        Some(GraphError::Parameter { pass, message }) => {
            assert_eq!(pass, "use");
            assert!(message.contains("`j`"), "{message}");
        }
        other => panic!("{other:?}"),
    }
    assert!(pipeline().pass_mut("nope").is_err());
}

#[test]
fn an_added_resource_binds_by_name_and_a_stage_binding_reaches_every_pass_of_it() {
    let mut p = pipeline();
    p.pass_mut("use").unwrap().unbind("side");
    // Unbound, the optional slot stays so: no resource is named `side`.
    assert_eq!(bound(&plan(&p), "use", "side"), None);
    // A resource of the slot's name binds by name.
    p.add_resource(
        ResourceEntry::buffer("side", EntryKind::Imported, "u32", None, 8).with_usage(&["STORAGE"]),
    )
    .unwrap();
    assert_eq!(bound(&plan(&p), "use", "side").as_deref(), Some("side"));
    assert!(
        p.add_resource(ResourceEntry::buffer(
            "a",
            EntryKind::Transient,
            "u32",
            None,
            1
        ))
        .is_err()
    );
    // Bound for the whole stage by a call.
    assert_eq!(p.bind_stage("use", "side", "side_list"), 1);
    assert_eq!(
        bound(&plan(&p), "use", "side").as_deref(),
        Some("side_list")
    );
}

#[test]
fn removing_passes_takes_what_only_they_made_and_unbinds_it() {
    let mut p = pipeline();
    let removed = p
        .remove_passes(&registry(), |e| e.stage == "extra")
        .unwrap();
    assert_eq!(removed.passes, ["extra"]);
    // `side_list` was written only by `extra`; `unused` was bound by nobody.
    assert_eq!(removed.resources, ["side_list", "unused"]);
    assert_eq!(p.pass("use").unwrap().binding("side"), None);
    let plan = plan(&p);
    assert_eq!(bound(&plan, "use", "side"), None);
    assert_eq!(bound(&plan, "use", "a").as_deref(), Some("a"));
    // What a kept pass still writes stays, even when a removed pass wrote it too.
    let mut q = pipeline();
    q.remove_passes(&registry(), |e| e.name == "use").unwrap();
    assert!(q.resource("a").is_some() && q.resource("side_list").is_some());
    assert!(q.resource("out").is_none(), "only `use` wrote `out`");
}

#[test]
fn full_mip_chains_follow_the_parameters_and_other_words_are_refused() {
    let text = r#"
[params]
w = 640
h = 360

[[resource]]
name = "chain"
kind = "exported"
texture = { format = "r32float", width_param = "w", height_param = "h", mip_levels = "full" }
"#;
    let mut p = Pipeline::parse(text, "mips.toml").unwrap();
    let mips = |p: &Pipeline| {
        let g = p.build(&Registry::new()).unwrap();
        match &g.resources()[0].desc {
            ResourceDesc::Texture(t) => t.mip_levels,
            other => panic!("{other:?}"),
        }
    };
    assert_eq!(mips(&p), 10, "640 → 1: 10 levels");
    p.set_param("w", 1024).unwrap();
    assert_eq!(mips(&p), 11);
    p.set_param("w", 1).unwrap();
    p.set_param("h", 1).unwrap();
    assert_eq!(mips(&p), 1);
    let err = Pipeline::parse(&text.replace("\"full\"", "\"all\""), "mips.toml")
        .err()
        .unwrap();
    assert!(err.to_string().contains("\"full\""), "{err}");
    // Written back out, the word survives.
    assert!(
        Pipeline::parse(text, "m.toml")
            .unwrap()
            .to_toml()
            .contains("mip_levels = \"full\"")
    );
}

/// Skips itself on one adapter class: stays in the plan, declares nothing, records
/// nothing, never holds a batch up.
struct SkipOnCpu;

impl Pass for SkipOnCpu {
    fn implementation(&self) -> Implementation {
        Implementation::new(
            "skip_on_cpu",
            StageContract {
                stage: "draw",
                slots: vec![Slot::buffer(
                    "a",
                    Access::StorageReadWrite,
                    Element::U32,
                    "",
                )],
            },
        )
    }
    fn setup(&self, ctx: &mut SetupContext) -> Result<()> {
        if ctx.adapter_class() == AdapterClass::Cpu {
            ctx.skip("nothing to draw on a CPU adapter");
            return Ok(());
        }
        ctx.needs_encoder("draws");
        Ok(())
    }
    fn record(&self, _: &mut RecordContext<'_>) -> Result<()> {
        panic!("a skipped pass was recorded")
    }
}

#[test]
fn a_pass_skipped_on_an_adapter_class_stays_in_the_plan_and_says_why() {
    let build = || {
        let mut g = GraphBuilder::new();
        g.create_buffer("a", u32s(4));
        let b = g.create_buffer("b", u32s(4));
        g.export(b);
        g.add_pass("make", Fake::rw(&[], &["a"]), Bindings::new())
            .unwrap();
        g.add_pass("draw", SkipOnCpu, Bindings::new()).unwrap();
        g.add_pass("use", Fake::rw(&["a"], &["b"]), Bindings::new())
            .unwrap();
        g
    };
    let cpu = build()
        .compile(&opts().with_class(AdapterClass::Cpu))
        .unwrap()
        .plan;
    let draw = &cpu.passes[cpu.pass_index("draw").unwrap()];
    assert_eq!(
        draw.skipped.as_deref(),
        Some("nothing to draw on a CPU adapter")
    );
    assert!(draw.implementation_label().contains("skipped"));
    assert!(draw.decision().unwrap().contains("nothing to draw"));
    assert!(cpu.order.contains(&cpu.pass_index("draw").unwrap()));
    assert!(dump::to_dot(&cpu).contains("nothing to draw"));
    let graphics = build().compile(&opts()).unwrap().plan;
    assert!(
        graphics.passes[graphics.pass_index("draw").unwrap()]
            .skipped
            .is_none()
    );
    // Skipped, the pass joins its neighbours' batch; run, it needs the encoder.
    assert!(
        cpu.batches.len() < graphics.batches.len(),
        "{:?} {:?}",
        cpu.batches,
        graphics.batches
    );
    // On a device (lavapipe is a CPU adapter), a frame runs without recording it (its
    // `record` would panic) or timing it: the per-pass profile lists the passes that ran.
    let gpu = meshlight_testing::gpu();
    assert_eq!(
        AdapterClass::of(&gpu.info),
        AdapterClass::Cpu,
        "{:?}",
        gpu.info
    );
    let compiled = build().compile(&CompileOptions::for_gpu(&gpu)).unwrap();
    let mut exec = Executor::new(gpu);
    exec.timing = TimingMode::Passes;
    let stats = exec.execute(&compiled, &Imports::new()).unwrap();
    let ran: Vec<&str> = stats.passes.iter().map(|p| p.name.as_str()).collect();
    assert_eq!(ran, ["make", "use"]);
    assert!(
        stats
            .batches
            .iter()
            .all(|b| !b.passes.contains(&"draw".to_string())),
        "{:?}",
        stats.batches
    );
    exec.finish().unwrap();
    for t in exec.take_gpu_timings().unwrap() {
        assert!(t.passes.iter().all(|(name, _)| name != "draw"), "{t:?}");
    }
}

#[test]
fn an_empty_binding_leaves_an_optional_slot_unbound_and_a_required_one_is_refused() {
    // `side` exists, so `use` would bind it by name.
    let text = FILE.replace(
        "[[pass]]\nname = \"use\"\nstage = \"use\"\nimplementation = \"one\"\nbind = { side = \"side_list\" }",
        "[[resource]]\nname = \"side\"\nkind = \"imported\"\nbuffer = { element = \"u32\", count = 4 }\nusage = [\"STORAGE\"]\n\n[[pass]]\nname = \"use\"\nstage = \"use\"\nimplementation = \"one\"\nbind = { side = \"\" }",
    );
    let p = Pipeline::parse(&text, "edit.toml").unwrap();
    assert_eq!(bound(&plan(&p), "use", "side"), None);
    let by_name =
        Pipeline::parse(&text.replace("bind = { side = \"\" }", ""), "edit.toml").unwrap();
    assert_eq!(
        bound(&plan(&by_name), "use", "side").as_deref(),
        Some("side")
    );
    let required = Pipeline::parse(&text.replace("side = \"\"", "a = \"\""), "edit.toml").unwrap();
    match required.build(&registry()).err() {
        Some(GraphError::UnboundSlot { pass, slot }) => {
            assert_eq!((pass.as_str(), slot.as_str()), ("use", "a"))
        }
        other => panic!("{other:?}"),
    }
}
