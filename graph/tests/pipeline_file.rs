//! Pipeline files: a file-built graph runs with the same result as the code-first one,
//! and wiring mistakes give typed errors naming what to change.

mod support;
use meshlight_graph::file::{Params, Registry, parse_pipeline};
use meshlight_graph::*;
use support::*;

fn registry() -> Registry {
    let mut r = Registry::new();
    r.register("produce", "fill", |p: &Params| {
        p.only(&["count", "k"])?;
        Ok(Arith::fill(p.u32("count", 1000)?, p.u32("k", 1)?))
    });
    r.register("transform", "add", |p: &Params| {
        Ok(Arith::add(p.u32("count", 1000)?, p.u32("k", 0)?))
    });
    r.register("transform", "add_twice", |p: &Params| {
        Ok(AddTwice {
            count: p.u32("count", 1000)?,
            half: p.u32("half", 0)?,
        })
    });
    r
}

const FILE: &str = r#"
name = "arith"

[[resource]]
name = "a"
kind = "transient"
buffer = { element = "u32", count = 1000 }

[[resource]]
name = "result"
kind = "imported"
buffer = { element = "u32", count = 1000 }
usage = ["STORAGE", "COPY_SRC", "COPY_DST"]

[[pass]]
name = "fill"
stage = "produce"
implementation = "fill"
params = { count = 1000, k = 3 }
bind = { output = "a" }

[[pass]]
name = "transform"
stage = "transform"
implementation = "IMPL"
params = { count = 1000, PARAM }
bind = { input = "a", output = "result" }
"#;

fn file(implementation: &str, param: &str) -> String {
    FILE.replace("IMPL", implementation).replace("PARAM", param)
}

fn run(text: &str) -> Vec<u32> {
    let g = parse_pipeline(text, "test.toml", &registry()).unwrap();
    let gpu = gpu();
    let compiled = g.compile(&CompileOptions::for_gpu(&gpu)).unwrap();
    let usage =
        wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC | wgpu::BufferUsages::COPY_DST;
    let result = gpu.buffer_with_data("result", &[0u8; 4000], usage);
    let mut exec = Executor::new(gpu);
    exec.execute(&compiled, &Imports::new().buffer("result", &result))
        .unwrap();
    read_u32s(&exec.gpu, &result, 1000)
}

#[test]
fn file_graph_runs_and_swapping_the_implementation_is_one_line() {
    let a = run(&file("add", "k = 8"));
    let b = run(&file("add_twice", "half = 4"));
    assert_eq!(a, (0..1000).map(|i| i * 3 + 8).collect::<Vec<u32>>());
    assert_eq!(a, b);
}

#[test]
fn wiring_a_slot_the_stage_does_not_have_is_a_typed_error() {
    let text = file("add", "k = 1").replace(
        "bind = { input = \"a\", output = \"result\" }",
        "bind = { inptu = \"a\", output = \"result\" }",
    );
    match parse_pipeline(&text, "test.toml", &registry()) {
        Err(GraphError::UnknownSlot {
            pass,
            slot,
            available,
            ..
        }) => {
            assert_eq!(
                (pass.as_str(), slot.as_str(), available.as_str()),
                ("transform", "inptu", "input, output")
            );
        }
        other => panic!("expected UnknownSlot, got {:?}", other.err()),
    }
}

#[test]
fn wiring_a_resource_of_the_wrong_kind_is_a_typed_error() {
    let text = file("add", "k = 1").replace(
        "buffer = { element = \"u32\", count = 1000 }\n\n[[resource]]\nname = \"result\"",
        "buffer = { element = \"f32\", count = 1000 }\n\n[[resource]]\nname = \"result\"",
    );
    let g = parse_pipeline(&text, "test.toml", &registry()).unwrap();
    match g.compile(&CompileOptions::new(wgpu::Features::empty())) {
        Err(GraphError::DescriptorMismatch {
            pass,
            slot,
            resource,
            ..
        }) => assert_eq!(
            (pass.as_str(), slot.as_str(), resource.as_str()),
            ("fill", "output", "a")
        ),
        other => panic!("expected DescriptorMismatch, got {:?}", other.err()),
    }
}

