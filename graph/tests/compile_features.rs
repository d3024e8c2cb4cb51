//! Headless compile tests of limits, size parameters, texture ranges, multi-access slots,
//! 64-bit visibility targets, mesh programs and pipeline-file errors.

#[path = "support/fake.rs"]
mod fake;
use fake::*;
use meshlight_graph::*;

fn limits() -> wgpu::Limits {
    wgpu::Limits::default()
}

/// Adds a pass `w` writing the resource `name` through its one slot.
fn writer(g: &mut GraphBuilder, name: &str, slot: Slot) {
    let bindings = Bindings::new().bind_named(slot.name, name);
    g.add_pass("w", Fake::new("t", vec![slot]), bindings)
        .unwrap();
}

fn one_writer(g: &mut GraphBuilder, name: &str) {
    writer(g, name, out_u32());
}

/// Adds a pass writing the texture `name` through a slot of any format.
fn one_texture_writer(g: &mut GraphBuilder, name: &str) {
    writer(g, name, Slot::texture("t", Access::StorageWrite, None, ""));
}

#[test]
fn a_size_that_overflows_u64_is_an_error_not_a_wrapped_size() {
    let desc = BufferDesc::array(Element::U32, (1u64 << 62) + 65536);
    assert_ne!(desc.size, 262_144, "the size must not wrap");
    let mut g = GraphBuilder::new();
    let h = g.create_buffer("huge", desc);
    g.export(h);
    one_writer(&mut g, "huge");
    let_compile_error!(g => GraphError::SizeOverflow { resource });
    assert_eq!(resource, "huge");
}

#[test]
fn a_buffer_over_max_buffer_size_is_a_compile_error() {
    let mut g = GraphBuilder::new();
    let h = g.create_buffer("four_tib", BufferDesc::array(Element::BYTES, 4 << 40));
    g.export(h);
    writer(
        &mut g,
        "four_tib",
        Slot::buffer("out", Access::CopyDst, Element::BYTES, ""),
    );
    let_compile_error!(g => GraphError::LimitExceeded { what, limit, max, .. });
    assert!(what.contains("four_tib"), "{what}");
    assert_eq!(limit, "max_buffer_size");
    assert_eq!(max, limits().max_buffer_size);
}

#[test]
fn a_storage_binding_over_its_limit_names_the_pass_slot_and_limit() {
    let bytes = limits().max_storage_buffer_binding_size + 4;
    let mut g = GraphBuilder::new();
    let h = g.create_buffer("big", BufferDesc::array(Element::BYTES, bytes));
    g.export(h);
    g.add_pass(
        "w",
        Fake::new(
            "t",
            vec![Slot::buffer(
                "out",
                Access::StorageWrite,
                Element::BYTES,
                "",
            )],
        ),
        Bindings::new().bind_named("out", "big"),
    )
    .unwrap();
    let_compile_error!(g => GraphError::LimitExceeded { what, limit, .. });
    assert!(
        what.contains("`big`") && what.contains("`out`") && what.contains("`w`"),
        "{what}"
    );
    assert_eq!(limit, "max_storage_buffer_binding_size");
    // The same buffer as a copy destination is fine: only bindings have that limit.
    let mut g = GraphBuilder::new();
    let h = g.create_buffer("big", BufferDesc::array(Element::BYTES, bytes));
    g.export(h);
    writer(
        &mut g,
        "big",
        Slot::buffer("out", Access::CopyDst, Element::BYTES, ""),
    );
    g.compile(&opts()).unwrap();
}

#[test]
fn more_mip_levels_than_the_size_has_is_an_error_naming_the_range() {
    let mut g = GraphBuilder::new();
    let t = g.create_texture(
        "deep",
        TextureDesc::d2(wgpu::TextureFormat::R32Float, 16, 8).with_mips(6),
    );
    g.export(t);
    one_texture_writer(&mut g, "deep");
    let e = compile_error(g);
    assert!(matches!(e, GraphError::BadDeclaration { .. }), "{e:?}");
    assert_eq!(
        e.to_string(),
        "resource `deep`: 6 mip levels; a 16×8 texture has 1 to 5, declare a count in that range"
    );
}

