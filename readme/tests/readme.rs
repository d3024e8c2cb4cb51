//! The README's code is code: every Rust block in it is a part of a program that compiles
//! (this crate's `src/bin`, or `examples/host`), with only the dependencies the README
//! tells a user to add; the WGSL and the Cargo.toml lines it shows are the files'; and the
//! programs run (lavapipe in CI).

use std::process::Command;

const README: &str = include_str!("../../README.md");

/// The compiled sources a README block may quote, by name.
const SOURCES: [(&str, &str); 4] = [
    (
        "readme/src/bin/library.rs",
        include_str!("../src/bin/library.rs"),
    ),
    (
        "readme/src/bin/frame_graph.rs",
        include_str!("../src/bin/frame_graph.rs"),
    ),
    (
        "readme/src/bin/own_pass.rs",
        include_str!("../src/bin/own_pass.rs"),
    ),
    (
        "examples/host/main.rs",
        include_str!("../../examples/host/main.rs"),
    ),
];

/// The fenced blocks of `lang` in the README, their text without the fences.
fn blocks(lang: &str) -> Vec<&'static str> {
    let open = format!("```{lang}\n");
    let mut out = Vec::new();
    let mut rest = README;
    while let Some(at) = rest.find(&open) {
        let body = &rest[at + open.len()..];
        let end = body.find("```").expect("a closed block");
        out.push(&body[..end]);
        rest = &body[end + 3..];
    }
    out
}

#[test]
fn every_rust_block_of_the_readme_is_compiled_code() {
    let rust = blocks("rust");
    assert!(rust.len() >= 4, "{} Rust blocks", rust.len());
    for block in &rust {
        assert!(
            SOURCES.iter().any(|(_, source)| source.contains(block)),
            "a Rust block of README.md is in no compiled program (copy it from one of {:?}):\n{block}",
            SOURCES.map(|(name, _)| name)
        );
    }
    // Each program of this crate is shown whole, from its first `use`.
    for (name, source) in &SOURCES[..3] {
        let code = &source[source.find("use ").unwrap()..];
        assert!(
            rust.contains(&code),
            "README.md does not show {name} from its first `use`"
        );
    }
    assert!(
        blocks("rust,ignore").is_empty() && blocks("rust,no_run").is_empty(),
        "README.md has Rust that is not checked"
    );
}

#[test]
fn the_readme_shows_the_shader_and_the_dependencies_the_programs_use() {
    let wgsl = include_str!("../src/bin/double.wgsl");
    assert!(
        blocks("wgsl").contains(&wgsl),
        "README.md's WGSL differs from double.wgsl"
    );
    // The `[dependencies]` the README gives are this crate's, and nothing else.
    let manifest = include_str!("../Cargo.toml");
    let ours = manifest[manifest.find("[dependencies]").unwrap()..]
        .lines()
        .skip(1)
        .take_while(|l| !l.starts_with('['))
        .filter_map(|l| l.split_once(".workspace").map(|(name, _)| name.trim()))
        .collect::<Vec<_>>();
    let toml = blocks("toml");
    let given = toml
        .iter()
        .find(|b| b.starts_with("[dependencies]"))
        .expect("a [dependencies] block in README.md");
    let names: Vec<&str> = given
        .lines()
        .skip(1)
        .filter_map(|l| l.split_once(" = ").map(|(name, _)| name.trim()))
        .collect();
    assert_eq!(names, ours, "README.md's [dependencies]: {given}");
}

fn run(exe: &str) -> String {
    let out = Command::new(exe)
        .current_dir(std::env::temp_dir())
        .env_remove("XDG_RUNTIME_DIR")
        .output()
        .expect("the program runs");
    assert!(
        out.status.success(),
        "{exe}: {}{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(
        out.stderr.is_empty(),
        "{exe} printed on standard error: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8_lossy(&out.stdout).into_owned()
}

/// Run from a directory of their own, as a user's programs would be: nothing of the
/// clone is at hand. Standard error stays empty (no driver alarms), even without an
/// `XDG_RUNTIME_DIR`.
#[test]
fn the_programs_run_where_a_user_runs_them() {
    let out = run(env!("CARGO_BIN_EXE_own_pass"));
    assert!(out.contains("doubled 100 values"), "{out}");
    let out = run(env!("CARGO_BIN_EXE_frame_graph"));
    assert!(
        out.contains("digraph") && out.contains("frame 1: total 131072"),
        "{out}"
    );
    let out = run(env!("CARGO_BIN_EXE_library"));
    assert!(out.contains("640 × 360 RGBA pixels"), "{out}");
}
