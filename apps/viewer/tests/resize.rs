//! A resize renders at the new size from the next frame, without a new renderer.

mod common;

#[test]
fn resize_changes_the_output_size_and_still_renders() {
    let _x = common::xvfb();
    let (_event_loop, mut v) = common::windowed(common::small_options());
    v.run_frames(2).expect("frames");
    let (w, h, rgba) = v.read_image().expect("image");
    assert_eq!((w, h, rgba.len()), (160, 96, 160 * 96 * 4));
    let adapter = v.renderer.adapter.clone();
    v.resize(224, 130).expect("resize");
    v.run_frames(3).expect("frames after the resize");
    let (w, h, rgba) = v.read_image().expect("image");
    assert_eq!((w, h, rgba.len()), (224, 130, 224 * 130 * 4));
    assert!(
        common::colours(&rgba) > 50,
        "the resized frame shows no scene"
    );
    assert_eq!(v.renderer.adapter, adapter);
    assert_eq!(v.error, None);
}
