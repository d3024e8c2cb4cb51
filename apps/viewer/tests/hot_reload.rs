//! A watched pipeline file: a broken edit is reported with the file and line while the
//! last good graph keeps rendering; a fixed edit ends on the new graph.

mod common;

use meshlight::resolve::DebugView;

#[test]
fn broken_then_fixed_pipeline_file() {
    let _x = common::xvfb();
    let (file, good) = common::pipeline_copy("reload");
    let mut o = common::unlit_options();
    o.scene.pipeline = Some(file.clone());
    let (_event_loop, mut v) = common::windowed(o);
    v.run_frames(3).expect("frames");
    let before = v.read_image().expect("image").2;
    assert!(
        common::colours(&before) > 50,
        "the first graph shows no scene"
    );
    let passes_before = v.renderer.compiled.plan.passes.len();

    // An implementation that does not exist: the line naming it is reported.
    let broken = good.replacen(
        "implementation = \"single_thread\"",
        "implementation = \"no_such_remap\"",
        1,
    );
    let broken_line = broken
        .lines()
        .position(|l| l.contains("no_such_remap"))
        .expect("edited")
        + 1;
    std::fs::write(&file, &broken).expect("write");
    assert!(v.poll_pipeline(true), "the change was not noticed");
    let e = v
        .file_error
        .clone()
        .expect("no error reported for the broken file");
    assert_eq!(e.file, file);
    assert_eq!(e.line, Some(broken_line), "error placed wrongly: {e}");
    assert!(
        v.error
            .as_deref()
            .is_some_and(|m| m.contains("no_such_remap"))
    );
    v.run_frames(3)
        .expect("the last good graph must keep rendering");
    assert_eq!(v.read_image().expect("image").2, before);

    // A TOML syntax error: the parser's line.
    let mut syntax = good.clone();
    syntax.push_str("\n[[pass]\n");
    let syntax_line = syntax.lines().count();
    std::fs::write(&file, &syntax).expect("write");
    assert!(v.poll_pipeline(true));
    let e = v.file_error.clone().expect("no error for a syntax error");
    assert_eq!(e.line, Some(syntax_line), "error placed wrongly: {e}");
    v.run_frames(2).expect("still rendering");

    // Fixed, and changed: the resolve shows LOD levels.
    let fixed = good.replacen("view = \"shaded\"", "view = \"lod\"", 1);
    assert_ne!(
        fixed, good,
        "the shipped file names no shaded view to change"
    );
    std::fs::write(&file, &fixed).expect("write");
    assert!(v.poll_pipeline(true));
    assert_eq!(v.error, None, "the fixed file still reports an error");
    assert_eq!(v.renderer.view, DebugView::Lod);
    v.run_frames(3).expect("frames");
    let after = v.read_image().expect("image").2;
    assert_ne!(after, before, "the new graph renders the old image");
    assert_eq!(v.renderer.compiled.plan.passes.len(), passes_before);
}