#[test]
fn unknown_implementation_names_the_known_ones() {
    match parse_pipeline(&file("add_thrice", "k = 1"), "test.toml", &registry()) {
        Err(GraphError::UnknownImplementation { known, .. }) => assert_eq!(known, "add, add_twice"),
        other => panic!("{:?}", other.err()),
    }
}

#[test]
fn bad_parameters_and_syntax_are_typed_errors() {
    match parse_pipeline(&file("add", "k = -1"), "test.toml", &registry()) {
        Err(GraphError::Parameter { pass, message }) => {
            assert_eq!(pass, "transform");
            assert!(message.contains("`k`"), "{message}");
        }
        other => panic!("{:?}", other.err()),
    }
    let misspelt = FILE
        .replace(
            "params = { count = 1000, k = 3 }",
            "params = { count = 1000, kk = 3 }",
        )
        .replace("IMPL", "add")
        .replace("PARAM", "k = 1");
    assert!(matches!(
        parse_pipeline(&misspelt, "t.toml", &registry()),
        Err(GraphError::Parameter { .. })
    ));
    match parse_pipeline("[[pass]]\nname = 3", "broken.toml", &registry()) {
        Err(GraphError::PipelineFile { file, .. }) => assert_eq!(file, "broken.toml"),
        other => panic!("{:?}", other.err()),
    }
}

/// `[params]` overridden by the caller reach buffer counts, texture sizes and `"$name"`
/// pass parameters; a misspelt override or reference is an error naming it.
#[test]
fn caller_parameters_size_textures_and_reach_pass_parameters() {
    use meshlight_graph::file::Pipeline;
    let text = include_str!("pipelines/caller_parameters.toml");
    let mut pipeline = Pipeline::parse(text, "t.toml").unwrap();
    pipeline.set_param("n", 500).unwrap();
    pipeline.set_param("width", 16).unwrap();
    let g = pipeline.build(&registry()).unwrap();
    let plan = g
        .compile(&CompileOptions::new(wgpu::Features::all()))
        .unwrap()
        .plan;
    let json = dump::to_json(&plan, None);
    assert!(
        json.contains("\"width\": 16") || json.contains("\"width\":16"),
        "{json}"
    );
    let a = plan.resources.iter().find(|r| r.info.name == "a").unwrap();
    assert!(
        format!("{a:?}").contains("2000"),
        "500 u32 = 2000 bytes: {a:?}"
    );
    let Err(e) = Pipeline::parse(text, "t.toml")
        .unwrap()
        .set_param("widht", 16)
    else {
        panic!("a misspelt override was accepted")
    };
    assert!(e.to_string().contains("`widht`"), "{e}");
    let Err(e) = parse_pipeline(&text.replace("$n", "$m"), "t.toml", &registry()) else {
        panic!("an unknown $ reference was accepted")
    };
    assert!(e.to_string().contains("`$m`"), "{e}");
    let Err(e) = parse_pipeline(
        &text.replace("width_param = \"width\"", "width_param = \"w\""),
        "t.toml",
        &registry(),
    ) else {
        panic!("an unknown width parameter was accepted")
    };
    assert!(e.to_string().contains("names no entry"), "{e}");
}

/// A view set: entries with `views` stand for one per view, `{view}` their number (a
/// param that is `{view}` alone becomes the number itself: view `k` fills with `i * k`).
const VIEWS: &str = r#"
[views]
cascades = COUNT

[[resource]]
name = "a_{view}"
kind = "transient"
views = "cascades"
buffer = { element = "u32", count = 1000 }

[[resource]]
name = "result"
kind = "imported"
buffer = { element = "u32", count = 1000 }
usage = ["STORAGE", "COPY_SRC", "COPY_DST"]

[[pass]]
name = "fill_{view}"
stage = "produce"
implementation = "fill"
views = "cascades"
params = { count = 1000, k = "{view}" }
bind = { output = "a_{view}" }

