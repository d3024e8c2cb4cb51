//! `view --pool-mb`: the viewer streams its scene (no window needed): frames run, pages
//! arrive, nothing is refused, and its HTML page shows the streamer's figures.

mod common;

use meshlight_viewer::viewer::Viewer;

#[test]
fn the_viewer_streams_a_scene_given_a_pool() {
    let mut options = common::unlit_options();
    options.scene.pool_mb = Some(8);
    let mut viewer = Viewer::new(options, None).unwrap_or_else(|e| panic!("{e}"));
    for _ in 0..12 {
        viewer.frame().unwrap_or_else(|e| panic!("{e}"));
    }
    let stats = viewer
        .renderer
        .streaming
        .as_ref()
        .expect("the viewer streams")
        .stats();
    assert!(stats.loaded_total > 0, "{stats:?}");
    assert_eq!(stats.failed_total, 0, "{stats:?}");
    let page =
        std::env::temp_dir().join(format!("meshlight-view-stream-{}.html", std::process::id()));
    viewer.write_html(&page).unwrap();
    let html = std::fs::read_to_string(&page).unwrap();
    std::fs::remove_file(&page).unwrap();
    for fact in [
        "pages resident",
        "of 8.0 MiB",
        "streamer CPU",
        "lists, plan, scene, upload",
    ] {
        assert!(html.contains(fact), "{fact} missing from the viewer's page");
    }
}
