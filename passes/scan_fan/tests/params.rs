//! Parameters and contract, with no GPU.

use meshlight_graph::file::{Params, Registry};
use meshlight_graph::*;
use meshlight_pass_scan_fan::{
    DecoupledLookback, ScanFan, ScanOptions, Subgroups, TileAccess, register,
};

fn params(text: &str) -> Params {
    Params::new(text.parse().expect("toml"))
}

#[test]
fn parameters_parse_with_defaults() {
    let o = ScanOptions::from_params(&params("count = 10")).unwrap();
    assert_eq!(o, ScanOptions::new(10));
    let o = ScanOptions::from_params(&params(
        "count = 7\ninclusive = true\nsubgroups = \"off\"\nitems_per_thread = 2\ntile_access = \"direct\"",
    ))
    .unwrap();
    assert_eq!(
        (
            o.count,
            o.inclusive,
            o.subgroups,
            o.items_per_thread,
            o.tile_access
        ),
        (7, true, Subgroups::Off, 2, TileAccess::Direct)
    );
}

#[test]
fn vector_tiles_are_the_default_and_the_single_pass_takes_bigger_ones() {
    let o = ScanOptions::from_params(&params("count = 10")).unwrap();
    assert_eq!((o.tile_access, o.items_per_thread), (TileAccess::Vector, 8));
    let o = ScanOptions::from_params_for_lookback(&params("count = 10")).unwrap();
    assert_eq!(
        (o.tile_access, o.items_per_thread),
        (TileAccess::Vector, 32)
    );
    assert_eq!(o, DecoupledLookback::new(10).options);
    // A named size or staged tiles keep their own default.
    let o = ScanOptions::from_params_for_lookback(&params("items_per_thread = 4")).unwrap();
    assert_eq!(o.items_per_thread, 4);
    let o = ScanOptions::from_params_for_lookback(&params("tile_access = \"staged\"")).unwrap();
    assert_eq!((o.tile_access, o.items_per_thread), (TileAccess::Staged, 8));
    let o = ScanOptions::from_params(&params("items_per_thread = 32")).unwrap();
    assert_eq!(o.tile(), 8192);
}

#[test]
fn bad_parameters_say_what_to_change() {
    for (text, needle) in [
        ("subgroups = \"on\"", "\"auto\" or \"off\""),
        ("items_per_thread = 3", "1, 2, 4, 8 or 16"),
        (
            "items_per_thread = 64",
            "1, 2, 4, 8 or 16 (32 with vector tiles)",
        ),
        (
            "items_per_thread = 32\ntile_access = \"staged\"",
            "needs `tile_access = \"vector\"`",
        ),
        (
            "tile_access = \"blocked\"",
            "\"staged\", \"direct\" or \"vector\"",
        ),
        ("count = 4294967295", "largest supported"),
        ("cuont = 5", "unknown parameter `cuont`"),
        ("inclusive = 1", "true or false"),
    ] {
        let err = ScanOptions::from_params(&params(text)).unwrap_err();
        assert!(matches!(err, GraphError::Parameter { .. }), "{text}: {err}");
        assert!(err.to_string().contains(needle), "{text}: {err}");
    }
}

#[test]
fn registry_knows_every_implementation() {
    let mut registry = Registry::new();
    register(&mut registry);
    assert_eq!(
        registry.implementations("scan_fan"),
        ["decoupled_lookback", "scan_fan", "two_step"]
    );
    let pass = registry
        .build("scan_fan", "decoupled_lookback", &params("count = 3"))
        .unwrap();
    assert_eq!(pass.implementation().name, "decoupled_lookback");
    let pass = registry
        .build("scan_fan", "two_step", &params("count = 3"))
        .unwrap();
    assert_eq!(pass.implementation().name, "two_step");
}

#[test]
fn an_oversized_count_fails_at_compile_naming_the_pass() {
    let mut g = GraphBuilder::new();
    let usage = wgpu::BufferUsages::STORAGE;
    let n = (1u64 << 31) + 1;
    let input = g.import_buffer("input", BufferDesc::array(Element::U32, n), usage);
    let output = g.import_buffer("output", BufferDesc::array(Element::U32, n), usage);
    let mut pass = ScanFan::new(0);
    pass.options.count = n as u32;
    g.add_pass(
        "prefix",
        pass,
        Bindings::new().bind("input", input).bind("output", output),
    )
    .unwrap();
    match g.compile(&CompileOptions::new(wgpu::Features::empty())) {
        Err(GraphError::Parameter { pass, message }) => {
            assert_eq!(pass, "prefix");
            assert!(message.contains("largest supported"), "{message}");
        }
        other => panic!("expected a parameter error, got {:?}", other.err()),
    }
}

#[test]
fn output_shorter_than_the_count_is_a_descriptor_error() {
    let mut g = GraphBuilder::new();
    let usage = wgpu::BufferUsages::STORAGE;
    let input = g.import_buffer("input", BufferDesc::array(Element::U32, 100), usage);
    let output = g.import_buffer("output", BufferDesc::array(Element::U32, 99), usage);
    g.add_pass(
        "prefix",
        ScanFan::new(100),
        Bindings::new().bind("input", input).bind("output", output),
    )
    .unwrap();
    let err = g
        .compile(&CompileOptions::new(wgpu::Features::empty()))
        .err()
        .expect("a descriptor error");
    assert!(
        matches!(err, GraphError::DescriptorMismatch { ref slot, .. } if slot == "output"),
        "{err}"
    );
}
