//! The `meshlight` binary: graph dumps of a shipped pipeline file, and typed errors for a
//! miswired one.

use std::process::Command;

fn meshlight(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_meshlight"))
        .args(args)
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .output()
        .expect("runs")
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
        let out = meshlight(&["graph", "--pipeline", file, "--format", format]);
        assert!(
            out.status.success(),
            "{format}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
        let text = String::from_utf8(out.stdout).unwrap();
        assert!(
            text.contains(marker) && text.contains(pass),
            "{file} {format}:\n{text}"
        );
    }
}

#[test]
fn a_miswired_pipeline_file_is_a_clear_error() {
    let dir = std::env::temp_dir().join(format!("meshlight-cli-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let text = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/pipelines/prefix_sum.toml"
    ))
    .unwrap();
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
    let dir = std::env::temp_dir().join(format!("meshlight-render-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let (png, html) = (dir.join("spot.png"), dir.join("spot.html"));
    let out = meshlight(&[
        "render",
        "--mesh",
        "assets/meshes/spot.obj",
        "--instances",
        "4",
        "--width",
        "96",
        "--height",
        "64",
        "--view",
        "lod",
        "--pipeline",
        "pipelines/virtual_geometry.toml",
        "-o",
        png.to_str().unwrap(),
        "--html",
        html.to_str().unwrap(),
    ]);
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success(),
        "{stdout}{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(stdout.contains("clusters visible (LOD cut)"), "{stdout}");
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