#[test]
fn a_texture_over_the_dimension_limit_is_a_compile_error() {
    let mut g = GraphBuilder::new();
    let wide = limits().max_texture_dimension_2d + 1;
    let t = g.create_texture(
        "wide",
        TextureDesc::d2(wgpu::TextureFormat::R32Float, wide, 4),
    );
    g.export(t);
    one_texture_writer(&mut g, "wide");
    let_compile_error!(g => GraphError::LimitExceeded { what, limit, .. });
    assert!(what.contains("wide"));
    assert_eq!(limit, "max_texture_dimension_2d");
}

#[test]
fn a_declared_dispatch_over_the_per_dimension_limit_is_a_compile_error() {
    let wide = pass(
        "wide",
        vec![out_u32()],
        |ctx| {
            ctx.dispatch(
                "main",
                [ctx.limits().max_compute_workgroups_per_dimension + 1, 1, 1],
            );
            Ok(())
        },
        |_| Ok(()),
    );
    let mut g = GraphBuilder::new();
    g.import_buffer("out", u32s(4), IMPORT_USAGE);
    g.add_pass("wide", wide, Bindings::new()).unwrap();
    let_compile_error!(g => GraphError::LimitExceeded { what, limit, .. });
    assert!(what.contains("`main`") && what.contains("`wide`"), "{what}");
    assert_eq!(limit, "max_compute_workgroups_per_dimension");
}

#[test]
fn limits_come_from_the_options() {
    let mut g = GraphBuilder::new();
    let h = g.create_buffer("b", BufferDesc::array(Element::U32, 1024));
    g.export(h);
    one_writer(&mut g, "b");
    let tight = wgpu::Limits {
        max_buffer_size: 1024,
        ..wgpu::Limits::default()
    };
    assert!(matches!(
        g.compile(&opts().with_limits(tight)),
        Err(GraphError::LimitExceeded { .. })
    ));
}

#[test]
fn size_parameters_resize_buffers_and_a_bad_value_leaves_the_plan_as_it_was() {
    let mut g = GraphBuilder::new();
    g.size_param("slots", 100);
    let h = g.create_buffer("list", BufferDesc::array_param(Element::U32, "slots"));
    g.export(h);
    one_writer(&mut g, "list");
    let mut c = g.compile(&opts()).unwrap();
    let list = c.plan.resource_index("list").unwrap();
    assert_eq!(c.plan.resources[list].info.desc.bytes(), 400);
    c.set_param("slots", 1000).unwrap();
    assert_eq!(c.plan.resources[list].info.desc.bytes(), 4000);
    assert_eq!(c.plan.generation, 1);
    // Past the adapter's buffer size: an error, and nothing changed.
    match c.set_param("slots", 1 << 40) {
        Err(GraphError::LimitExceeded { what, .. }) => assert!(what.contains("list")),
        other => panic!("{other:?}"),
    }
    assert!(matches!(
        c.set_param("slots", u64::MAX),
        Err(GraphError::SizeOverflow { .. })
    ));
    assert_eq!(c.plan.resources[list].info.desc.bytes(), 4000);
    assert_eq!(c.plan.generation, 1);
    match c.set_param("nope", 1) {
        Err(e @ GraphError::NoSuchParam { .. }) => {
            let text = e.to_string();
            assert!(text.contains("`nope`") && text.contains("slots"), "{text}");
        }
        other => panic!("{other:?}"),
    }
    // A buffer naming an undeclared parameter fails at compile.
    let mut g = GraphBuilder::new();
    let h = g.create_buffer("list", BufferDesc::array_param(Element::U32, "slotz"));
    g.export(h);
    one_writer(&mut g, "list");
    let_compile_error!(g => GraphError::UnknownParam { resource, param, .. });
    assert_eq!((resource.as_str(), param.as_str()), ("list", "slotz"))
}

