//! A 64-bit visibility target as an `R64Uint` storage texture with atomics: the graph gives
//! it `STORAGE_ATOMIC`, asks for the texture-atomic features, and the raster matches the
//! CPU where the adapter has them; where it has not (lavapipe) compile names the feature.

mod support;

use meshlight_graph::*;
use support::rects::*;

const SHADER: PassShader = support::support_shader!(
    "test::texture_atomics",
    "texture_atomics.wgsl",
    modules: [RECT_VERTICES_WGSL]
);

/// Stage `raster` with a visibility target that may be a buffer or a texture; this
/// implementation takes the texture.
struct TextureRaster {
    vertices: u32,
}

impl Pass for TextureRaster {
    fn implementation(&self) -> Implementation {
        Implementation::new(
            "texture_atomics",
            StageContract {
                stage: "raster",
                slots: vec![
                    rects_slot(),
                    Slot::visibility64("vis", Access::ClearedReadWrite, ""),
                ],
            },
        )
    }
    fn setup(&self, ctx: &mut SetupContext) -> Result<()> {
        ctx.require_features(wgpu::Features::SHADER_INT64);
        let layout = BindingLayout::render("raster")
            .slot(0, "rects")
            .visible_in(wgpu::ShaderStages::VERTEX)
            .slot(1, "vis")
            .visible_in(wgpu::ShaderStages::FRAGMENT);
        let program = ProgramDesc::render(&SHADER, "rect_vs").fragment("rect_fs");
        declare_masked_raster(ctx, program.layout(layout));
        Ok(())
    }
    fn record(&self, ctx: &mut RecordContext<'_>) -> Result<()> {
        record_masked_raster(ctx, &[], |rp| rp.draw(0..self.vertices, 0..1))
    }
}

fn graph(vertices: u32) -> GraphBuilder {
    let mut g = GraphBuilder::new();
    let rects = import_rect_vertices(&mut g, vertices);
    let vis = g.create_texture("vis", TextureDesc::d2(wgpu::TextureFormat::R64Uint, W, H));
    let out = g.create_buffer("out", BufferDesc::array(Element::U64, (W * H) as u64));
    let drawn = g
        .add_pass(
            "raster",
            TextureRaster { vertices },
            Bindings::new().bind("rects", rects).bind("vis", vis),
        )
        .unwrap();
    let vis = drawn.texture("vis").unwrap();
    copy_out(&mut g, "copy_out", wgpu::TextureFormat::R64Uint, vis, out);
    g
}

#[test]
fn an_r64uint_visibility_texture_rasterises_like_the_cpu_where_atomics_exist() {
    let adapter = GpuAdapter::select().unwrap_or_else(|e| panic!("{e}"));
    let vertices = rect_vertices();
    let compiled = graph(vertices.len() as u32).compile(&CompileOptions::for_adapter(&adapter));
    let atomics = wgpu::Features::TEXTURE_ATOMIC | wgpu::Features::TEXTURE_INT64_ATOMIC;
    eprintln!(
        "{}: 64-bit texture atomics {}",
        adapter.info().name,
        if adapter.features().contains(atomics) {
            "present"
        } else {
            "absent"
        }
    );
    if !adapter.features().contains(atomics) {
        match compiled {
            Err(GraphError::MissingFeature { pass, features, .. }) => {
                assert_eq!(pass, "raster");
                assert!(features.contains("TEXTURE_INT64_ATOMIC"), "{features}");
            }
            other => panic!("{:?}", other.err()),
        }
        return;
    }
    let compiled = compiled.unwrap();
    let vis = &compiled.plan.resources[compiled.plan.resource_index("vis").unwrap()];
    assert!(
        vis.texture_usage
            .contains(wgpu::TextureUsages::STORAGE_ATOMIC)
    );
    let gpu = adapter.open(compiled.plan.enabled_features).unwrap();
    let rects = bytemuck::cast_slice(&vertices);
    let mut exec = support::run_frames(gpu, &compiled, ("rects", rects), 2);
    let got: Vec<u64> = support::read_export(&mut exec, "out");
    assert_eq!(got, cpu_rects());
}
