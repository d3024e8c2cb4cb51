//! What `resolve` declares, with no device: with its depth targets unbound, one compute
//! program and no render program (so the frame records no render pass); each bound
//! target adds its own fullscreen render program; the same from a pipeline file; the
//! `pyramid` slot adds a binding and nothing else.

use meshlight_gpu_scene::SceneData;
use meshlight_gpu_scene::data::Limits;
use meshlight_gpu_scene::gpu::{elements, import_for};
use meshlight_graph::*;
use meshlight_pass_resolve::{COLOR_FORMAT, DEPTH_FORMAT, PYRAMID_FORMAT, Resolve};

const W: u32 = 96;
const H: u32 = 64;

/// A graph of `resolve` alone, with the optional textures named in `optional` created
/// (and exported, so nothing culls them).
fn plan(pass: Resolve, optional: &[&str]) -> Result<Plan> {
    let mut g = GraphBuilder::new();
    import_for(&SceneData::new(Limits::default()), &mut g);
    let storage = wgpu::BufferUsages::STORAGE;
    let clusters = g.import_buffer(
        "raster_clusters",
        BufferDesc::array(elements::CLUSTER, 64),
        storage,
    );
    let counts = g.import_buffer("raster_counts", BufferDesc::array(Element::U32, 8), storage);
    let vis = g.import_buffer(
        "visbuffer",
        BufferDesc::array(Element::U64, (W * H) as u64),
        storage,
    );
    let color = g.create_texture("color", TextureDesc::d2(COLOR_FORMAT, W, H));
    g.export(color);
    let mut bindings = Bindings::new()
        .bind("visbuffer", vis)
        .bind("raster_clusters", clusters)
        .bind("raster_counts", counts)
        .bind("color", color);
    for &name in optional {
        let desc = match name {
            "pyramid" => TextureDesc::d2(PYRAMID_FORMAT, W / 2, H / 2).with_full_mips(),
            _ => TextureDesc::d2(DEPTH_FORMAT, W, H),
        };
        let t = g.import_texture(name, desc, wgpu::TextureUsages::all());
        bindings = bindings.bind(name, t);
    }
    let out = g.add_pass("resolve", pass, bindings)?;
    for &name in optional {
        if name != "pyramid" {
            g.export(out.texture(name)?);
        }
    }
    Ok(g.compile(&CompileOptions::new(wgpu::Features::empty()))?
        .plan)
}

/// (program, kind) of the pass.
fn programs(plan: &Plan) -> Vec<(String, &'static str)> {
    plan.passes[plan.pass_index("resolve").unwrap()]
        .programs
        .iter()
        .map(|p| (p.name.clone(), p.kind))
        .collect()
}

/// A program's name and kind.
type Program = (&'static str, &'static str);

fn names(list: &[Program]) -> Vec<(String, &'static str)> {
    list.iter().map(|(n, k)| (n.to_string(), *k)).collect()
}

#[test]
fn unbound_depth_targets_declare_no_render_program() {
    let plan = plan(Resolve::new(W, H), &[]).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(programs(&plan), names(&[("shade", "compute")]));
    // Nothing of the depth targets is in the plan, so nothing allocates or clears them.
    assert!(plan.resource_index("depth").is_none());
    assert!(plan.resource_index("material_depth").is_none());
    let dot = dump::to_dot(&plan);
    assert!(!dot.contains("depth-target"), "{dot}");
}

#[test]
fn each_bound_depth_target_adds_its_fullscreen_render_program() {
    let cases: [(&[&str], &[Program]); 3] = [
        (&["depth"], &[("depth", "render"), ("shade", "compute")]),
        (
            &["material_depth"],
            &[("material_depth", "render"), ("shade", "compute")],
        ),
        (
            &["depth", "material_depth"],
            &[
                ("depth", "render"),
                ("material_depth", "render"),
                ("shade", "compute"),
            ],
        ),
    ];
    for (bound, want) in cases {
        let plan = plan(Resolve::new(W, H), bound).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(programs(&plan), names(want), "{bound:?}");
        for name in bound {
            let r = &plan.resources[plan.resource_index(name).unwrap()];
            assert!(
                r.texture_usage
                    .contains(wgpu::TextureUsages::RENDER_ATTACHMENT),
                "{name}"
            );
        }
    }
}

#[test]
fn the_pyramid_slot_adds_a_binding_and_no_program() {
    let plan = plan(Resolve::new(W, H), &["pyramid"]).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(programs(&plan), names(&[("shade", "compute")]));
    let pass = &plan.passes[plan.pass_index("resolve").unwrap()];
    assert!(
        pass.shader_defs
            .iter()
            .any(|(n, v)| n == "PYRAMID" && v.contains("true")),
        "{:?}",
        pass.shader_defs
    );
    let r = &plan.resources[plan.resource_index("pyramid").unwrap()];
    assert!(
        r.texture_usage
            .contains(wgpu::TextureUsages::TEXTURE_BINDING)
    );
}
