//! Implementation choice (`auto`, named with alternatives) and 64-bit visibility targets
//! whose form follows the pass that clears them; all headless.

use meshlight_graph::file::{Registry, parse_pipeline};
use meshlight_graph::*;

const ATOMICS: wgpu::Features =
    wgpu::Features::TEXTURE_ATOMIC.union(wgpu::Features::TEXTURE_INT64_ATOMIC);

/// A rasteriser clearing `vis`: `texture` needs 64-bit texture atomics, `buffer` nothing.
struct Raster {
    name: &'static str,
    form: Visibility64,
}

impl Pass for Raster {
    fn implementation(&self) -> Implementation {
        Implementation::new(
            self.name,
            StageContract {
                stage: "raster",
                slots: vec![Slot::visibility64("vis", Access::ClearedReadWrite, "")],
            },
        )
    }
    fn setup(&self, ctx: &mut SetupContext) -> Result<()> {
        if self.form == Visibility64::Texture {
            ctx.require_features(ATOMICS);
        }
        Ok(())
    }
    fn record(&self, _: &mut RecordContext<'_>) -> Result<()> {
        Ok(())
    }
    fn visibility64(&self) -> Option<Visibility64> {
        Some(self.form)
    }
}

fn texture() -> Box<dyn Pass> {
    Box::new(Raster {
        name: "texture",
        form: Visibility64::Texture,
    })
}
fn buffer() -> Box<dyn Pass> {
    Box::new(Raster {
        name: "buffer",
        form: Visibility64::Buffer,
    })
}

/// Reads `vis` in whatever form it has; records which in a shader def.
struct Reader;

impl Pass for Reader {
    fn implementation(&self) -> Implementation {
        Implementation::new(
            "reader",
            StageContract {
                stage: "reader",
                slots: vec![
                    Slot::visibility64("vis", Access::StorageRead, ""),
                    Slot::buffer("out", Access::StorageWrite, Element::U32, ""),
                ],
            },
        )
    }
    fn setup(&self, ctx: &mut SetupContext) -> Result<()> {
        struct Defs(bool);
        impl ShaderDefs for Defs {
            fn shader_defs(&self) -> Vec<(&'static str, ShaderDef)> {
                vec![("VIS_TEXTURE", ShaderDef::Bool(self.0))]
            }
        }
        ctx.shader_defs(&Defs(ctx.is_texture("vis")));
        Ok(())
    }
    fn record(&self, _: &mut RecordContext<'_>) -> Result<()> {
        Ok(())
    }
}

/// A graph holding only the 8 × 4 visibility target `vis`, its form not yet chosen.
fn with_vis() -> GraphBuilder {
    let mut g = GraphBuilder::new();
    g.create_visibility64("vis", 8, 4);
    g
}

fn frame(choice: Choice) -> GraphBuilder {
    let mut g = with_vis();
    let out = g.create_buffer("out", BufferDesc::array(Element::U32, 1));
    g.add_choice("raster", choice, Bindings::new()).unwrap();
    g.add_pass("read", Reader, Bindings::new()).unwrap();
    g.export(out);
    g
}

fn reader_sees_texture(c: &CompiledGraph) -> bool {
    let p = &c.plan.passes[c.plan.pass_index("read").unwrap()];
    p.shader_defs
        .iter()
        .any(|(n, v)| n == "VIS_TEXTURE" && v.contains("true"))
}

#[test]
fn auto_takes_texture_atomics_where_present_and_the_target_follows() {
    let c = frame(Choice::auto(vec![texture(), buffer()]))
        .compile(&CompileOptions::new(ATOMICS))
        .unwrap();
    let raster = &c.plan.passes[0];
    assert_eq!(raster.implementation, "texture");
    let choice = raster.choice.as_ref().unwrap();
    assert_eq!(choice.selection, Selection::Auto);
    assert!(choice.candidates.iter().all(|c| c.missing.is_empty()));
    let vis = &c.plan.resources[c.plan.resource_index("vis").unwrap()];
    match &vis.info.desc {
        ResourceDesc::Texture(t) => {
            assert_eq!(t.format, wgpu::TextureFormat::R64Uint);
            assert_eq!((t.width, t.height), (8, 4));
        }
        other => panic!("vis should be a texture, is {other:?}"),
    }
    assert!(reader_sees_texture(&c));
}

#[test]
fn auto_falls_back_to_the_buffer_and_the_dumps_say_why() {
    let c = frame(Choice::auto(vec![texture(), buffer()]))
        .compile(&CompileOptions::new(wgpu::Features::empty()))
        .unwrap();
    let raster = &c.plan.passes[0];
    assert_eq!(raster.implementation, "buffer");
    let reason = raster.choice_reason().unwrap();
    assert!(
        reason.contains("`texture` needs") && reason.contains("TEXTURE_INT64_ATOMIC"),
        "{reason}"
    );
    let vis = &c.plan.resources[c.plan.resource_index("vis").unwrap()];
    assert!(matches!(vis.info.desc, ResourceDesc::Buffer(_)));
    assert!(!reader_sees_texture(&c));
    for dump in [
        dump::to_dot(&c.plan),
        dump::to_json(&c.plan, None),
        dump::to_html(&c.plan, "choice", None),
    ] {
        assert!(dump.contains("buffer (auto)") || dump.contains("\"auto\""));
        assert!(
            dump.contains("TEXTURE_INT64_ATOMIC"),
            "the reason is in every dump"
        );
    }
}

