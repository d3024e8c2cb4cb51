//! Choosing another implementation of a stage through the viewer's API changes the plan
//! and not the image; one the adapter cannot run is reported and the last good graph
//! keeps rendering.

mod common;

#[test]
fn switching_an_implementation_changes_the_plan_not_the_image() {
    let _x = common::xvfb();
    let (file, _) = common::pipeline_copy("impl");
    let mut o = common::unlit_options();
    o.scene.pipeline = Some(file);
    let (_event_loop, mut v) = common::windowed(o);
    let stage = "depth_pyramid";
    assert!(
        v.choices()
            .iter()
            .any(|(s, names)| s == stage && names.len() > 1),
        "{stage} offers no choice: {:?}",
        v.choices()
    );
    v.run_frames(4).expect("frames");
    let before = v.read_image().expect("image").2;
    let was = v.implementations()[stage].clone();
    let other = if was == "single_pass" {
        "two_pass"
    } else {
        "single_pass"
    };
    v.select_implementation(stage, other)
        .unwrap_or_else(|e| panic!("{stage} = {other}: {e}"));
    let ran: Vec<&str> = v
        .renderer
        .compiled
        .plan
        .passes
        .iter()
        .filter(|p| p.stage == stage)
        .map(|p| p.implementation)
        .collect();
    assert!(
        !ran.is_empty() && ran.iter().all(|i| *i == other),
        "plan runs {ran:?}"
    );
    v.run_frames(4).expect("frames");
    let after = v.read_image().expect("image").2;
    assert_eq!(
        common::differing(&before, &after, 0),
        0,
        "{stage} {was} → {other} changed the image"
    );

    // The software rasteriser on 64-bit texture atomics, where the adapter has none
    // (lavapipe): an error, and the last good graph still runs. Where the adapter has
    // them, the image must not change either.
    let features = v.renderer.executor.gpu.adapter.features();
    let result = v.select_implementation("sw_raster", "texture");
    if features.contains(wgpu::Features::TEXTURE_INT64_ATOMIC) {
        result.unwrap_or_else(|e| panic!("sw_raster = texture: {e}"));
    } else {
        let e = result.expect_err("texture atomics accepted on an adapter without them");
        assert_eq!(v.error.as_deref(), Some(e.as_str()));
        assert!(
            v.implementations()["sw_raster"] != "texture",
            "the failed choice replaced the graph"
        );
    }
    v.run_frames(3).expect("frames");
    let last = v.read_image().expect("image").2;
    assert_eq!(common::differing(&before, &last, 0), 0);
}