/// Adds a `mip_pass` reading range `src` of `t` and writing range `dst` of it.
fn add_mip_pass(
    g: &mut GraphBuilder,
    name: &str,
    t: Handle<Texture>,
    src: TextureRange,
    dst: TextureRange,
) -> Result<PassOutputs> {
    let bindings = Bindings::new()
        .bind_range("src", t, src)
        .bind_range("dst", t, dst);
    g.add_pass(name, mip_pass(), bindings)
}

fn mip_pass() -> Fake {
    Fake::new(
        "down",
        vec![
            Slot::texture("src", Access::Sampled, None, ""),
            Slot::texture("dst", Access::StorageWrite, None, ""),
        ],
    )
}

#[test]
fn disjoint_mips_of_one_texture_may_be_read_and_written_by_one_pass() {
    let mut g = GraphBuilder::new();
    let desc = TextureDesc::d2(wgpu::TextureFormat::R32Float, 16, 16).with_full_mips();
    let t = g.import_texture("pyr", desc, wgpu::TextureUsages::all());
    let out = add_mip_pass(
        &mut g,
        "mip1",
        t,
        TextureRange::mip(0),
        TextureRange::mip(1),
    )
    .unwrap();
    let t1 = out.texture("dst").unwrap();
    assert_eq!(t1.version(), 1);
    add_mip_pass(
        &mut g,
        "mip2",
        t1,
        TextureRange::mip(1),
        TextureRange::mip(2),
    )
    .unwrap();
    let c = g.compile(&opts()).unwrap();
    assert_eq!(c.plan.order, [0, 1]);
    assert_eq!(c.plan.edges.len(), 2, "{:?}", c.plan.edges);
}

#[test]
fn overlapping_ranges_in_one_pass_stay_an_error() {
    for (src, dst) in [
        (TextureRange::mips(0, 2), TextureRange::mip(1)),
        (TextureRange::mips(0, u32::MAX), TextureRange::mip(3)),
    ] {
        let mut g = GraphBuilder::new();
        let desc = TextureDesc::d2(wgpu::TextureFormat::R32Float, 16, 16).with_full_mips();
        let t = g.import_texture("pyr", desc, wgpu::TextureUsages::all());
        add_mip_pass(&mut g, "bad", t, src, dst).unwrap();
        let_compile_error!(g => GraphError::UsageNotAllowed { pass, reason, .. });
        assert_eq!(pass, "bad");
        assert!(reason.contains("overlapping"), "{reason}");
    }
    // A range outside the texture is a descriptor error.
    let mut g = GraphBuilder::new();
    let desc = TextureDesc::d2(wgpu::TextureFormat::R32Float, 16, 16).with_mips(2);
    let t = g.import_texture("pyr", desc, wgpu::TextureUsages::all());
    add_mip_pass(&mut g, "bad", t, TextureRange::mip(0), TextureRange::mip(2)).unwrap();
    let_compile_error!(g => GraphError::DescriptorMismatch { .. });
}

#[test]
fn texture_arrays_and_layer_ranges_plan_like_mips() {
    let mut g = GraphBuilder::new();
    let desc = TextureDesc::d2(wgpu::TextureFormat::R32Float, 8, 8).with_layers(4);
    assert_eq!(desc.bytes(), 8 * 8 * 4 * 4);
    let t = g.create_texture("layers", desc);
    let out = g.add_pass(
        "copy",
        mip_pass(),
        Bindings::new()
            .bind_range("dst", t, TextureRange::layer(0))
            .bind_range("src", t, TextureRange::layer(1)),
    );
    // Layer 1 has no writer yet.
    assert!(out.is_ok());
    let_compile_error!(g => GraphError::ReadWithoutWriter { .. });
}

