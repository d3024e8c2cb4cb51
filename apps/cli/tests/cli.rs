//! The `meshlight` binary: graph dumps of a shipped pipeline file, and typed errors for a
//! miswired one.

mod common;

use common::{ROOT, command, meshlight, scratch};
use std::path::Path;

/// `render` of `instances` spots at `width` × `height`, for more flags to follow.
fn render_spot<'a>(instances: &'a str, width: &'a str, height: &'a str) -> Vec<&'a str> {
    vec![
        "render",
        "--mesh",
        "assets/meshes/spot.obj",
        "--instances",
        instances,
        "--width",
        width,
        "--height",
        height,
    ]
}

/// One spot at 16×16: the smallest render that still writes a PNG.
fn small_render<'a>() -> Vec<&'a str> {
    render_spot("1", "16", "16")
}

/// The environment entry that names an adapter no machine has: a command that asks for
/// one fails with exit 3, so a run that ends otherwise did not get that far.
fn no_adapter() -> (&'static str, &'static Path) {
    ("MESHLIGHT_ADAPTER", Path::new("no adapter is called this"))
}

/// [`meshlight`], failing the test with its output unless it succeeds.
fn meshlight_ok(args: &[&str]) -> std::process::Output {
    let out = meshlight(args);
    assert!(
        out.status.success(),
        "meshlight {}: {}{}",
        args.join(" "),
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    out
}

/// The text of a file of the repository.
fn repository_file(path: &str) -> String {
    std::fs::read_to_string(Path::new(ROOT).join(path)).unwrap()
}

#[test]
fn graph_dumps_the_shipped_pipelines_in_every_format() {
    for (file, pass) in [
        ("pipelines/prefix_sum.toml", "scan"),
        ("pipelines/virtual_geometry.toml", "sw_raster"),
        ("pipelines/brute_force.toml", "brute_force"),
    ] {
        dumps_in_every_format(file, pass);
    }
}

fn dumps_in_every_format(file: &str, pass: &str) {
    for (format, marker) in [
        ("dot", "digraph meshlight"),
        ("json", "\"order\""),
        ("mermaid", "flowchart LR"),
        ("html", "<!DOCTYPE html>"),
    ] {
        let out = meshlight_ok(&["graph", "--pipeline", file, "--format", format]);
        let text = String::from_utf8(out.stdout).unwrap();
        assert!(
            text.contains(marker) && text.contains(pass),
            "{file} {format}:\n{text}"
        );
    }
}

#[test]
fn a_miswired_pipeline_file_is_a_clear_error() {
    let dir = scratch("miswired");
    let text = repository_file("pipelines/prefix_sum.toml");
    let bad = dir.join("bad.toml");
    std::fs::write(
        &bad,
        text.replace(
            "bind = { input = \"counts\"",
            "bind = { counts = \"counts\"",
        ),
    )
    .unwrap();
    let out = meshlight(&["graph", "--pipeline", bad.to_str().unwrap()]);
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("has no slot `counts`") && err.contains("input"),
        "{err}"
    );
}

#[test]
fn every_command_has_help() {
    for cmd in ["render", "graph", "bench", "bake", "inspect"] {
        let out = meshlight(&[cmd, "--help"]);
        assert!(out.status.success() && !out.stdout.is_empty(), "{cmd}");
    }
}

#[test]
fn render_draws_a_mesh_file_through_the_shipped_pipeline_and_reports_its_counters() {
    let dir = scratch("render");
    let (png, html) = (dir.join("spot.png"), dir.join("spot.html"));
    let mut args = render_spot("4", "96", "64");
    args.extend([
        "--view",
        "lod",
        "--pipeline",
        "pipelines/virtual_geometry.toml",
        "-o",
        png.to_str().unwrap(),
        "--html",
        html.to_str().unwrap(),
    ]);
    let out = meshlight_ok(&args);
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(stdout.contains("clusters visible (LOD cut)"), "{stdout}");
    // The default shadow: held cascades, one walk for the camera and the cascades.
    assert!(stdout.contains("held 0.125"), "{stdout}");
    assert!(
        stdout.contains("one walk serves the camera and the cascades"),
        "{stdout}"
    );
    let page = std::fs::read_to_string(&html).unwrap();
    assert!(page.contains("sw_raster") && page.contains("triangles rasterised"));
    let decoder = png::Decoder::new(std::io::BufReader::new(std::fs::File::open(&png).unwrap()));
    let info = decoder.read_info().unwrap();
    assert_eq!((info.info().width, info.info().height), (96, 64));
    // A misspelt view is refused with the names that exist.
    let out = meshlight(&["render", "--view", "normals"]);
    assert!(!out.status.success());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("clusters") && err.contains("shaded"), "{err}");
}

/// `render --trace` writes the frame's GPU timings as Chrome trace JSON: one complete
/// event per batch the report lists, each naming its passes; and the report lists no
/// pass without a GPU time of its own (GPU: lavapipe, which has timestamps).
#[test]
fn render_writes_a_chrome_trace_with_an_event_per_batch() {
    let dir = scratch("trace");
    let (png, trace) = (dir.join("spot.png"), dir.join("frame.trace.json"));
    let mut args = render_spot("4", "96", "64");
    args.extend([
        "-o",
        png.to_str().unwrap(),
        "--trace",
        trace.to_str().unwrap(),
    ]);
    let out = meshlight_ok(&args);
    let stdout = String::from_utf8_lossy(&out.stdout);
    let batches = stdout
        .lines()
        .filter(|l| l.trim_start().starts_with("batch ") && l.contains("µs GPU"))
        .count();
    assert!(batches >= 2, "{stdout}");
    assert!(!stdout.contains("no timestamps"), "{stdout}");
    let text = std::fs::read_to_string(&trace).expect("the trace was written");
    let json: serde_json::Value = serde_json::from_str(&text).expect("the trace is JSON");
    let events = json["traceEvents"].as_array().expect("traceEvents");
    let complete: Vec<_> = events.iter().filter(|e| e["ph"] == "X").collect();
    assert_eq!(complete.len(), batches, "{text}");
    assert!(
        complete
            .iter()
            .all(|e| e["dur"].is_number() && e["ts"].is_number())
    );
    assert!(
        complete.iter().any(|e| e["args"]["passes"]
            .as_str()
            .is_some_and(|p| p.contains("sw_raster"))),
        "{text}"
    );
}

