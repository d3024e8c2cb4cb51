//! What compile and the pipeline-file registry refuse, with no device: bad params,
//! buffers too small for them, targets of the wrong format.

use meshlight_gpu_scene::gpu::elements;
use meshlight_graph::file::Registry;
use meshlight_graph::*;
use meshlight_pass_brute_force::{BruteForce, DEPTH_FORMAT, IDS_FORMAT, register};
use meshlight_testing::{parameter_message, params};

const USAGE: wgpu::BufferUsages = wgpu::BufferUsages::STORAGE
    .union(wgpu::BufferUsages::INDEX)
    .union(wgpu::BufferUsages::COPY_DST);
const TEXTURE_USAGE: wgpu::TextureUsages = wgpu::TextureUsages::RENDER_ATTACHMENT;

/// Buffer sizes and the id target's format of a one-pass graph.
struct Setup {
    indices: u64,
    instances: u64,
    ids_format: wgpu::TextureFormat,
}

const FITS: Setup = Setup {
    indices: 300,
    instances: 4,
    ids_format: IDS_FORMAT,
};

fn compile(pass: BruteForce, s: Setup) -> Result<CompiledGraph> {
    let mut g = GraphBuilder::new();
    let positions = g.import_buffer(
        "positions",
        BufferDesc::array(Element::VEC4_F32, 100),
        USAGE,
    );
    let indices = g.import_buffer("indices", BufferDesc::array(Element::U32, s.indices), USAGE);
    let instances = g.import_buffer(
        "instances",
        BufferDesc::array(elements::INSTANCE, s.instances),
        USAGE,
    );
    let depth = g.import_texture(
        "depth",
        TextureDesc::d2(DEPTH_FORMAT, 96, 64),
        TEXTURE_USAGE,
    );
    let ids = g.import_texture("ids", TextureDesc::d2(s.ids_format, 96, 64), TEXTURE_USAGE);
    g.add_pass(
        "baseline",
        pass,
        Bindings::new()
            .bind("positions", positions)
            .bind("indices", indices)
            .bind("instances", instances)
            .bind("depth", depth)
            .bind("ids", ids),
    )?;
    g.compile(&CompileOptions::new(wgpu::Features::empty()))
}

fn pass() -> BruteForce {
    BruteForce {
        width: 96,
        height: 64,
        index_count: 300,
        instance_count: 4,
    }
}

#[test]
fn a_fitting_graph_compiles_with_its_draw_program() {
    let compiled = compile(pass(), FITS).unwrap();
    let json = dump::to_json(&compiled.plan, None);
    assert!(
        json.contains("instanced_draw") && json.contains("draw_vs"),
        "{json}"
    );
}

#[test]
fn bad_params_in_code_fail_compile_naming_the_pass_and_the_param() {
    let cases = [
        (BruteForce { width: 0, ..pass() }, "`width`"),
        (
            BruteForce {
                height: 0,
                ..pass()
            },
            "`height`",
        ),
        (
            BruteForce {
                index_count: 299,
                ..pass()
            },
            "`index_count`",
        ),
        (
            BruteForce {
                instance_count: 0,
                ..pass()
            },
            "`instance_count`",
        ),
    ];
    for (bad, name) in cases {
        match compile(bad, FITS) {
            Err(GraphError::Parameter { pass, message }) => {
                assert_eq!(pass, "baseline");
                assert!(message.contains(name), "{message}");
            }
            Err(other) => panic!("{name}: {other}"),
            Ok(_) => panic!("{name}: compiled"),
        }
    }
}

#[test]
fn buffers_smaller_than_the_params_need_are_refused_by_slot() {
    for (s, slot) in [
        (
            Setup {
                indices: 299,
                ..FITS
            },
            "indices",
        ),
        (
            Setup {
                instances: 3,
                ..FITS
            },
            "instances",
        ),
    ] {
        match compile(pass(), s) {
            Err(GraphError::DescriptorMismatch { slot: got, .. }) => assert_eq!(got, slot),
            Err(other) => panic!("{slot}: {other}"),
            Ok(_) => panic!("{slot}: compiled"),
        }
    }
    match compile(
        pass(),
        Setup {
            ids_format: wgpu::TextureFormat::R32Float,
            ..FITS
        },
    ) {
        Err(GraphError::DescriptorMismatch { slot, .. }) => assert_eq!(slot, "ids"),
        Err(other) => panic!("{other}"),
        Ok(_) => panic!("an R32Float id target compiled"),
    }
}

fn build(text: &str) -> Result<Box<dyn Pass>> {
    let mut registry = Registry::new();
    register(&mut registry);
    registry.build("brute_force", "instanced_draw", &params(text))
}

#[test]
fn pipeline_files_get_the_pass_and_errors_naming_what_to_change() {
    let pass = build("width = 96\nheight = 64\nindex_count = 300\ninstance_count = 4").unwrap();
    assert_eq!(pass.implementation().name, "instanced_draw");
    assert_eq!(pass.implementation().contract.stage, "brute_force");
    let m = parameter_message(build(
        "width = 0\nheight = 64\nindex_count = 300\ninstance_count = 4",
    ));
    assert!(m.contains("`width`"), "{m}");
    let m = parameter_message(build(
        "width = 96\nheight = 64\nindex_count = 100\ninstance_count = 4",
    ));
    assert!(m.contains("`index_count`") && m.contains("100"), "{m}");
    // Leaving the size out is the same as zero.
    let m = parameter_message(build("index_count = 300\ninstance_count = 4"));
    assert!(m.contains("`width`"), "{m}");
}
