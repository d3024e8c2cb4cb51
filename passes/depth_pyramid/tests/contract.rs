//! What compile plans and refuses for `depth_pyramid`, with no device: the programs and
//! dispatches of each implementation, `auto` through the registry, the texture form's
//! features, and bad params or bindings.

use meshlight_graph::file::{Registry, parse_pipeline};
use meshlight_graph::*;
use meshlight_pass_depth_pyramid::{
    DepthPyramid, FORMAT, Method, STAGE, pyramid_extent, register, texture_desc,
};
use meshlight_testing::pass_errors::pass_parameter_message;
use meshlight_testing::{parameter_message, params};

mod common;
use common::{Visibility, add_pyramid_pass};

/// How the one-pass graph is bound.
struct Binding {
    /// The visibility target as an R64Uint texture instead of a u64 buffer.
    texture: bool,
    /// The `counter` slot bound to an imported buffer.
    counter: bool,
    /// The pyramid texture's descriptor; `None`: [`texture_desc`].
    pyramid: Option<TextureDesc>,
    /// Visibility values in the buffer form; `None`: width × height.
    values: Option<u64>,
    features: wgpu::Features,
}

const PLAIN: Binding = Binding {
    texture: false,
    counter: false,
    pyramid: None,
    values: None,
    features: wgpu::Features::empty(),
};

fn compile(pass: DepthPyramid, b: Binding) -> Result<CompiledGraph> {
    let (w, h) = (pass.width.max(1), pass.height.max(1));
    let visibility = if b.texture {
        Visibility::Texture
    } else {
        Visibility::Buffer(b.values.unwrap_or(w as u64 * h as u64))
    };
    let pyramid = b.pyramid.unwrap_or_else(|| texture_desc(w, h));
    let mut g = GraphBuilder::new();
    add_pyramid_pass(&mut g, pass, visibility, pyramid, b.counter)?;
    g.compile(&CompileOptions::new(b.features))
}

fn programs(compiled: &CompiledGraph) -> Vec<&str> {
    compiled.plan.passes[0]
        .programs
        .iter()
        .map(|p| p.name.as_str())
        .collect()
}

/// The pass's scratch resources: (name, bytes).
fn scratch(compiled: &CompiledGraph) -> Vec<(String, u64)> {
    let plan = &compiled.plan;
    plan.passes[0]
        .scratch
        .iter()
        .map(|&r| {
            let info = &plan.resources[r].info;
            (info.name.clone(), info.desc.bytes())
        })
        .collect()
}

#[test]
fn single_pass_is_one_program_with_a_tile_result_each_and_a_cleared_counter() {
    let compiled = compile(DepthPyramid::single_pass(2240, 1260), PLAIN).unwrap();
    assert_eq!(programs(&compiled), ["single_pass"]);
    // 18 × 10 tiles of 128 pixels.
    assert_eq!(
        scratch(&compiled),
        [
            ("pyramid/tile_results".to_string(), 18 * 10 * 4),
            ("pyramid/arrivals".to_string(), 4)
        ]
    );
    let defs = &compiled.plan.passes[0].shader_defs;
    assert!(
        defs.iter()
            .any(|(n, v)| n == "SINGLE_PASS" && v.contains("true")),
        "{defs:?}"
    );
    // With a persistent counter bound, there is no scratch counter to clear.
    let bound = Binding {
        counter: true,
        ..PLAIN
    };
    let compiled = compile(DepthPyramid::single_pass(2240, 1260), bound).unwrap();
    assert_eq!(
        scratch(&compiled),
        [("pyramid/tile_results".to_string(), 18 * 10 * 4)]
    );
}

#[test]
fn two_pass_adds_the_top_dispatch_only_above_one_tile() {
    let compiled = compile(DepthPyramid::two_pass(2240, 1260), PLAIN).unwrap();
    assert_eq!(programs(&compiled), ["tiles", "top"]);
    for (w, h) in [(128, 128), (65, 33), (1, 1)] {
        let compiled = compile(DepthPyramid::two_pass(w, h), PLAIN).unwrap();
        assert_eq!(programs(&compiled), ["tiles"], "{w}×{h}");
    }
    let compiled = compile(DepthPyramid::two_pass(129, 1), PLAIN).unwrap();
    assert_eq!(programs(&compiled), ["tiles", "top"]);
}