/// `meshlight` with extra environment variables.
fn meshlight_env(args: &[&str], env: &[(&str, &Path)]) -> std::process::Output {
    let mut cmd = command(args);
    for (k, v) in env {
        cmd.env(k, v);
    }
    cmd.output().expect("runs")
}

/// Each bounded number is refused with the number and the limit, before a mesh is baked
/// (the cache stays empty) or an adapter is requested (one that cannot exist is named,
/// which would fail with the no-adapter exit code 3 if it were looked for).
#[test]
fn render_refuses_numbers_it_cannot_hold_before_baking_or_asking_for_an_adapter() {
    let dir = scratch("bounds");
    let cache = dir.join("cache");
    let max_lights = meshlight_cli::render_bounds::max_lights().to_string();
    let max_instances = meshlight_cli::render_bounds::max_instances().to_string();
    let max_clusters = meshlight_cli::render_bounds::max_clusters().to_string();
    let max_segments = meshlight_cli::render_bounds::MAX_RESIDENT_SEGMENTS;
    let cases: &[(&[&str], &str)] = &[
        (
            &["--lights", "4294967295"],
            &format!("--lights 4294967295 is outside 0..={max_lights}"),
        ),
        (
            &["--segments", "100000"],
            &format!("--segments 100000 is outside 3..={max_segments}"),
        ),
        (
            &["--segments", "0"],
            &format!("--segments 0 is outside 3..={max_segments}"),
        ),
        (
            &["--segments", "1"],
            &format!("--segments 1 is outside 3..={max_segments}"),
        ),
        (
            &["--instances", "4294967295"],
            &format!("--instances 4294967295 is outside 0..={max_instances}"),
        ),
        (&["--width", "0"], "--width 0 is outside 1..=8192"),
        (
            &["--height", "100000"],
            "--height 100000 is outside 1..=8192",
        ),
        (
            &["--clusters", "0"],
            &format!("--clusters 0 is outside 1..={max_clusters}"),
        ),
        (&["--slots", "0"], "--slots 0 is outside 1..="),
    ];
    for (args, expected) in cases {
        let mut all = vec!["render"];
        all.extend_from_slice(args);
        let out = meshlight_env(&all, &[("MESHLIGHT_CACHE_DIR", &cache), no_adapter()]);
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(1), "{args:?}: {err}");
        assert!(err.contains(expected), "{args:?}: {err}");
        assert!(!err.contains("panicked"), "{err}");
        assert!(!cache.exists(), "{args:?} baked before refusing");
    }
    // At a bound, the check passes and the render goes on to ask for the adapter.
    let out = meshlight_env(
        &[
            "render",
            "--segments",
            "3",
            "--instances",
            "0",
            "--lights",
            &max_lights,
            "--width",
            "8",
            "--height",
            "8",
        ],
        &[("MESHLIGHT_CACHE_DIR", &cache), no_adapter()],
    );
    assert_eq!(
        out.status.code(),
        Some(3),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// A pipeline file that is a device is refused by `render` and `graph` without reading
/// it; an output that cannot be written names its path, before rendering where it can.
#[test]
fn inputs_and_outputs_that_cannot_be_used_are_named() {
    for cmd in ["render", "graph"] {
        let out = meshlight(&[cmd, "--pipeline", "/dev/zero"]);
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success(), "{cmd}");
        assert!(
            err.contains("/dev/zero") && err.contains("not a regular file"),
            "{cmd}: {err}"
        );
    }
    let out = meshlight(&[
        "graph",
        "--pipeline",
        "pipelines/prefix_sum.toml",
        "-o",
        "/dev/full",
    ]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success());
    assert!(err.contains("cannot write /dev/full"), "{err}");
    // Standard output on a full device: an error naming it, not a panic.
    let full = std::fs::OpenOptions::new()
        .write(true)
        .open("/dev/full")
        .unwrap();
    let out = command(&["graph", "--pipeline", "pipelines/prefix_sum.toml"])
        .stdout(full)
        .output()
        .expect("runs");
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{err}");
    assert!(
        err.contains("cannot write standard output") && !err.contains("panicked"),
        "{err}"
    );
    // The directory of the output cannot be made: refused before any rendering.
    let out = meshlight_env(
        &["render", "-o", "/dev/null/out/image.png"],
        &[no_adapter()],
    );
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{err}");
    assert!(
        err.contains("cannot create the directory /dev/null/out"),
        "{err}"
    );
}

