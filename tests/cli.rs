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
fn graph_dumps_the_shipped_pipeline_in_every_format() {
    for (format, marker) in [
        ("dot", "digraph meshlight"),
        ("json", "\"order\""),
        ("mermaid", "flowchart LR"),
        ("html", "<!DOCTYPE html>"),
    ] {
        let out = meshlight(&[
            "graph",
            "--pipeline",
            "pipelines/prefix_sum.toml",
            "--format",
            format,
        ]);
        assert!(
            out.status.success(),
            "{format}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
        let text = String::from_utf8(out.stdout).unwrap();
        assert!(
            text.contains(marker) && text.contains("scan"),
            "{format}:\n{text}"
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