#[test]
fn auto_takes_single_pass_and_both_are_registered() {
    let mut registry = Registry::new();
    register(&mut registry);
    let (w, h) = (50, 40);
    let d = texture_desc(w, h);
    assert_eq!(pyramid_extent(w, h).mip_levels, d.mip_levels);
    for (implementation, want) in [
        ("auto", "single_pass"),
        ("single_pass", "single_pass"),
        ("two_pass", "two_pass"),
    ] {
        let text = format!(
            r#"
[[resource]]
name = "visibility"
kind = "imported"
buffer = {{ element = "u64", count = {pixels} }}
usage = ["STORAGE"]

[[resource]]
name = "pyramid"
kind = "imported"
texture = {{ format = "r32float", width = {tw}, height = {th}, mip_levels = {mips} }}
usage = ["STORAGE_BINDING"]

[[pass]]
name = "hzb"
stage = "{STAGE}"
implementation = "{implementation}"
params = {{ width = {w}, height = {h} }}
"#,
            pixels = w * h,
            tw = d.width,
            th = d.height,
            mips = d.mip_levels,
        );
        let g = parse_pipeline(&text, "test.toml", &registry).unwrap_or_else(|e| panic!("{e}"));
        let compiled = g
            .compile(&CompileOptions::new(wgpu::Features::empty()))
            .unwrap_or_else(|e| panic!("{e}"));
        let pass = &compiled.plan.passes[0];
        assert_eq!(pass.implementation, want, "{implementation}");
        if implementation == "auto" {
            let reason = pass.choice_reason().unwrap_or_default();
            assert!(reason.contains("`single_pass` is the first"), "{reason}");
        }
    }
}

#[test]
fn the_texture_form_needs_64_bit_texture_support_and_switches_the_shader() {
    let texture = Binding {
        texture: true,
        ..PLAIN
    };
    match compile(DepthPyramid::single_pass(64, 48), texture) {
        Err(GraphError::MissingFeature { features, .. }) => {
            assert!(features.contains("TEXTURE_INT64_ATOMIC"), "{features}")
        }
        other => panic!("compiled without TEXTURE_INT64_ATOMIC: {:?}", other.err()),
    }
    let features = wgpu::Features::SHADER_INT64
        | wgpu::Features::TEXTURE_INT64_ATOMIC
        | wgpu::Features::TEXTURE_ATOMIC;
    for pass in [
        DepthPyramid::single_pass(64, 48),
        DepthPyramid::two_pass(64, 48),
    ] {
        let b = Binding {
            texture: true,
            features,
            ..PLAIN
        };
        let compiled = compile(pass, b).unwrap_or_else(|e| panic!("{e}"));
        let defs = &compiled.plan.passes[0].shader_defs;
        assert!(
            defs.iter()
                .any(|(n, v)| n == "VIS_TEXTURE" && v.contains("true")),
            "{defs:?}"
        );
    }
}

#[test]
fn bad_params_are_errors_that_say_what_to_change() {
    // (params, implementation, what the message must say)
    let refused: [(&str, Method, &[&str]); 4] = [
        (
            "width = 0\nheight = 4",
            Method::SinglePass,
            &["`width`", "0 × 4"],
        ),
        ("height = 4", Method::TwoPass, &["> 0"]),
        (
            "width = 20000\nheight = 4",
            Method::SinglePass,
            &["16384", "smaller"],
        ),
        (
            "width = 4\nheight = 4\nlevels = 3",
            Method::SinglePass,
            &["`levels`"],
        ),
    ];
    for (text, method, says) in refused {
        let m = parameter_message(DepthPyramid::from_params(&params(text), method));
        assert!(says.iter().all(|s| m.contains(s)), "{m}");
    }
    let p = DepthPyramid::from_params(&params("width = 37\nheight = 23"), Method::TwoPass).unwrap();
    assert_eq!((p.width, p.height, p.method), (37, 23, Method::TwoPass));
    // Built in code, the same check runs at compile and names the pass.
    let message =
        pass_parameter_message(compile(DepthPyramid::single_pass(0, 23), PLAIN), "pyramid");
    assert!(message.contains("`width`"), "{message}");
}

#[test]
fn wrong_bindings_are_refused_at_compile() {
    // A pyramid of another format.
    let b = Binding {
        pyramid: Some(TextureDesc::d2(wgpu::TextureFormat::R16Float, 32, 24).with_mips(6)),
        ..PLAIN
    };
    match compile(DepthPyramid::single_pass(64, 48), b) {
        Err(GraphError::DescriptorMismatch { slot, .. }) => assert_eq!(slot, "pyramid"),
        other => panic!("{:?}", other.err()),
    }
    // A visibility buffer too small for the params.
    let b = Binding {
        values: Some(64 * 47),
        ..PLAIN
    };
    let e = match compile(DepthPyramid::two_pass(64, 48), b) {
        Err(e) => e.to_string(),
        Ok(_) => panic!("compiled with a visibility buffer of 64 × 47 values"),
    };
    assert!(e.contains("visibility"), "{e}");
    // Another R32Float texture compiles; record checks it against texture_desc.
    let b = Binding {
        pyramid: Some(TextureDesc::d2(FORMAT, 32, 24).with_mips(6)),
        ..PLAIN
    };
    assert!(compile(DepthPyramid::single_pass(64, 48), b).is_ok());
}
