//! The LOD-0 reference `meshlight bench --scenario lod-quality` compares each threshold's
//! images with: the same frame at LOD threshold 0 draws exactly LOD 0, through the same
//! passes, so that only the LOD differs between the images it compares.

mod common;

use common::asset;
use meshlight::gpu_scene::SceneData;
use meshlight_virtual_geometry::scenes;
use meshlight_virtual_geometry::{FrameSettings, GraphSource, Renderer};

/// Levels of the meshlets the mesh's copy drew at `lod_threshold_px`, and whether each
/// LOD-0 meshlet was drawn.
fn drawn_at(lod_threshold_px: f32) -> (Vec<u32>, Vec<bool>) {
    let placed = scenes::single(SceneData::new(Default::default()), asset()).unwrap();
    let settings = FrameSettings {
        lod_threshold_px: Some(lod_threshold_px),
        occlusion: false,
        keep_visibility: true,
        ..FrameSettings::new(320, 180)
    };
    let mut r = Renderer::new(placed.data, settings, &GraphSource::Shipped).unwrap();
    let still = r.render_still(&placed.camera).unwrap();
    assert!(!still.counts.overflowed(), "{:?}", still.counts);
    let meshlets = asset().meshlets();
    let mut lod0 = vec![false; meshlets.len()];
    let mut levels = Vec::new();
    for c in r
        .drawn_clusters()
        .unwrap()
        .iter()
        .filter(|c| c.instance == 0)
    {
        let level = meshlets[c.meshlet as usize].level();
        levels.push(level);
        if level == 0 {
            lod0[c.meshlet as usize] = true;
        }
    }
    (levels, lod0)
}

#[test]
fn threshold_0_draws_every_lod0_meshlet_and_nothing_coarser() {
    let (levels, lod0) = drawn_at(0.0);
    assert!(levels.iter().all(|&l| l == 0), "{levels:?}");
    // The whole mesh is in view: every LOD-0 meshlet, each once.
    let want = asset().meshlets().iter().filter(|m| m.level() == 0).count();
    assert_eq!(levels.len(), want);
    assert_eq!(lod0.iter().filter(|&&d| d).count(), want);
    // At the default threshold the same view draws coarser levels: the reference differs.
    let (levels, _) = drawn_at(1.0);
    assert!(levels.iter().any(|&l| l > 0), "{levels:?}");
}