/// `bench`'s outputs: a directory is refused before any scenario runs, and a full
/// device fails naming it, never a bare OS error.
#[test]
fn bench_outputs_that_cannot_be_written_are_named() {
    let dir = scratch("bench-outputs");
    let start = std::time::Instant::now();
    let out = meshlight(&[
        "bench",
        "--scenario",
        "virtual-geometry",
        "--json",
        dir.to_str().unwrap(),
    ]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{err}");
    assert!(
        err.contains(dir.to_str().unwrap()) && err.contains("directory"),
        "{err}"
    );
    assert!(
        start.elapsed() < std::time::Duration::from_secs(20),
        "refused only after {:?}",
        start.elapsed()
    );
    let rows = dir.join("rows.json");
    std::fs::write(&rows, "[]").unwrap();
    let out = meshlight(&[
        "bench",
        "--from-json",
        rows.to_str().unwrap(),
        "--html",
        "/dev/full",
    ]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{err}");
    assert!(err.contains("cannot write /dev/full"), "{err}");
}

/// A PNG small enough to sit in the write buffer until the end used to be lost there
/// with exit 0 and "rendered" printed (GPU: lavapipe).
#[test]
fn rendering_to_a_full_device_fails_naming_it() {
    let mut args = small_render();
    args.extend(["-o", "/dev/full"]);
    let out = meshlight(&args);
    let err = String::from_utf8_lossy(&out.stderr);
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert_eq!(out.status.code(), Some(1), "{stdout}{err}");
    assert!(err.contains("cannot write /dev/full"), "{err}");
    assert!(!stdout.contains("rendered"), "{stdout}");
}

/// The exit status of a process `meshlight args` whose standard output is a pipe
/// nobody reads (its read end closed before it starts), and its standard error.
fn with_closed_stdout(args: &[&str]) -> (std::process::ExitStatus, String) {
    let (reader, writer) = std::io::pipe().unwrap();
    drop(reader);
    let out = command(args)
        .stdout(writer)
        .stderr(std::process::Stdio::piped())
        .output()
        .expect("runs");
    (
        out.status,
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

/// `meshlight inspect … | head -1` and `meshlight graph … | head -1`: the writer ends
/// as a broken pipe ends any tool (by SIGPIPE), with nothing on standard error.
#[cfg(unix)]
#[test]
fn a_closed_stdout_ends_quietly_as_a_broken_pipe() {
    use std::os::unix::process::ExitStatusExt;
    let dir = scratch("pipe");
    let asset = dir.join("knot.mlasset");
    meshlight_ok(&[
        "bake",
        "procedural",
        "--segments",
        "4",
        "-o",
        asset.to_str().unwrap(),
    ]);
    for args in [
        vec!["inspect", asset.to_str().unwrap()],
        vec!["graph", "--pipeline", "pipelines/virtual_geometry.toml"],
    ] {
        let (status, err) = with_closed_stdout(&args);
        assert_eq!(
            status.signal(),
            Some(libc::SIGPIPE),
            "{args:?}: {status:?} {err}"
        );
        assert!(err.is_empty(), "{args:?}: {err}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// An asset whose structure is sound but whose DAG is not (a group's error below its
/// child's): `inspect` rejects it, and `render` refuses it with the same message before
/// anything reaches the GPU.
#[test]
fn render_refuses_an_asset_that_inspect_rejects_with_the_same_message() {
    use meshlight::scene::{BuildOptions, build_asset, procedural_mesh};
    let dir = scratch("damaged-dag");
    let built = build_asset(&procedural_mesh(8), &BuildOptions::default(), &mut |_| {}).unwrap();
    let bad = dir.join("bad.mlasset");
    meshlight::scene::damaged::error_below_child(&built)
        .unwrap()
        .save(&bad)
        .unwrap();
    let bad = bad.to_str().unwrap();
    let inspect = meshlight(&["inspect", bad]);
    assert!(!inspect.status.success());
    let render = meshlight(&[
        "render",
        "--mesh",
        bad,
        "--width",
        "32",
        "--height",
        "32",
        "-o",
        &dir.join("bad.png").to_string_lossy(),
    ]);
    assert!(!render.status.success());
    let said = |o: &std::process::Output| {
        let text = String::from_utf8_lossy(&o.stderr).to_string();
        text.lines()
            .find(|l| l.contains("below child"))
            .map(|l| l[l.find(bad).unwrap_or(0)..].to_string())
            .unwrap_or_else(|| panic!("no DAG error in: {text}"))
    };
    assert_eq!(said(&render), said(&inspect));
    assert!(!dir.join("bad.png").exists());
}

/// The drivers' window-system code complains on standard error when XDG_RUNTIME_DIR is
/// unset or not an absolute path; the library keeps that line off standard error while
/// it enumerates adapters, so a run says nothing of it (GPU: lavapipe).
#[test]
fn an_unset_or_invalid_runtime_dir_is_not_complained_about() {
    for value in [None, Some(""), Some("relative/dir"), Some("/no/such/dir")] {
        let mut cmd = command(&["info"]);
        match value {
            None => cmd.env_remove("XDG_RUNTIME_DIR"),
            Some(v) => cmd.env("XDG_RUNTIME_DIR", v),
        };
        let out = cmd.output().expect("runs");
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(out.status.success(), "{value:?}: {err}");
        assert!(!err.contains("XDG_RUNTIME_DIR"), "{value:?}: {err}");
    }
}

/// `bench --help` names every scenario `meshlight bench` runs.
#[test]
fn bench_help_lists_every_scenario() {
    let out = meshlight(&["bench", "--help"]);
    let help = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success());
    for scenario in meshlight_bench::ALL {
        assert!(help.contains(scenario), "{scenario} missing:\n{help}");
    }
}

/// `render --help` names every view the resolve pass has, and says what the size is.
#[test]
fn render_help_lists_the_views_and_the_size() {
    let out = meshlight(&["render", "--help"]);
    let help = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success());
    for view in meshlight::resolve::DebugView::ALL {
        assert!(help.contains(view.name()), "{view:?} missing:\n{help}");
    }
    assert!(
        help.contains("Image width in pixels") && help.contains("Image height in pixels"),
        "{help}"
    );
}

/// `inspect` on a mesh file suggests baking it beside itself, never over itself.
#[test]
fn inspect_of_a_mesh_suggests_a_bake_that_keeps_the_mesh() {
    let out = meshlight(&["inspect", "assets/meshes/spot.obj"]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success());
    assert!(
        err.contains("meshlight bake assets/meshes/spot.obj -o assets/meshes/spot.mlasset"),
        "{err}"
    );
    assert!(!err.contains("-o assets/meshes/spot.obj"), "{err}");
}

/// An image path naming another format is refused, naming the path and the fix, before
/// an adapter is asked for (one that cannot exist is named: exit 3 if it were).
#[test]
fn render_refuses_an_output_that_is_not_png() {
    let dir = scratch("not-png");
    for name in ["x.jpg", "x.PNG.webp"] {
        let path = dir.join(name);
        let out = meshlight_env(&["render", "-o", path.to_str().unwrap()], &[no_adapter()]);
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(1), "{name}: {err}");
        assert!(
            err.contains(&path.display().to_string())
                && err.contains("PNG only")
                && err.contains(&path.with_extension("png").display().to_string()),
            "{name}: {err}"
        );
        assert!(!path.exists());
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// Without --html, the page beside the image named like it (an earlier render's report)
/// is rewritten for this render; where there is none, none is made (GPU: lavapipe).
#[test]
fn render_keeps_the_report_beside_the_image_in_step() {
    let dir = scratch("report");
    let (png, html) = (dir.join("a.png"), dir.join("a.html"));
    std::fs::write(&html, "an earlier render's report").unwrap();
    let mut args = small_render();
    args.push("-o");
    args.push(png.to_str().unwrap());
    let out = meshlight_ok(&args);
    let stdout = String::from_utf8_lossy(&out.stdout);
    let page = std::fs::read_to_string(&html).unwrap();
    assert!(
        page.contains("<!DOCTYPE html>") && page.contains("sw_raster"),
        "{page}"
    );
    assert!(
        stdout.contains(&format!("graph: {}", html.display())),
        "{stdout}"
    );
    let other = dir.join("b.png");
    let mut args = small_render();
    args.extend(["-o", other.to_str().unwrap()]);
    let out = meshlight(&args);
    assert!(out.status.success());
    assert!(other.exists() && !dir.join("b.html").exists());
    let _ = std::fs::remove_dir_all(&dir);
}

/// The pixels of a PNG.
fn pixels(path: &Path) -> Vec<u8> {
    let decoder = png::Decoder::new(std::io::BufReader::new(std::fs::File::open(path).unwrap()));
    let mut reader = decoder.read_info().unwrap();
    let mut buf = vec![0; reader.output_buffer_size().unwrap()];
    let info = reader.next_frame(&mut buf).unwrap();
    buf.truncate(info.buffer_size());
    buf
}

/// `render --pipeline`: a file's own `view` and `slots` stand when --view and --slots
/// are not given, and the flags win over them when given; the shipped file renders with the default lights flag (none)
/// and refuses lights asked for (GPU: lavapipe).
#[test]
fn render_pipeline_settings_yield_only_to_flags_given() {
    let dir = scratch("precedence");
    let shipped = "pipelines/virtual_geometry.toml";
    let text = repository_file(shipped);
    assert!(text.contains("view = \"shaded\""));
    let lod_file = dir.join("lod.toml");
    std::fs::write(
        &lod_file,
        text.replace("view = \"shaded\"", "view = \"lod\""),
    )
    .unwrap();
    let lod_file = lod_file.to_str().unwrap();
    // Spot four times at 48 × 32 through `file`, with `extra` flags: the image's pixels
    // and the run's report.
    let render = |file: &str, extra: &[&str], name: &str| {
        let png = dir.join(name);
        let mut args = render_spot("4", "48", "32");
        args.extend(["--pipeline", file, "-o", png.to_str().unwrap()]);
        args.extend(extra);
        let out = meshlight_ok(&args);
        (
            pixels(&png),
            String::from_utf8_lossy(&out.stdout).to_string(),
        )
    };
    let shaded = render(shipped, &[], "shaded.png").0;
    let lod = render(shipped, &["--view", "lod"], "lod.png").0;
    assert_ne!(shaded, lod, "the two views should differ");
    // The file's view stands without --view …
    assert!(render(lod_file, &[], "file-lod.png").0 == lod);
    // … and --view wins over it.
    assert!(render(lod_file, &["--view", "shaded"], "flag-shaded.png").0 == shaded);
    // The same both ways for the list sizes: a file's `slots` stands without --slots
    // (two slots: the frame has to grow them) and --slots wins over it.
    assert!(text.contains("slots = 262144"));
    let small_file = dir.join("small.toml");
    std::fs::write(&small_file, text.replace("slots = 262144", "slots = 2")).unwrap();
    let small_file = small_file.to_str().unwrap();
    let kept = render(small_file, &["--lights", "0"], "lists.png").1;
    assert!(kept.contains("the lists grew (slots 2 → "), "{kept}");
    let flagged = render(
        small_file,
        &["--lights", "0", "--slots", "262144"],
        "lists.png",
    )
    .1;
    assert!(!flagged.contains("the lists grew"), "{flagged}");
    // Lights asked for with a file that clusters none (the one-pass frame with its
    // light clustering taken out) are refused, naming the file and the fix.
    let mut unlit = meshlight::graph::file::Pipeline::parse(
        include_str!("../../../pipelines/virtual_geometry_one_pass.toml"),
        "one_pass.toml",
    )
    .unwrap();
    let stages = meshlight_light_clustering::frame_graph::STAGES;
    unlit
        .remove_passes(&meshlight::registry(), |p| {
            stages.contains(&p.stage.as_str())
        })
        .unwrap();
    let unlit_file = dir.join("unlit.toml");
    std::fs::write(&unlit_file, unlit.to_toml()).unwrap();
    let unlit_file = unlit_file.to_str().unwrap();
    let out = meshlight(&[
        "render",
        "--pipeline",
        unlit_file,
        "--lights",
        "8",
        "--instances",
        "4",
    ]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{err}");
    assert!(
        err.contains(unlit_file) && err.contains("--lights 0"),
        "{err}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// The default scene (at a small viewport: the light grid's size is fixed, so its lists
/// fill the same) starts with lists large enough: one frame, no growth (GPU: lavapipe).
#[test]
fn the_default_render_needs_no_list_to_grow() {
    let dir = scratch("default");
    let png = dir.join("default.png");
    let out = meshlight(&[
        "render",
        "--width",
        "160",
        "--height",
        "90",
        "-o",
        png.to_str().unwrap(),
    ]);
    let (stdout, stderr) = (
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr),
    );
    assert!(out.status.success(), "{stdout}{stderr}");
    assert!(stdout.contains("point lights clustered"), "{stdout}");
    assert!(!stderr.contains("wanted but the list holds"), "{stderr}");
    assert!(!stdout.contains("the lists grew"), "{stdout}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// The shipped pipeline file renders the default image: the default scene with its
/// lights, clustered by the file's own passes, pixel for pixel the frame built in code;
/// with `--lights 0` both render the field without them (GPU: lavapipe).
#[test]
fn the_shipped_pipeline_renders_the_default_image() {
    let dir = scratch("shipped");
    let render = |extra: &[&str], name: &str| {
        let png = dir.join(name);
        let mut args = vec!["render", "--width", "96", "--height", "64", "-o"];
        args.push(png.to_str().unwrap());
        args.extend(extra);
        meshlight_ok(&args);
        pixels(&png)
    };
    let file = ["--pipeline", "pipelines/virtual_geometry.toml"];
    let code = render(&[], "code.png");
    assert!(
        render(&file, "file.png") == code,
        "the shipped file's image differs"
    );
    let unlit = render(&["--lights", "0"], "code-unlit.png");
    assert!(unlit != code, "the lights should show");
    assert!(render(&[&file[..], &["--lights", "0"]].concat(), "file-unlit.png") == unlit);
    let _ = std::fs::remove_dir_all(&dir);
}

/// `bench --from-json … --html`: the saved GPU rows under docs/ drawn as charts without a
/// GPU; a file that is not a list of rows is named with what to give instead.
#[test]
fn bench_charts_saved_rows_and_names_a_file_it_cannot_read() {
    let dir = scratch("bench-html");
    let page = dir.join("charts.html");
    let charts_of = |rows: &'static str| {
        [
            "bench",
            "--from-json",
            rows,
            "--html",
            page.to_str().unwrap(),
        ]
    };
    meshlight_ok(&charts_of("docs/bench-h200-vg2.json"));
    let html = std::fs::read_to_string(&page).unwrap();
    assert!(html.contains("<h2>vg-scale</h2>") && html.contains("<polyline"));
    assert!(html.contains("GPU time per pass"));
    let out = meshlight(&charts_of("Cargo.toml"));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success());
    assert!(
        err.contains("Cargo.toml") && err.contains("--json"),
        "{err}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// Every file of rows under docs/ draws, as BENCHMARKS says it does, those with values
/// `--json` wrote as `null` (not finite: a PSNR of +∞, a pass a frame did not run) too.
#[test]
fn bench_charts_every_saved_file_of_rows() {
    let dir = scratch("bench-html-every");
    let page = dir.join("charts.html");
    let mut files: Vec<String> = std::fs::read_dir(format!("{ROOT}/docs"))
        .unwrap()
        .map(|e| format!("docs/{}", e.unwrap().file_name().to_str().unwrap()))
        .filter(|p| p.ends_with(".json"))
        .collect();
    files.sort();
    assert!(files.len() >= 10, "{files:?}");
    let mut args = vec!["bench"];
    for f in &files {
        args.extend(["--from-json", f.as_str()]);
    }
    args.extend(["--html", page.to_str().unwrap()]);
    meshlight_ok(&args);
    let html = std::fs::read_to_string(&page).unwrap();
    assert!(
        html.contains(">not a number<"),
        "no null value among the files"
    );
    assert!(!html.contains("NaN"));
    let _ = std::fs::remove_dir_all(&dir);
}

/// `bake`'s options are bounded where they are parsed: a bad value is clap's usage error
/// (exit 2) naming the option, before any mesh is read; a good one gets past parsing to
/// the missing file (exit 1).
#[test]
fn bake_refuses_options_out_of_bounds_when_parsing() {
    use meshlight::scene::load::DEFAULT_TRIANGLE_BUDGET;
    use meshlight::scene::mesh::MAX_TRIANGLES;
    let bake = |extra: &[&str]| {
        let mut args = vec!["bake", "no-such-mesh.gltf", "-o", "x.mlasset"];
        args.extend_from_slice(extra);
        meshlight(&args)
    };
    let over = (MAX_TRIANGLES + 1).to_string();
    for (extra, option) in [
        (&["--position-bits", "40"][..], "--position-bits"),
        (&["--grouping", "random"][..], "--grouping"),
        (&["--max-triangles", "0"][..], "--max-triangles"),
        (&["--max-triangles", over.as_str()][..], "--max-triangles"),
        (&["--segments", "2"][..], "--segments"),
        (&["--jobs", "0"][..], "--jobs"),
    ] {
        let out = bake(extra);
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{extra:?} accepted: {err}");
        assert!(err.contains(option), "{extra:?}: {err}");
    }
    let missing_output = meshlight(&["bake", "no-such-mesh.gltf"]);
    assert_eq!(missing_output.status.code(), Some(2), "-o is required");
    for extra in [
        &["--max-triangles", "100"][..],
        &["--grouping", "metis", "--position-bits", "auto"][..],
        &["--position-bits", "12"][..],
    ] {
        let out = bake(extra);
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(1), "{extra:?}: {err}");
        assert!(err.contains("no-such-mesh.gltf"), "{extra:?}: {err}");
    }
    let help = String::from_utf8_lossy(&meshlight_ok(&["bake", "--help"]).stdout).into_owned();
    assert!(
        help.contains(&format!("[default: {DEFAULT_TRIANGLE_BUDGET}]"))
            && help.contains("partition")
            && help.contains("metis"),
        "{help}"
    );
}

/// `bake --jobs N` where N threads cannot be started (here an address-space limit with
/// room for the process but not for 4,096 thread stacks) fails saying so and what to
/// change, not with a bare OS error; two jobs bake under the same limit.
#[cfg(unix)]
#[test]
fn bake_says_when_its_threads_cannot_start() {
    use std::os::unix::process::CommandExt;
    let dir = scratch("jobs-limit");
    let out = dir.join("teapot.mlasset");
    let run = |jobs: &str| {
        let mut cmd = command(&[
            "bake",
            "--jobs",
            jobs,
            "assets/meshes/teapot.obj",
            "-o",
            out.to_str().unwrap(),
        ]);
        // SAFETY: the closure only calls setrlimit, which is async-signal-safe.
        unsafe {
            cmd.pre_exec(|| {
                let limit = libc::rlimit {
                    rlim_cur: 1_500_000_000,
                    rlim_max: 1_500_000_000,
                };
                match libc::setrlimit(libc::RLIMIT_AS, &limit) {
                    0 => Ok(()),
                    _ => Err(std::io::Error::last_os_error()),
                }
            });
        }
        cmd.output().expect("runs")
    };
    let many = run("4096");
    let err = String::from_utf8_lossy(&many.stderr);
    assert_eq!(many.status.code(), Some(1), "{err}");
    assert!(
        err.contains("4096 threads could not be started") && err.contains("smaller --jobs"),
        "{err}"
    );
    let two = run("2");
    assert!(
        two.status.success(),
        "{}",
        String::from_utf8_lossy(&two.stderr)
    );
    assert!(out.is_file());
}

/// A glTF file of two tetrahedra on two nodes and a camera, written for the test.
fn two_node_scene(dir: &Path) -> std::path::PathBuf {
    use meshlight_testing::gltf_writer::{GltfWriter, Node, Primitive};
    let mut w = GltfWriter::new();
    let tet = w.mesh(
        "tetrahedron",
        &[Primitive {
            positions: vec![
                [0.0, 0.0, 0.0],
                [1.0, 0.0, 0.0],
                [0.0, 1.0, 0.0],
                [0.0, 0.0, 1.0],
            ],
            indices: vec![0, 2, 1, 0, 1, 3, 0, 3, 2, 1, 2, 3],
            ..Primitive::default()
        }],
    );
    let camera = w.perspective_camera("eye", 0.8, 0.1);
    let nodes = [0.0f32, 2.0].map(|x| {
        w.node(Node {
            mesh: Some(tet),
            translation: Some([x, 0.0, 0.0]),
            ..Node::default()
        })
    });
    let eye = w.node(Node {
        camera: Some(camera),
        translation: Some([1.0, 0.5, 6.0]),
        ..Node::default()
    });
    w.scene(&[nodes[0], nodes[1], eye]);
    let path = dir.join("two.glb");
    std::fs::write(&path, w.glb()).unwrap();
    path
}

#[test]
fn render_draws_a_gltf_file_as_its_scene_and_offers_its_cameras() {
    let dir = scratch("gltf-scene");
    let glb = two_node_scene(&dir);
    let png = dir.join("two.png");
    let base = [
        "render",
        "--mesh",
        glb.to_str().unwrap(),
        "--width",
        "64",
        "--height",
        "48",
        "-o",
        png.to_str().unwrap(),
    ];
    let out = meshlight_ok(&base);
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(stdout.contains("2 instances"), "{stdout}");
    let mut through = base.to_vec();
    through.extend(["--camera-index", "0"]);
    meshlight_ok(&through);
    let mut merged = base.to_vec();
    merged.extend(["--merge-gltf", "--instances", "3"]);
    let out = meshlight_ok(&merged);
    let stdout = String::from_utf8_lossy(&out.stdout);
    // Three copies of the merged file on the field, and the ground.
    assert!(stdout.contains("4 instances"), "{stdout}");

    let mut missing = base.to_vec();
    missing.extend(["--camera-index", "1"]);
    let out = meshlight(&missing);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        !out.status.success() && err.contains("camera 1 asked for"),
        "{err}"
    );
    let out = meshlight(&["render", "--camera-index", "0", "-o", png.to_str().unwrap()]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        !out.status.success() && err.contains("only for a glTF scene"),
        "{err}"
    );
}

/// `meshlight args` (with no adapter to open) run to its end, which must come within
/// `seconds`: its exit status and standard error.
#[cfg(unix)]
fn run_within(args: &[&str], seconds: u64) -> (std::process::ExitStatus, String) {
    let started = std::time::Instant::now();
    let mut child = command(args)
        .env("MESHLIGHT_ADAPTER", "no adapter is called this")
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .expect("runs");
    let status = loop {
        if let Some(status) = child.try_wait().unwrap() {
            break status;
        }
        if started.elapsed() > std::time::Duration::from_secs(seconds) {
            let _ = child.kill();
            panic!(
                "meshlight {}: still running after {seconds} s",
                args.join(" ")
            );
        }
        std::thread::sleep(std::time::Duration::from_millis(20));
    };
    let out = child.wait_with_output().unwrap();
    (status, String::from_utf8_lossy(&out.stderr).into_owned())
}

/// A named pipe in a fresh directory.
#[cfg(unix)]
fn fifo(name: &str) -> std::path::PathBuf {
    let path = scratch(name).join(format!("{name}.fifo"));
    let made = std::process::Command::new("mkfifo")
        .arg(&path)
        .status()
        .expect("mkfifo runs");
    assert!(made.success());
    path
}

/// Every command that reads a user's file refuses a device or a pipe at once, naming
/// it, rather than reading `/dev/zero` until memory runs out or waiting on a pipe for a
/// writer (each run is given 20 s; a refusal takes milliseconds).
#[cfg(unix)]
#[test]
fn devices_and_pipes_given_as_inputs_are_refused_at_once() {
    let pipe = fifo("input-pipe");
    let pipe = pipe.to_str().unwrap();
    let asset_pipe = fifo("asset-pipe");
    let asset_pipe = asset_pipe.with_extension("mlasset");
    std::fs::rename(asset_pipe.with_extension("fifo"), &asset_pipe).unwrap();
    let asset_pipe = asset_pipe.to_str().unwrap();
    let cases: Vec<Vec<&str>> = vec![
        vec!["render", "--mesh", "/dev/zero"],
        vec!["render", "--mesh", pipe],
        vec!["render", "--mesh", asset_pipe],
        vec!["inspect", asset_pipe],
        vec!["inspect", "/dev/zero"],
        vec!["bench", "--from-json", "/dev/zero", "--html", "/dev/null"],
        vec!["bench", "--from-json", pipe, "--html", "/dev/null"],
    ];
    for args in cases {
        let (status, err) = run_within(&args, 20);
        assert!(!status.success(), "{}: {err}", args.join(" "));
        assert!(
            err.contains("not a regular file"),
            "meshlight {}: {err}",
            args.join(" ")
        );
    }
}

/// Every argument that names a file to read, given each kind of path that is not a
/// regular file (a named pipe, a directory, a link to `/dev/zero`, a link to a pipe),
/// named with the extension the argument expects: the command fails within 20 s (a
/// refusal takes milliseconds; reading `/dev/zero` runs out of memory and a pipe waits
/// forever), without a panic, and its message names the path.
#[cfg(unix)]
#[test]
fn every_input_argument_refuses_pipes_directories_and_devices() {
    let dir = scratch("hostile-inputs");
    let pipe_target = dir.join("target.fifo");
    assert!(
        std::process::Command::new("mkfifo")
            .arg(&pipe_target)
            .status()
            .expect("mkfifo runs")
            .success()
    );
    // Each hostile kind, as a path ending in `ext`.
    let hostile = |kind: &str, ext: &str| -> String {
        let path = dir.join(format!("{kind}.{ext}"));
        if !path.exists() && std::fs::symlink_metadata(&path).is_err() {
            match kind {
                "pipe" => assert!(
                    std::process::Command::new("mkfifo")
                        .arg(&path)
                        .status()
                        .unwrap()
                        .success()
                ),
                "directory" => std::fs::create_dir(&path).unwrap(),
                "zero-link" => std::os::unix::fs::symlink("/dev/zero", &path).unwrap(),
                "pipe-link" => std::os::unix::fs::symlink(&pipe_target, &path).unwrap(),
                _ => unreachable!(),
            }
        }
        path.to_str().unwrap().to_string()
    };
    let out = dir.join("out.mlasset");
    let out = out.to_str().unwrap();
    for kind in ["pipe", "directory", "zero-link", "pipe-link"] {
        let mut cases: Vec<Vec<String>> = Vec::new();
        for mesh_ext in ["obj", "glb", "gltf", "stl", "mlasset"] {
            let mesh = hostile(kind, mesh_ext);
            cases.push(vec!["render".into(), "--mesh".into(), mesh.clone()]);
            cases.push(vec![
                "view".into(),
                "--offscreen".into(),
                "--frames".into(),
                "1".into(),
                "--mesh".into(),
                mesh.clone(),
            ]);
            // A directory is what `bake DIR` bakes: only the file kinds are refused.
            if kind != "directory" {
                cases.push(vec!["bake".into(), mesh.clone(), "-o".into(), out.into()]);
            }
        }
        let pipeline = hostile(kind, "toml");
        cases.push(vec!["render".into(), "--pipeline".into(), pipeline.clone()]);
        cases.push(vec![
            "view".into(),
            "--offscreen".into(),
            "--frames".into(),
            "1".into(),
            "--pipeline".into(),
            pipeline.clone(),
        ]);
        cases.push(vec!["graph".into(), "--pipeline".into(), pipeline]);
        cases.push(vec!["inspect".into(), hostile(kind, "mlasset")]);
        let json = hostile(kind, "json");
        cases.push(vec![
            "bench".into(),
            "--from-json".into(),
            json,
            "--html".into(),
            "/dev/null".into(),
        ]);
        for args in &cases {
            let args: Vec<&str> = args.iter().map(String::as_str).collect();
            let (status, err) = run_within(&args, 20);
            let shown = args.join(" ");
            assert!(!status.success(), "meshlight {shown} succeeded: {err}");
            assert!(!err.contains("panicked"), "meshlight {shown}: {err}");
            let named = args
                .iter()
                .skip(1)
                .any(|a| a.contains(kind) && err.contains(a));
            assert!(
                named,
                "meshlight {shown}: the message does not name the path: {err}"
            );
        }
    }
}

/// Every argument that names a file to write, given a directory or a full device: the
/// command fails without a panic, and its message names the path (render runs on the
/// adapter the GPU tests use, since it writes only after drawing).
#[cfg(unix)]
#[test]
fn every_output_argument_names_the_path_it_cannot_write() {
    let dir = scratch("hostile-outputs");
    let folder = |ext: &str| -> String {
        let path = dir.join(format!("folder.{ext}"));
        std::fs::create_dir_all(&path).unwrap();
        path.to_str().unwrap().to_string()
    };
    const PNG: &str = "PNG";
    let png = dir.join("frame.png").to_str().unwrap().to_string();
    let rows = "docs/bench-h200-resolve-decode.json";
    let pipeline = "pipelines/virtual_geometry.toml";
    let small = [
        "render",
        "--instances",
        "1",
        "--segments",
        "8",
        "--width",
        "32",
        "--height",
        "32",
    ];
    // Each form with BAD where the path goes, and the extension its path takes.
    const BAD: &str = "BAD";
    let render = |extra: &[&'static str]| [&small[..], extra].concat();
    let forms: Vec<(&str, Vec<&str>)> = vec![
        (
            "svg",
            vec![
                "graph",
                "--pipeline",
                pipeline,
                "--format",
                "svg",
                "-o",
                BAD,
            ],
        ),
        ("html", vec!["bench", "--from-json", rows, "--html", BAD]),
        ("json", vec!["bench", "--from-json", rows, "--json", BAD]),
        ("html", render(&["-o", PNG, "--html", BAD])),
        ("json", render(&["-o", PNG, "--trace", BAD])),
        ("png", render(&["-o", BAD])),
        (
            "mlasset",
            vec!["bake", "procedural", "--segments", "8", "-o", BAD],
        ),
    ];
    let mut cases: Vec<(Vec<String>, String)> = Vec::new();
    for (ext, form) in &forms {
        // `bake -o DIR` is the directory form: only the device is a bad output there.
        let folders = if *ext == "mlasset" {
            vec![]
        } else {
            vec![folder(ext)]
        };
        for bad in folders.into_iter().chain(["/dev/full".to_string()]) {
            let args = form
                .iter()
                .map(|a| match *a {
                    BAD => bad.clone(),
                    PNG => png.clone(),
                    _ => a.to_string(),
                })
                .collect();
            cases.push((args, bad));
        }
    }
    for (args, bad) in &cases {
        let args: Vec<&str> = args.iter().map(String::as_str).collect();
        let out = command(&args).output().expect("runs");
        let err = String::from_utf8_lossy(&out.stderr);
        let shown = args.join(" ");
        assert!(!out.status.success(), "meshlight {shown} succeeded: {err}");
        assert!(!err.contains("panicked"), "meshlight {shown}: {err}");
        assert!(
            err.contains(bad.as_str()),
            "meshlight {shown}: the message does not name {bad}: {err}"
        );
    }
    // Checked before any work: with no adapter to open, a directory given as an image,
    // page, trace, screenshot or asset is still what the message names.
    let before_work = [
        render(&["-o", "DIR.png"]),
        render(&["-o", PNG, "--html", "DIR.html"]),
        render(&["-o", PNG, "--trace", "DIR.json"]),
        vec![
            "view",
            "--offscreen",
            "--frames",
            "1",
            "--screenshot",
            "DIR.png",
        ],
        vec!["bake", "procedural", "--segments", "8", "-o", "DIR.mlasset"],
    ];
    for form in before_work {
        let args: Vec<String> = form
            .iter()
            .map(|a| match a.strip_prefix("DIR.") {
                Some(ext) => folder(ext),
                None if *a == PNG => png.clone(),
                None => a.to_string(),
            })
            .collect();
        let args: Vec<&str> = args.iter().map(String::as_str).collect();
        let (status, err) = run_within(&args, 20);
        let shown = args.join(" ");
        assert!(!status.success(), "meshlight {shown} succeeded: {err}");
        assert!(
            err.contains("folder.") && err.contains("is a directory"),
            "meshlight {shown}: refused for another reason than its output: {err}"
        );
    }
}

/// `generate` writes a world, `bake DIR` bakes it, and `render --mesh OUT` draws the
/// directory of assets: resident, and streamed through a pool far smaller than the
/// assets (only their resident parts read up front), the same image once streaming
/// has settled.
#[test]
fn a_generated_world_bakes_and_renders_resident_and_streamed() {
    let dir = scratch("world");
    let (meshes, assets) = (dir.join("meshes"), dir.join("assets"));
    let s = |p: &Path| p.to_str().unwrap().to_string();
    let out = meshlight_ok(&[
        "generate",
        &s(&meshes),
        "--tiles",
        "2",
        "--cells",
        "96",
        "--knot-segments",
        "24",
    ]);
    let said = String::from_utf8_lossy(&out.stdout);
    assert!(said.contains("8 meshes"), "{said}");
    meshlight_ok(&["bake", &s(&meshes), "-o", &s(&assets)]);
    let asset_bytes: u64 = ["ground", "knots"]
        .iter()
        .flat_map(|d| std::fs::read_dir(assets.join(d)).unwrap())
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "mlasset"))
        .map(|p| std::fs::metadata(p).unwrap().len())
        .sum();
    assert!(asset_bytes > 1 << 20, "{asset_bytes} bytes of assets");
    let render = |png: &Path, pool: Option<&str>| {
        let mut args = vec![
            "render".to_string(),
            "--mesh".into(),
            s(&assets),
            "--width".into(),
            "160".into(),
            "--height".into(),
            "90".into(),
            "-o".into(),
            s(png),
        ];
        if let Some(mb) = pool {
            args.extend(["--pool-mb".into(), mb.into()]);
        }
        let args: Vec<&str> = args.iter().map(String::as_str).collect();
        let out = meshlight_ok(&args);
        String::from_utf8_lossy(&out.stdout).to_string()
    };
    render(&dir.join("resident.png"), None);
    // A page beside the image is rewritten with it: the streamed one shows the pool.
    std::fs::write(dir.join("streamed.html"), "").unwrap();
    let report = render(&dir.join("streamed.png"), Some("1"));
    assert!(report.contains("streamed: settled after"), "{report}");
    assert!(report.contains("0 refused"), "{report}");
    let page = std::fs::read_to_string(dir.join("streamed.html")).unwrap();
    for fact in [
        "pages resident",
        "LOD scale from pool pressure",
        "of 1.0 MiB",
    ] {
        assert!(page.contains(fact), "{fact} missing from the page");
    }
    assert_eq!(
        std::fs::read(dir.join("resident.png")).unwrap(),
        std::fs::read(dir.join("streamed.png")).unwrap(),
        "the settled streamed image differs from the resident one"
    );
    // An empty directory names what to do.
    let empty = dir.join("empty");
    std::fs::create_dir_all(&empty).unwrap();
    let out = meshlight(&["render", "--mesh", &s(&empty), "-o", &s(&dir.join("x.png"))]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        !out.status.success() && err.contains("holds no .mlasset files"),
        "{err}"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}