[[pass]]
name = "transform"
stage = "transform"
implementation = "add"
params = { count = 1000, k = 1 }
bind = { input = "LAST", output = "result" }
"#;

/// The plan of a view-set file, compiled without an adapter.
fn plan_of(text: &str) -> meshlight_graph::Plan {
    parse_pipeline(text, "views.toml", &registry())
        .unwrap()
        .compile(&CompileOptions::new(wgpu::Features::empty()))
        .unwrap()
        .plan
}

/// The plan's passes, in order.
fn pass_names(plan: &meshlight_graph::Plan) -> Vec<&str> {
    plan.passes.iter().map(|p| p.name.as_str()).collect()
}

#[test]
fn a_view_set_writes_its_entries_out_once_per_view() {
    let text = VIEWS.replace("COUNT", "3").replace("LAST", "a_2");
    let plan = plan_of(&text);
    assert_eq!(
        pass_names(&plan),
        ["fill_0", "fill_1", "fill_2", "transform"]
    );
    for k in 0..3 {
        assert!(
            plan.resources
                .iter()
                .any(|r| r.info.name == format!("a_{k}")),
            "a_{k} was not declared"
        );
    }
    // The file runs: the last view's buffer (filled with `k = 2`) feeds the transform.
    assert_eq!(
        run(&text),
        (0..1000).map(|i| i * 2 + 1).collect::<Vec<u32>>()
    );
    // No views: the set's entries are left out, and a binding to one is refused by name.
    let none = VIEWS.replace("COUNT", "0").replace("LAST", "a_0");
    match parse_pipeline(&none, "views.toml", &registry()) {
        Err(GraphError::UnknownResource { resource, .. }) => assert_eq!(resource, "a_0"),
        other => panic!("{:?}", other.err()),
    }
}

#[test]
fn view_set_mistakes_name_the_entry_and_what_to_change() {
    let base = VIEWS.replace("COUNT", "2").replace("LAST", "a_1");
    let refused = |text: &str| match parse_pipeline(text, "views.toml", &registry())
        .and_then(|g| g.compile(&CompileOptions::new(wgpu::Features::empty())))
    {
        Err(e) => e.to_string(),
        Ok(_) => panic!("accepted:\n{text}"),
    };
    let e = refused(&base.replace(
        "views = \"cascades\"\nparams",
        "views = \"cascdes\"\nparams",
    ));
    assert!(
        e.contains("view set `cascdes`, which [views] does not declare"),
        "{e}"
    );
    // (what the file changes, what the error must say)
    let mistakes = [
        (
            ("name = \"fill_{view}\"", "name = \"fill\""),
            "pass `fill` runs once for the whole view set `cascades` (its name holds no `{view}`), so `{view}` in its bindings",
        ),
        (
            ("name = \"a_{view}\"", "name = \"a\""),
            "resource `a` runs over view set `cascades`, but its name holds no `{view}`",
        ),
        (
            ("[views]", "[params]\ncascades = 3\n\n[views]"),
            "`cascades` is both a size parameter ([params]) and a view set ([views])",
        ),
        (
            ("count = 1000, k = 1 }", "count = 1000, k = \"$cascade\" }"),
            "refers to `$cascade`, which neither [params] nor [views] declares",
        ),
        (
            ("bind = { input = \"a_1\"", "bind = { input = \"a_{view}\""),
            "pass `transform` writes `{view}` but runs over no view set",
        ),
    ];
    for ((from, to), want) in mistakes {
        let e = refused(&base.replace(from, to));
        assert!(e.contains(want), "{e}");
    }
    // A pass supplied a frame input it does not read.
    let e = refused(&base.replace(
        "params = { count = 1000, k = 1 }",
        "params = { count = 1000, k = 1 }\ninputs = { view = \"view_0\" }",
    ));
    assert!(
        e.contains("reads no frame input `view` (it reads: none)"),
        "{e}"
    );
}