#[test]
fn cleared_read_write_needs_no_writer_and_a_second_use_adds_its_usage() {
    // One pass appending to a fresh `args` through `slot`.
    let append = |slot: Slot| {
        let mut g = GraphBuilder::new();
        let args = g.create_buffer("args", u32s(4));
        let out = g
            .add_pass(
                "append",
                Fake::new("a", vec![slot]),
                Bindings::new().bind("args", args),
            )
            .unwrap();
        g.export(out.buffer("args").unwrap());
        g
    };
    let cleared = Slot::buffer("args", Access::ClearedReadWrite, Element::U32, "");
    let c = append(cleared.also(Access::Indirect))
        .compile(&opts())
        .unwrap();
    let r = &c.plan.resources[c.plan.resource_index("args").unwrap()];
    assert_eq!(
        r.buffer_usage,
        wgpu::BufferUsages::STORAGE
            | wgpu::BufferUsages::COPY_DST
            | wgpu::BufferUsages::INDIRECT
            | wgpu::BufferUsages::COPY_SRC
    );
    // The same slot as plain read-write is a read of a version nothing wrote.
    let read_write = Slot::buffer("args", Access::StorageReadWrite, Element::U32, "");
    assert!(matches!(
        append(read_write).compile(&opts()),
        Err(GraphError::ReadWithoutWriter { .. })
    ));
}

fn vis_pass(access: Access) -> Fake {
    Fake::new("sw_raster", vec![Slot::visibility64("vis", access, "")])
}

/// Adds a raster that clears and writes `vis`, and exports what it writes.
fn add_exported_raster(g: &mut GraphBuilder, vis: impl Into<AnyHandle>) {
    let bindings = Bindings::new().bind("vis", vis);
    let o = g
        .add_pass("raster", vis_pass(Access::ClearedReadWrite), bindings)
        .unwrap();
    g.export(o.written()[0].1);
}

#[test]
fn a_64_bit_visibility_slot_takes_a_u64_buffer_or_an_r64uint_texture() {
    // Buffer: fine anywhere.
    let mut g = GraphBuilder::new();
    let v = g.create_buffer("vis", BufferDesc::array(Element::U64, 64));
    add_exported_raster(&mut g, v);
    g.compile(&opts()).unwrap();

    // Texture: STORAGE_ATOMIC usage and the texture-atomic features, required.
    let build = || {
        let mut g = GraphBuilder::new();
        let v = g.create_texture("vis", TextureDesc::d2(wgpu::TextureFormat::R64Uint, 8, 8));
        add_exported_raster(&mut g, v);
        g
    };
    let atomics = wgpu::Features::TEXTURE_ATOMIC | wgpu::Features::TEXTURE_INT64_ATOMIC;
    let c = build().compile(&CompileOptions::new(atomics)).unwrap();
    let r = &c.plan.resources[c.plan.resource_index("vis").unwrap()];
    assert!(
        r.texture_usage
            .contains(wgpu::TextureUsages::STORAGE_BINDING | wgpu::TextureUsages::STORAGE_ATOMIC)
    );
    assert!(c.plan.passes[0].required_features.contains(atomics));
    let_compile_error!(build() => GraphError::MissingFeature { pass, features, .. });
    assert_eq!(pass, "raster");
    assert!(features.contains("TEXTURE_INT64_ATOMIC"), "{features}");

    // Anything else: a descriptor error naming both.
    let mut g = GraphBuilder::new();
    let v = g.create_buffer("vis", u32s(64));
    g.add_pass(
        "raster",
        vis_pass(Access::ClearedReadWrite),
        Bindings::new().bind("vis", v),
    )
    .unwrap();
    let_compile_error!(g => GraphError::DescriptorMismatch { expected, found, .. });
    assert!(expected.contains("64-bit visibility"), "{expected}");
    assert!(found.contains("u32"), "{found}");
}

