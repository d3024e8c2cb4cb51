//! The README's library example is `examples/library.rs` of this crate, character for character from
//! its first `use`, and it runs (lavapipe in CI).

#[path = "../examples/library.rs"]
mod library;

#[test]
fn the_readme_shows_the_library_example() {
    let source = include_str!("../examples/library.rs");
    let code = &source[source.find("use ").unwrap()..];
    assert!(
        include_str!("../../../README.md").contains(code),
        "README.md's library example differs from examples/library.rs; copy the file from its first `use` into the README"
    );
}

#[test]
fn the_library_example_renders() {
    // The example names its mesh from the repository's root, where `cargo run` starts it.
    std::env::set_current_dir(concat!(env!("CARGO_MANIFEST_DIR"), "/../.."))
        .expect("the repository's root");
    library::main().unwrap_or_else(|e| panic!("{e}"));
}
