//! What a two-pass frame leaves out while it does not test occlusion
//! (`adaptive_occlusion::SecondPass`), found in the compiled plan without a GPU: on the
//! shipped frame (with shadows and lights, planned for an NVIDIA H200 and for
//! lavapipe), exactly the second walk, cull, remap and rasterisers and their readbacks,
//! and the one pyramid; the `occlusion` view, whose `resolve` reads the second pass's
//! counters, cannot leave it out.

mod common;

use meshlight::graph::file::Pipeline;
use meshlight::graph::{AdapterClass, CompileOptions, Plan};
use meshlight::resolve::DebugView;
use meshlight_light_clustering::ClusteringSettings;
use meshlight_virtual_geometry::adaptive_occlusion::SecondPass;
use meshlight_virtual_geometry::frame_graph::{frame, is_second_pass};
use meshlight_virtual_geometry::{FrameSettings, GraphSource, ShadowSettings};

fn plan(settings: &FrameSettings, class: AdapterClass) -> (Plan, Pipeline) {
    let (data, _, _) = common::grey_scene();
    let f = frame(&GraphSource::Shipped, &data, settings).unwrap_or_else(|e| panic!("{e}"));
    let options = CompileOptions::new(wgpu::Features::all()).with_class(class);
    let compiled = f.graph.compile(&options).unwrap_or_else(|e| panic!("{e}"));
    (compiled.plan, f.pipeline)
}

#[test]
fn the_shipped_frames_second_pass_is_its_second_walk_cull_and_rasterisers() {
    let settings = FrameSettings {
        clustering: Some(ClusteringSettings::new([640, 360], 8)),
        shadows: Some(ShadowSettings::default()),
        ..FrameSettings::new(640, 360)
    };
    for class in [AdapterClass::FewGraphicsUnits, AdapterClass::Cpu] {
        let (plan, pipeline) = plan(&settings, class);
        let got = SecondPass::of(&plan, &pipeline).unwrap_or_else(|e| panic!("{class:?}: {e}"));
        let mut passes = got.passes.clone();
        passes.sort();
        assert_eq!(
            passes,
            [
                "cull_second",
                "fill_second",
                "hw_raster_second",
                "readback:hierarchy_counts_second",
                "readback:raster_counts_second",
                "readback:second_walk_count",
                "remap_second",
                "sw_raster_second",
            ],
            "{class:?}"
        );
        assert_eq!(got.pyramid, "depth_pyramid", "{class:?}");
    }
}

#[test]
fn the_occlusion_views_resolve_reads_the_second_pass_so_it_stays() {
    let settings = FrameSettings::new(320, 180).with_view(DebugView::Occlusion);
    let (plan, pipeline) = plan(&settings, AdapterClass::FewGraphicsUnits);
    match SecondPass::of(&plan, &pipeline) {
        Err(why) => assert!(why.contains("`resolve`"), "{why}"),
        Ok(p) => panic!("left out with the occlusion view: {:?}", p.passes),
    }
    // No second walk or cull: nothing to leave out.
    let mut one_pass = pipeline.clone();
    one_pass.passes.retain(|e| !is_second_pass(e));
    assert!(SecondPass::of(&plan, &one_pass).is_err());
}
