//! The adapter-specific rasterisers: `auto` picks what the adapter runs (the portable
//! `buffer` and `indirect_draw` on lavapipe) and renders the image the explicit choice
//! renders; every combination of software and hardware rasteriser renders the same
//! frame where the adapter has what it needs (an NVIDIA GPU through Vulkan), and is the
//! typed error naming the missing feature and the implementation that would run where
//! it has not.

use meshlight::gpu_scene::SceneData;
use meshlight::gpu_scene::data::Limits;
use meshlight::graph::{GpuAdapter, GraphError};
use meshlight::resolve::DebugView;
use meshlight::scene::{BuildOptions, MeshletAsset, build_asset, procedural_mesh};
use meshlight_virtual_geometry::scenes::{self, Placed};
use meshlight_virtual_geometry::{FrameSettings, GraphSource, Renderer, Still};
use std::sync::OnceLock;

const W: u32 = 192;
const H: u32 = 108;

fn placed() -> Placed {
    static ASSET: OnceLock<MeshletAsset> = OnceLock::new();
    let asset = ASSET.get_or_init(|| {
        build_asset(&procedural_mesh(24), &BuildOptions::default(), &mut |_| {})
            .unwrap()
            .asset
    });
    scenes::field(SceneData::new(Limits::default()), asset, 16).unwrap()
}

fn settings(view: DebugView, sw: &str, hw: &str) -> FrameSettings {
    FrameSettings {
        // Low, so that at this size both rasterisers draw.
        sw_threshold_px: Some(16.0),
        ..FrameSettings::new(W, H)
    }
    .with_view(view)
    .with_implementation(meshlight::sw_raster::STAGE, sw)
    .with_implementation(meshlight::hw_raster::STAGE, hw)
}

fn render(placed: &Placed, settings: FrameSettings) -> Result<(Still, Renderer), GraphError> {
    let mut r = Renderer::new(placed.data.clone(), settings, &GraphSource::Shipped)?;
    let still = r.render_still(&placed.camera)?;
    Ok((still, r))
}

fn chosen(r: &Renderer, pass: &str) -> &'static str {
    let plan = &r.compiled.plan;
    plan.passes[plan.pass_index(pass).unwrap()].implementation
}

fn differing(a: &[u8], b: &[u8]) -> usize {
    a.chunks(4).zip(b.chunks(4)).filter(|(p, q)| p != q).count()
}

struct Has {
    texture: bool,
    mesh: bool,
}

fn adapter() -> Has {
    let adapter = GpuAdapter::select().unwrap_or_else(|e| panic!("{e}"));
    let f = adapter.features();
    let has = Has {
        texture: f.contains(meshlight::sw_raster::TEXTURE_FEATURES),
        mesh: f.contains(wgpu::Features::EXPERIMENTAL_MESH_SHADER),
    };
    eprintln!(
        "{}: 64-bit texture atomics {}, mesh shaders {}",
        adapter.info().name,
        has.texture,
        has.mesh
    );
    has
}

#[test]
fn auto_picks_what_the_adapter_runs_and_renders_the_explicit_choices_image() {
    let has = adapter();
    let placed = placed();
    for view in [DebugView::Shaded, DebugView::Clusters] {
        let (auto, r) = render(&placed, settings(view, "auto", "auto")).unwrap();
        let (sw, hw) = (chosen(&r, "sw_raster"), chosen(&r, "hw_raster"));
        // Lavapipe has neither: the portable implementations run.
        assert_eq!(sw, if has.texture { "texture" } else { "buffer" });
        assert_eq!(
            hw,
            if has.mesh {
                "mesh_shader"
            } else {
                "indirect_draw"
            }
        );
        let reason = r.compiled.plan.passes[r.compiled.plan.pass_index("sw_raster").unwrap()]
            .choice_reason()
            .unwrap()
            .to_string();
        if !has.texture {
            assert!(reason.contains("TEXTURE_INT64_ATOMIC"), "{reason}");
        }
        let (explicit, _) = render(&placed, settings(view, sw, hw)).unwrap();
        assert!(
            auto.counts.software > 0 && auto.counts.hardware > 0,
            "{:?}",
            auto.counts
        );
        assert_eq!(auto.counts, explicit.counts, "{view:?}");
        assert_eq!(differing(&auto.rgba, &explicit.rgba), 0, "{view:?}");
    }
}

#[test]
fn every_combination_renders_the_same_frame_or_names_what_is_missing_and_what_runs() {
    let has = adapter();
    let placed = placed();
    let view = DebugView::Shaded;
    let (base, _) = render(&placed, settings(view, "buffer", "indirect_draw")).unwrap();
    let pixels = (W * H) as usize;
    for (sw, hw) in [
        ("texture", "indirect_draw"),
        ("buffer", "mesh_shader"),
        ("texture", "mesh_shader"),
    ] {
        let runs = (sw == "buffer" || has.texture) && (hw == "indirect_draw" || has.mesh);
        match render(&placed, settings(view, sw, hw)) {
            Ok((still, r)) => {
                assert!(runs, "{sw} + {hw} ran on an adapter without its feature");
                assert_eq!((chosen(&r, "sw_raster"), chosen(&r, "hw_raster")), (sw, hw));
                assert_eq!(still.counts.visible, base.counts.visible, "{sw} + {hw}");
                let diff = differing(&still.rgba, &base.rgba);
                eprintln!(
                    "{sw} + {hw}: {diff} of {pixels} pixels differ from buffer + indirect_draw"
                );
                if hw == "indirect_draw" {
                    // Same values in another kind of memory: the same image.
                    assert_eq!(diff, 0, "{sw} + {hw}");
                } else {
                    // The hardware orders equal-depth writes its own way: a handful of
                    // pixels at most.
                    assert!(diff * 100 <= pixels, "{sw} + {hw}: {diff} pixels differ");
                }
            }
            Err(GraphError::MissingFeature {
                pass,
                features,
                instead,
                ..
            }) => {
                assert!(
                    !runs,
                    "{sw} + {hw} failed on an adapter that has its features"
                );
                let (wanted, portable) = if sw == "texture" && !has.texture {
                    ("TEXTURE_INT64_ATOMIC", "`buffer`")
                } else {
                    ("EXPERIMENTAL_MESH_SHADER", "`indirect_draw`")
                };
                assert!(features.contains(wanted), "{pass}: {features}");
                assert!(instead.contains(portable), "{pass}: {instead}");
                eprintln!("{sw} + {hw}: {pass} needs {features}; {instead}");
            }
            Err(other) => panic!("{sw} + {hw}: {other}"),
        }
    }
    // An unknown name lists the known ones.
    let err = render(&placed, settings(view, "bufer", "auto"))
        .err()
        .unwrap();
    let text = err.to_string();
    assert!(
        text.contains("`bufer`") && text.contains("known: buffer, texture, auto"),
        "{text}"
    );
}