/// A pass over a view set whose name holds no `{view}` runs once for the whole set, and
/// reads the set's size as `"$cascades"`: here `transform` adds the number of views.
#[test]
fn a_pass_for_the_whole_view_set_runs_once_and_reads_its_size() {
    for count in [2u32, 3] {
        let text = VIEWS
            .replace("COUNT", &count.to_string())
            .replace("LAST", "a_1")
            .replace(
                "name = \"transform\"\nstage",
                "name = \"transform\"\nviews = \"cascades\"\nstage",
            )
            .replace("count = 1000, k = 1 }", "count = 1000, k = \"$cascades\" }");
        let mut want: Vec<String> = (0..count).map(|k| format!("fill_{k}")).collect();
        want.push("transform".into());
        assert_eq!(pass_names(&plan_of(&text)), want);
        assert_eq!(
            run(&text),
            (0..1000).map(|i| i + count).collect::<Vec<u32>>()
        );
    }
}

/// Consecutive entries over one view set run view by view: view 0's passes, then view
/// 1's. So the views may share a list each refills: here every view fills `shared` with
/// `i * k` and copies it out before the next view refills it.
#[test]
fn consecutive_entries_over_a_view_set_run_view_by_view() {
    // The view set above, each view's fill writing one `shared` list that a copy per
    // view takes out.
    let text = VIEWS
        .replace("COUNT", "3")
        .replace("LAST", "a_1")
        .replace(
            "[[resource]]\nname = \"result\"",
            "[[resource]]\nname = \"shared\"\nkind = \"transient\"\nbuffer = { element = \"u32\", count = 1000 }\n\n[[resource]]\nname = \"result\"",
        )
        .replace(
            "bind = { output = \"a_{view}\" }",
            "bind = { output = \"shared\" }\n\n[[pass]]\nname = \"copy_{view}\"\nstage = \"transform\"\nimplementation = \"add\"\nviews = \"cascades\"\nparams = { count = 1000, k = 0 }\nbind = { input = \"shared\", output = \"a_{view}\" }",
        );
    let text = text.as_str();
    assert_eq!(
        pass_names(&plan_of(text)),
        [
            "fill_0",
            "copy_0",
            "fill_1",
            "copy_1",
            "fill_2",
            "copy_2",
            "transform"
        ]
    );
    // View 1's copy holds view 1's fill, not the last view's.
    assert_eq!(run(text), (0..1000).map(|i| i + 1).collect::<Vec<u32>>());
}

/// A pass left out of one frame (`FrameData::skip`) records nothing: the imported
/// buffer it writes keeps what it held; the next frame runs it again. A name that is no
/// pass is refused by name.
#[test]
fn a_pass_left_out_of_a_frame_records_nothing_and_an_unknown_name_is_refused() {
    let g = parse_pipeline(&file("add", "k = 8"), "test.toml", &registry()).unwrap();
    let gpu = gpu();
    let compiled = g.compile(&CompileOptions::for_gpu(&gpu)).unwrap();
    let usage =
        wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC | wgpu::BufferUsages::COPY_DST;
    let stale: Vec<u8> = (0..1000u32).flat_map(|i| (i + 5).to_le_bytes()).collect();
    let result = gpu.buffer_with_data("result", &stale, usage);
    let imports = Imports::new().buffer("result", &result);
    let mut exec = Executor::new(gpu);
    let mut skip = FrameData::new();
    skip.skip("transform");
    let stats = exec.execute_frame(&compiled, &imports, &skip).unwrap();
    exec.finish().unwrap();
    assert!(!stats.passes.iter().any(|p| p.name == "transform"));
    assert_eq!(
        read_u32s(&exec.gpu, &result, 1000),
        (0..1000).map(|i| i + 5).collect::<Vec<u32>>()
    );
    exec.execute_frame(&compiled, &imports, &FrameData::new())
        .unwrap();
    exec.finish().unwrap();
    assert_eq!(
        read_u32s(&exec.gpu, &result, 1000),
        (0..1000).map(|i| i * 3 + 8).collect::<Vec<u32>>()
    );
    let mut unknown = FrameData::new();
    unknown.skip("transfrom");
    let e = exec
        .execute_frame(&compiled, &imports, &unknown)
        .unwrap_err();
    assert!(e.to_string().contains("`transfrom`"), "{e}");
}