const MESH: PassShader = PassShader {
    name: "test::mesh",
    source: "",
    file_path: "graph/tests/compile_features.rs",
    modules: &[],
};

#[test]
fn a_mesh_program_requires_the_mesh_shader_feature() {
    let meshy = || {
        pass(
            "hw_raster",
            vec![out_u32()],
            |ctx| {
                ctx.program(
                    "draw",
                    ProgramDesc::mesh(&MESH, Some("ts"), "ms").fragment("fs"),
                );
                Ok(())
            },
            |_| Ok(()),
        )
    };
    let build = || {
        let mut g = GraphBuilder::new();
        g.import_buffer("out", u32s(4), IMPORT_USAGE);
        g.add_pass("hw", meshy(), Bindings::new()).unwrap();
        g
    };
    let_compile_error!(build() => GraphError::MissingFeature { pass, features, .. });
    assert_eq!(pass, "hw");
    assert!(features.contains("EXPERIMENTAL_MESH_SHADER"), "{features}");
    let c = build()
        .compile(&CompileOptions::new(
            wgpu::Features::EXPERIMENTAL_MESH_SHADER,
        ))
        .unwrap();
    let program = &c.plan.passes[0].programs[0];
    assert_eq!(
        (program.kind, program.entries.clone()),
        ("mesh", vec!["ts", "ms", "fs"])
    );
}

#[test]
fn pipeline_file_errors_name_the_stage_and_the_version() {
    let registry = {
        let mut r = file::Registry::new();
        r.register("transform", "add", |_| -> Result<Fake> {
            unreachable!("never built in these tests")
        });
        r
    };
    let text = r#"
[[pass]]
name = "first"
stage = "trnasform"
implementation = "add"
"#;
    match file::parse_pipeline(text, "p.toml", &registry) {
        Err(GraphError::UnknownStage {
            file,
            pass,
            stage,
            known,
        }) => {
            assert_eq!(
                (file.as_str(), pass.as_str(), stage.as_str()),
                ("p.toml", "first", "trnasform")
            );
            assert_eq!(known, "transform");
        }
        other => panic!("{:?}", other.err()),
    }
    let text = r#"
[[resource]]
name = "x"
kind = "transient"
buffer = { element = "u32", count = 4 }

[[pass]]
name = "first"
stage = "transform"
implementation = "add"
bind = { input = "x@4294967296" }
"#;
    let registry = {
        let mut r = file::Registry::new();
        r.register("transform", "add", |_| {
            Ok(Fake::rw(&["input"], &["output"]))
        });
        r
    };
    match file::parse_pipeline(text, "p.toml", &registry) {
        Err(GraphError::PipelineFile { message, .. }) => {
            assert!(message.contains("too large"), "{message}")
        }
        other => panic!("{:?}", other.err()),
    }
}

#[test]
fn pipeline_files_declare_size_parameters_and_texture_ranges() {
    let mut registry = file::Registry::new();
    registry.register("down", "fake", |_| Ok(mip_pass()));
    registry.register("fill", "fake", |_| Ok(Fake::new("fill", vec![out_u32()])));
    let text = include_str!("pipelines/size_params_and_texture_ranges.toml");
    let c = file::parse_pipeline(text, "p.toml", &registry)
        .unwrap()
        .compile(&opts())
        .unwrap();
    assert_eq!(c.param("slots"), Some(300));
    let list = c.plan.resource_index("list").unwrap();
    assert_eq!(c.plan.resources[list].info.desc.bytes(), 1200);
    let mip2 = &c.plan.passes[c.plan.pass_index("mip2").unwrap()];
    assert_eq!(
        mip2.slots[0].range.map(|r| (r.base_mip, r.mip_count)),
        Some((1, 1))
    );
    let bad = text.replace("pyr#mip=0", "pyr#mip=x");
    assert!(matches!(
        file::parse_pipeline(&bad, "p.toml", &registry),
        Err(GraphError::PipelineFile { .. })
    ));
}
