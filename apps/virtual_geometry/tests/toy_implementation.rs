//! A stage implementation written outside the workspace crates, as a user writes one: its
//! code (this file), its WGSL (`toy/remap_square.wgsl`) and one `register` line. It
//! implements `remap_dispatch` with a square grid instead of a row as wide as allowed, and
//! the shipped pipeline file renders through it by naming it (lavapipe in CI).

use meshlight::gpu_scene::SceneData;
use meshlight::gpu_scene::data::Limits;
use meshlight::graph::file::{Params, Registry};
use meshlight::graph::{
    BindingLayout, Implementation, Pass, PassShader, ProgramDesc, RecordContext, Result,
    SetupContext, Workgroups,
};
use meshlight::remap_dispatch;
use meshlight::scene::{BuildOptions, build_asset, procedural_mesh};
use meshlight_virtual_geometry::scenes;
use meshlight_virtual_geometry::{FrameSettings, GraphSource, Renderer};
use std::path::PathBuf;

const SHADER: PassShader = PassShader {
    name: "toy::remap_square",
    source: include_str!("toy/remap_square.wgsl"),
    file_path: "apps/virtual_geometry/tests/toy/remap_square.wgsl",
    modules: &[],
};

/// `remap_dispatch`, implementation `square`.
struct Square {
    count_word: u32,
}

impl Pass for Square {
    fn implementation(&self) -> Implementation {
        Implementation::new("square", remap_dispatch::contract())
    }
    fn setup(&self, ctx: &mut SetupContext) -> Result<()> {
        ctx.min_bytes("count", (self.count_word as u64 + 1) * 4);
        ctx.program(
            "square",
            ProgramDesc::compute(&SHADER, "square").layout(BindingLayout::from_shader("square")),
        );
        Ok(())
    }
    fn record(&self, ctx: &mut RecordContext<'_>) -> Result<()> {
        let params = [self.count_word, 0, 0, 0];
        ctx.dispatch_compute(
            "square",
            &[("params", bytemuck::cast_slice(&params))],
            Workgroups::Direct([1, 1, 1]),
        )
    }
}

impl Square {
    fn from_params(params: &Params) -> Result<Self> {
        params.only(&["count_word"])?;
        Ok(Self {
            count_word: params.u32("count_word", 0)?,
        })
    }
}

fn registry() -> Registry {
    let mut r = meshlight::registry();
    r.register(remap_dispatch::STAGE, "square", Square::from_params);
    r
}

#[test]
fn a_toy_implementation_registered_outside_renders_from_a_pipeline_file() {
    let shipped = PathBuf::from(concat!(
        concat!(env!("CARGO_MANIFEST_DIR"), "/../.."),
        "/pipelines/virtual_geometry.toml"
    ));
    let text = std::fs::read_to_string(&shipped).unwrap();
    let named = "stage = \"remap_dispatch\"\nimplementation = \"single_thread\"";
    assert_eq!(
        text.matches(named).count(),
        3,
        "both culling passes remap, and the shadow cascades' (taken out without shadows)"
    );
    let dir = std::env::temp_dir().join(format!("meshlight-toy-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let toy = dir.join("virtual_geometry_square.toml");
    std::fs::write(
        &toy,
        text.replace(
            named,
            "stage = \"remap_dispatch\"\nimplementation = \"square\"",
        ),
    )
    .unwrap();

    let asset = build_asset(&procedural_mesh(24), &BuildOptions::default(), &mut |_| {})
        .unwrap()
        .asset;
    let placed = scenes::field(SceneData::new(Limits::default()), &asset, 16).unwrap();
    let render = |source: GraphSource| {
        let mut r = Renderer::new(placed.data.clone(), FrameSettings::new(192, 108), &source)
            .unwrap_or_else(|e| panic!("{e}"));
        let still = r
            .render_still(&placed.camera)
            .unwrap_or_else(|e| panic!("{e}"));
        (still, r)
    };
    let (want, _) = render(GraphSource::File(shipped));
    let (got, r) = render(GraphSource::FileWith(toy.clone(), registry));
    let plan = &r.compiled.plan;
    let remaps: Vec<&str> = plan
        .passes
        .iter()
        .filter(|p| p.name.starts_with("remap"))
        .map(|p| p.implementation)
        .collect();
    assert_eq!(remaps, ["square", "square"]);
    assert!(got.counts.software > 0, "{:?}", got.counts);
    assert_eq!(got.counts, want.counts);
    assert_eq!(
        got.rgba, want.rgba,
        "the square grid draws what the row draws"
    );

    // Without the registration the file's implementation is an error naming the known ones.
    match Renderer::new(
        placed.data.clone(),
        FrameSettings::new(192, 108),
        &GraphSource::File(toy),
    ) {
        Err(e) => {
            let text = e.to_string();
            assert!(
                text.contains("square") && text.contains("single_thread"),
                "{text}"
            );
        }
        Ok(_) => panic!("an unregistered implementation loaded"),
    }
}