/// A rasteriser whose setup refuses its parameters (as an implementation refuses one it
/// does not support yet).
struct Refusing;

impl Pass for Refusing {
    fn implementation(&self) -> Implementation {
        Raster {
            name: "refusing",
            form: Visibility64::Buffer,
        }
        .implementation()
    }
    fn setup(&self, _: &mut SetupContext) -> Result<()> {
        Err(GraphError::parameter(
            "`cut` is not available here yet".to_string(),
        ))
    }
    fn record(&self, _: &mut RecordContext<'_>) -> Result<()> {
        Ok(())
    }
    fn visibility64(&self) -> Option<Visibility64> {
        Some(Visibility64::Buffer)
    }
}

#[test]
fn auto_passes_over_a_candidate_that_refuses_its_parameters_and_says_why() {
    let c = frame(Choice::auto(vec![Box::new(Refusing), buffer()]))
        .compile(&CompileOptions::new(ATOMICS))
        .unwrap();
    let raster = &c.plan.passes[0];
    assert_eq!(raster.implementation, "buffer");
    let reason = raster.choice_reason().unwrap();
    assert!(
        reason.contains("`refusing` refuses its parameters") && reason.contains("`cut`"),
        "{reason}"
    );
    // Named, its refusal is the error; with nothing accepting them, so is auto's.
    let named = frame(Choice::named(Box::new(Refusing), vec![buffer()]))
        .compile(&CompileOptions::new(ATOMICS))
        .err()
        .expect("a named candidate's refusal is an error")
        .to_string();
    assert!(named.contains("`cut` is not available"), "{named}");
    let none = frame(Choice::auto(vec![Box::new(Refusing)]))
        .compile(&CompileOptions::new(ATOMICS))
        .err()
        .expect("auto with every candidate refusing is an error")
        .to_string();
    assert!(
        none.contains("no implementation of stage `raster` accepts") && none.contains("`cut`"),
        "{none}"
    );
}

#[test]
fn a_named_implementation_the_adapter_lacks_names_the_one_that_would_run() {
    let err = frame(Choice::named(texture(), vec![buffer()]))
        .compile(&CompileOptions::new(wgpu::Features::empty()))
        .err()
        .unwrap();
    match &err {
        GraphError::MissingFeature {
            pass,
            features,
            instead,
            ..
        } => {
            assert_eq!(pass, "raster");
            assert!(features.contains("TEXTURE_INT64_ATOMIC"), "{features}");
            assert!(instead.contains("`buffer`"), "{instead}");
        }
        other => panic!("{other}"),
    }
    assert!(err.to_string().contains("`buffer`"), "{err}");
    // Named and runnable: it runs, marked as named.
    let c = frame(Choice::named(texture(), vec![buffer()]))
        .compile(&CompileOptions::new(ATOMICS))
        .unwrap();
    assert_eq!(c.plan.passes[0].implementation, "texture");
    assert_eq!(
        c.plan.passes[0].choice.as_ref().unwrap().selection,
        Selection::Named
    );
}

#[test]
fn auto_with_nothing_runnable_is_an_error() {
    let err = frame(Choice::auto(vec![texture()]))
        .compile(&CompileOptions::new(wgpu::Features::empty()))
        .err()
        .unwrap();
    assert!(
        matches!(&err, GraphError::MissingFeature { instead, .. } if instead.contains("`auto` found no")),
        "{err}"
    );
}

#[test]
fn a_texture_rasteriser_on_a_declared_u64_buffer_says_how_to_declare_it() {
    let mut g = GraphBuilder::new();
    let vis = g.create_buffer("vis", BufferDesc::array(Element::U64, 32));
    let o = g
        .add_boxed_pass("raster", texture(), Bindings::new().bind("vis", vis))
        .unwrap();
    g.export(o.buffer("vis").unwrap());
    let err = g.compile(&CompileOptions::new(ATOMICS)).err().unwrap();
    assert!(
        matches!(&err, GraphError::DescriptorMismatch { expected, .. } if expected.contains("visibility = {")),
        "{err}"
    );
}

#[test]
fn two_writers_wanting_different_forms_are_an_error() {
    let mut g = with_vis();
    g.add_boxed_pass("a", texture(), Bindings::new()).unwrap();
    let o = g.add_boxed_pass("b", buffer(), Bindings::new()).unwrap();
    g.export(o.written()[0].1);
    let err = g.compile(&CompileOptions::new(ATOMICS)).err().unwrap();
    assert!(err.to_string().contains("agree"), "{err}");
}

