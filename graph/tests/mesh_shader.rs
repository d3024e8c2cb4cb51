//! Mesh programs: mesh-stage WGSL composes through the shader library, and a mesh pass
//! draws like the CPU where the adapter has mesh shaders; where it has not (lavapipe),
//! the graph reports the missing feature and everything else still opens and runs.

mod support;

use meshlight_graph::*;
use meshlight_shaders::{Capabilities, ShaderLibrary};
use support::rects::*;

const MESH: PassShader = support::support_shader!("test::mesh", "mesh.wgsl");

#[test]
fn mesh_stage_wgsl_composes_and_validates_through_the_shader_library() {
    let caps = Capabilities::MESH_SHADER
        | Capabilities::SHADER_INT64
        | Capabilities::SHADER_INT64_ATOMIC_MIN_MAX;
    let mut library = ShaderLibrary::new(caps).unwrap();
    let module = library
        .compose(&MESH, &[])
        .unwrap_or_else(|e| panic!("{e}"));
    let stages: Vec<(String, naga::ShaderStage)> = module
        .entry_points
        .iter()
        .map(|e| (e.name.clone(), e.stage))
        .collect();
    assert!(
        stages.contains(&("rect_ms".into(), naga::ShaderStage::Mesh)),
        "{stages:?}"
    );
    assert!(stages.contains(&("rect_fs".into(), naga::ShaderStage::Fragment)));
    // Without the capability the same source is refused, naming the problem.
    let mut plain =
        ShaderLibrary::new(Capabilities::SHADER_INT64 | Capabilities::SHADER_INT64_ATOMIC_MIN_MAX)
            .unwrap();
    assert!(plain.compose(&MESH, &[]).is_err());
}

fn mesh_graph(task: bool) -> GraphBuilder {
    let mut g = GraphBuilder::new();
    let rects = g.import_buffer(
        "rects",
        BufferDesc::array(Element::named("Rect", 32), RECTS.len() as u64),
        wgpu::BufferUsages::STORAGE,
    );
    let vis = g.create_buffer("vis", BufferDesc::array(Element::U64, (W * H) as u64));
    support::add_exported(
        &mut g,
        "mesh_raster",
        MeshRaster { task },
        Bindings::new().bind("rects", rects).bind("vis", vis),
        "vis",
    );
    g
}

/// Draws the rectangles with a mesh program, with or without a task stage.
struct MeshRaster {
    task: bool,
}

impl Pass for MeshRaster {
    fn implementation(&self) -> Implementation {
        Implementation::new(
            "mesh_shader",
            StageContract {
                stage: "hw_raster",
                slots: vec![
                    Slot::buffer("rects", Access::StorageRead, Element::named("Rect", 32), ""),
                    Slot::buffer("vis", Access::ClearedReadWrite, Element::U64, ""),
                ],
            },
        )
    }
    fn setup(&self, ctx: &mut SetupContext) -> Result<()> {
        ctx.require_features(
            wgpu::Features::SHADER_INT64 | wgpu::Features::SHADER_INT64_ATOMIC_MIN_MAX,
        );
        let layout = BindingLayout::with_visibility(
            "mesh_raster",
            wgpu::ShaderStages::TASK | wgpu::ShaderStages::MESH | wgpu::ShaderStages::FRAGMENT,
        )
        .slot(0, "rects")
        .visible_in(wgpu::ShaderStages::TASK | wgpu::ShaderStages::MESH)
        .slot(1, "vis")
        .visible_in(wgpu::ShaderStages::FRAGMENT)
        .uniform(2, "mesh_params");
        let program = if self.task {
            ProgramDesc::mesh(&MESH, Some("rect_ts"), "rect_ms_task")
        } else {
            ProgramDesc::mesh(&MESH, None, "rect_ms")
        };
        declare_masked_raster(ctx, program.fragment("rect_fs").layout(layout));
        Ok(())
    }
    fn record(&self, ctx: &mut RecordContext<'_>) -> Result<()> {
        let params = [W, H, 0, 0];
        let uniforms = [("mesh_params", bytemuck::cast_slice(&params))];
        // One task workgroup launches every rectangle's mesh workgroup.
        let groups = if self.task { 1 } else { RECTS.len() as u32 };
        record_masked_raster(ctx, &uniforms, |rp| rp.draw_mesh_tasks(groups, 1, 1))
    }
}

#[test]
fn a_mesh_pass_draws_like_the_cpu_where_the_adapter_has_mesh_shaders() {
    let adapter = GpuAdapter::select().unwrap_or_else(|e| panic!("{e}"));
    let has_mesh = adapter
        .features()
        .contains(wgpu::Features::EXPERIMENTAL_MESH_SHADER);
    for task in [false, true] {
        mesh_pass_against_the_cpu(&adapter, has_mesh, task);
    }
}

fn mesh_pass_against_the_cpu(adapter: &GpuAdapter, has_mesh: bool, task: bool) {
    let compiled = mesh_graph(task).compile(&CompileOptions::for_adapter(adapter));
    eprintln!(
        "{}: mesh shaders {}",
        adapter.info().name,
        if has_mesh { "present" } else { "absent" }
    );
    if !has_mesh {
        // Lavapipe: the capability is reported missing at compile time, by name …
        match compiled {
            Err(GraphError::MissingFeature { pass, features, .. }) => {
                assert_eq!(pass, "mesh_raster");
                assert!(features.contains("EXPERIMENTAL_MESH_SHADER"), "{features}");
            }
            other => panic!("{:?}", other.err()),
        }
        // … and asking for everything still opens a working device without it.
        let gpu = support::gpu();
        assert!(
            !gpu.features
                .contains(wgpu::Features::EXPERIMENTAL_MESH_SHADER)
        );
        return;
    }
    let compiled = compiled.unwrap();
    let gpu = GpuContext::with_available(compiled.plan.enabled_features).unwrap();
    let data: Vec<[u32; 8]> = RECTS
        .iter()
        .map(|([x0, y0, x1, y1], depth, id)| [*x0, *y0, *x1, *y1, *depth, *id, 0, 0])
        .collect();
    let rects = bytemuck::cast_slice(&data);
    let mut exec = support::run_frames(gpu, &compiled, ("rects", rects), 1);
    let got: Vec<u64> = support::read_export(&mut exec, "vis");
    assert_eq!(got, cpu_rects(), "task stage: {task}");
}
