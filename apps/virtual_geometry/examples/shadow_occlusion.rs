//! How much two-pass occlusion could save the sun's shadow: each cascade's cut (the
//! hierarchy walk's candidates culled by `cull_lod`'s CPU reference) is rasterised by
//! the software rasteriser's reference into the cascade's map, and every cluster of the
//! cut is tested against that map's own depth pyramid with the occlusion test the cull
//! runs. This frame's finished map is the best occluder a second pass could have, and a
//! cluster cannot hide itself (the test takes the nearest point of its sphere), so the
//! clusters it hides bound what two-pass occlusion could skip in the cascade.
//!
//! `cargo run --release -p meshlight-virtual-geometry --example shadow_occlusion -- [procedural|MESH] [INSTANCES] [WIDTH HEIGHT] [RESOLUTION]`
//!
//! The defaults are the benchmark's default scene: 1,024 procedural meshes at
//! 1920×1080, four 2048² cascades to the default shadow distance, the default sun.

use meshlight::cull_lod::Thresholds;
use meshlight::cull_lod::cpu::{classify, occlusion_test};
use meshlight::fill_clusters::{WalkParams, cpu_walk};
use meshlight::gpu_scene::SceneData;
use meshlight::gpu_scene::data::Limits;
use meshlight::shaders::cpu::occlusion::DepthPyramid;
use meshlight_virtual_geometry::scenes;
use meshlight_virtual_geometry::setup::ShadowRequest;
use meshlight_virtual_geometry::shadows::ShadowFrame;
use std::path::Path;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let arg = |i: usize, default: &str| args.get(i).cloned().unwrap_or(default.to_string());
    let mesh = arg(0, "procedural");
    let instances: u32 = arg(1, "1024").parse()?;
    let viewport = [arg(2, "1920").parse()?, arg(3, "1080").parse()?];
    let resolution: u32 = arg(4, "2048").parse()?;
    let asset = scenes::load_asset(Path::new(&mesh), meshlight::scene::DEFAULT_SEGMENTS)?;
    let limits = Limits::for_binding_size(u32::MAX as u64);
    let placed = scenes::field(SceneData::new(limits), &asset, instances)?;
    let data = &placed.data;
    let shadows = ShadowRequest {
        cascades: Some(4),
        resolution: Some(resolution),
        ..ShadowRequest::default()
    }
    .settings(data, &placed.camera, viewport, true)
    .ok_or("no shadows")?;
    let sun = meshlight::resolve::settings::Settings::default().light_direction;
    let frame = ShadowFrame::new(&placed.camera, viewport, sun, &shadows, 0, 1.0)?;
    println!(
        "{instances} × {mesh} at {}×{}, {} cascades of {resolution}² to {:.0} units",
        viewport[0], viewport[1], shadows.cascades.count, shadows.cascades.distance
    );
    let thresholds = Thresholds {
        lod_threshold_px: 1.0,
        hardware: false,
        ..Thresholds::default()
    };
    // The camera's view first, measured alike: what occlusion finds there shows the
    // measure can find it.
    let camera = placed.camera.view(viewport, 0, None);
    let views: Vec<(String, _, [u32; 2])> =
        std::iter::once(("camera".to_string(), camera, viewport))
            .chain(
                frame
                    .cascades
                    .iter()
                    .enumerate()
                    .map(|(k, c)| (format!("cascade {k}"), c.view, [resolution; 2])),
            )
            .collect();
    let rows: Vec<String> = std::thread::scope(|s| {
        let handles: Vec<_> = views
            .iter()
            .map(|(name, view, [width, height])| {
                let (width, height) = (*width, *height);
                s.spawn(move || {
                    let params = WalkParams {
                        capacity: u32::MAX,
                        ..WalkParams::default()
                    };
                    let walk = cpu_walk(data, view, &params, 0.0);
                    let cut: Vec<_> = walk
                        .clusters
                        .iter()
                        .copied()
                        .filter(|&c| {
                            let d = classify(data, view, c, &thresholds);
                            d.in_frustum && d.in_cut
                        })
                        .collect();
                    let map = meshlight::sw_raster::cpu::rasterize(data, view, &cut, width, height);
                    let pyramid = DepthPyramid::from_visibility(&map, width, height);
                    let triangles =
                        |c: &meshlight::shaders::cpu::layout::Cluster| -> u64 {
                            data.meshlets[c.meshlet as usize].triangle_count() as u64
                        };
                    let hidden: Vec<_> = cut
                        .iter()
                        .filter(|&&c| occlusion_test(data, view, c, &pyramid, false).2)
                        .collect();
                    let all: u64 = cut.iter().map(triangles).sum();
                    let hid: u64 = hidden.iter().map(|c| triangles(c)).sum();
                    format!(
                        "{name}: {} instances walked, {} nodes tested, {} candidates; {} clusters, {all} triangles; hidden by its own finished map: {} clusters ({:.1} %), {hid} triangles ({:.1} %)",
                        walk.visible_instances.len(),
                        walk.counts[0],
                        walk.clusters.len(),
                        cut.len(),
                        hidden.len(),
                        100.0 * hidden.len() as f64 / cut.len().max(1) as f64,
                        100.0 * hid as f64 / all.max(1) as f64
                    )
                })
            })
            .collect();
        handles
            .into_iter()
            .map(|h| h.join().expect("a cascade's thread"))
            .collect()
    });
    for row in rows {
        println!("{row}");
    }
    Ok(())
}