#[test]
fn candidates_of_different_stages_are_refused() {
    let mut g = with_vis();
    g.create_buffer("out", BufferDesc::array(Element::U32, 1));
    let err = g
        .add_choice(
            "mixed",
            Choice::auto(vec![texture(), Box::new(Reader)]),
            Bindings::new(),
        )
        .err()
        .unwrap();
    assert!(err.to_string().contains("share one contract"), "{err}");
}

fn registry() -> Registry {
    let mut r = Registry::new();
    r.register("raster", "texture", |_| Ok(texture()));
    r.register("raster", "buffer", |_| Ok(buffer()));
    r
}

const FILE: &str = r#"
[params]
width = 8
height = 4

[[resource]]
name = "vis"
kind = "exported"
visibility = { width_param = "width", height_param = "height" }

[[pass]]
name = "raster"
stage = "raster"
implementation = "IMPL"
"#;

#[test]
fn pipeline_files_say_auto_and_swap_the_target_form_with_one_line() {
    let mut r = registry();
    // Without a preference order, `auto` is unknown for the stage.
    let err = parse_pipeline(&FILE.replace("IMPL", "auto"), "f.toml", &r)
        .err()
        .unwrap();
    assert!(
        matches!(&err, GraphError::UnknownImplementation { known, .. } if known.contains("no `auto`")),
        "{err}"
    );
    r.prefer("raster", &["texture", "buffer"]);
    assert!(r.implementations("raster").contains(&"auto".to_string()));
    let plan = |imp: &str, features| {
        parse_pipeline(&FILE.replace("IMPL", imp), "f.toml", &r)
            .unwrap()
            .compile(&CompileOptions::new(features))
    };
    let on_lavapipe = plan("auto", wgpu::Features::empty()).unwrap();
    assert_eq!(on_lavapipe.plan.passes[0].implementation, "buffer");
    let on_nvidia = plan("auto", ATOMICS).unwrap();
    assert_eq!(on_nvidia.plan.passes[0].implementation, "texture");
    let vis = |c: &CompiledGraph| {
        c.plan.resources[c.plan.resource_index("vis").unwrap()]
            .info
            .desc
            .kind_name()
    };
    assert_eq!(vis(&on_lavapipe), "buffer");
    assert_eq!(vis(&on_nvidia), "texture");
    // The one-line swap to `texture`, on an adapter without texture atomics.
    let err = plan("texture", wgpu::Features::empty()).err().unwrap();
    assert!(
        matches!(&err, GraphError::MissingFeature { instead, .. } if instead.contains("`buffer`")),
        "{err}"
    );
    assert_eq!(vis(&plan("buffer", ATOMICS).unwrap()), "buffer");
}

#[test]
fn a_visibility_entry_takes_no_other_shape_and_no_history() {
    let r = registry();
    let both = FILE.replace("IMPL", "buffer").replace(
        "visibility = {",
        "buffer = { element = \"u64\", count = 32 }\nvisibility = {",
    );
    let err = parse_pipeline(&both, "f.toml", &r).err().unwrap();
    assert!(err.to_string().contains("exactly one of"), "{err}");
    let history = FILE
        .replace("IMPL", "buffer")
        .replace("kind = \"exported\"", "kind = \"history\"");
    let err = parse_pipeline(&history, "f.toml", &r).err().unwrap();
    assert!(err.to_string().contains("transient"), "{err}");
}

/// An adapter class with an order of its own changes what `auto` tries first there, and
/// the plan says so; other classes, and a named implementation, are unaffected.
#[test]
fn auto_follows_the_adapter_class_order_and_says_why() {
    let mut r = registry();
    r.prefer("raster", &["texture", "buffer"]);
    r.prefer_on(
        "raster",
        AdapterClass::FewGraphicsUnits,
        &["buffer"],
        "measured: buffers win there",
    );
    assert_eq!(
        r.preference("raster", AdapterClass::FewGraphicsUnits),
        Some(vec!["buffer".to_string(), "texture".to_string()])
    );
    let plan = |imp: &str, class| {
        parse_pipeline(&FILE.replace("IMPL", imp), "f.toml", &r)
            .unwrap()
            .compile(&CompileOptions::new(ATOMICS).with_class(class))
            .unwrap()
            .plan
    };
    let few = plan("auto", AdapterClass::FewGraphicsUnits);
    assert_eq!(few.passes[0].implementation, "buffer");
    let reason = few.passes[0].choice_reason().unwrap();
    assert!(
        reason.contains("few graphics units") && reason.contains("buffers win"),
        "{reason}"
    );
    let graphics = plan("auto", AdapterClass::Graphics);
    assert_eq!(graphics.passes[0].implementation, "texture");
    assert!(
        !graphics.passes[0]
            .choice_reason()
            .unwrap()
            .contains("buffers win")
    );
    // A named implementation is what runs, whatever the class prefers.
    let named = plan("texture", AdapterClass::FewGraphicsUnits);
    assert_eq!(named.passes[0].implementation, "texture");
}
