//! What the viewer's tests share: an X server of their own (Xvfb, started through
//! scripts/ensure-xvfb.sh on a free display), a small scene, image comparison.

#![allow(dead_code)]

use meshlight_viewer::{Viewer, ViewerOptions};
use std::path::{Path, PathBuf};

/// The repository's root.
pub fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..")
}

pub use meshlight_testing::xvfb::Xvfb;

/// Starts Xvfb on a free display and points this process at it (call before any window
/// is opened); fails the test if it cannot, never skipped.
pub fn xvfb() -> Xvfb {
    let x = meshlight_testing::xvfb::start(&tempdir("xvfb"));
    use_display(&x);
    x
}

/// Points this process at `x` (each test binary has one test, so no other thread reads
/// the environment meanwhile).
fn use_display(x: &Xvfb) {
    // SAFETY: called at the start of the test binary's only test, before any thread of
    // it reads the environment.
    unsafe { std::env::set_var("DISPLAY", &x.display) };
    // The Vulkan loader's Wayland probe only needs a directory of our own.
    if std::env::var_os("XDG_RUNTIME_DIR").is_none() {
        let dir = tempdir("runtime");
        // SAFETY: as above.
        unsafe { std::env::set_var("XDG_RUNTIME_DIR", &dir) };
    }
}

/// A copy of the shipped pipeline file in a fresh directory, for a test to edit while
/// the viewer watches it: its path and its text.
pub fn pipeline_copy(what: &str) -> (PathBuf, String) {
    let file = tempdir(what).join("frame.toml");
    let text = std::fs::read_to_string(root().join("pipelines/virtual_geometry.toml"))
        .expect("the shipped pipeline");
    std::fs::write(&file, &text).expect("write");
    (file, text)
}

/// A fresh directory under the temporary directory.
pub fn tempdir(what: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!(
        "meshlight-viewer-test-{what}-{}-{:?}",
        std::process::id(),
        std::time::SystemTime::now()
            .duration_since(std::time::UNIX_EPOCH)
            .expect("a clock after 1970")
            .as_nanos()
    ));
    std::fs::create_dir_all(&dir).expect("cannot make a temporary directory");
    dir
}

/// A small scene: 16 copies of a 4,096-triangle procedural mesh at 160 × 96.
pub fn small_options() -> ViewerOptions {
    let mut o = ViewerOptions::new(160, 96);
    o.scene.segments = 16;
    o.scene.instances = 16;
    o.no_vsync = true;
    o
}

/// [`small_options`] without lights, for tests whose subject is not the lights: their
/// frames skip light clustering. (A lit frame renders the same bytes every time too:
/// the resolve sums a froxel's lights in fixed point, whatever order populate's atomics
/// list them in; `the_lit_frame_renders_the_same_bytes_every_time` checks it.)
pub fn unlit_options() -> ViewerOptions {
    let mut o = small_options();
    o.scene.lights = Some(0);
    o
}

/// A viewer in a window of its own on the test's X server.
pub fn windowed(options: ViewerOptions) -> (winit::event_loop::EventLoop<()>, Viewer) {
    let (event_loop, window) =
        meshlight_viewer::app::test_window(options.scene.width, options.scene.height)
            .unwrap_or_else(|e| panic!("{e}"));
    let viewer = Viewer::new(options, Some(window)).unwrap_or_else(|e| panic!("{e}"));
    (event_loop, viewer)
}

/// Pixels (of RGBA8 images of one size) whose channels differ by more than `tolerance`.
pub fn differing(a: &[u8], b: &[u8], tolerance: u8) -> usize {
    assert_eq!(a.len(), b.len(), "the images differ in size");
    a.chunks(4)
        .zip(b.chunks(4))
        .filter(|(p, q)| p.iter().zip(*q).any(|(x, y)| x.abs_diff(*y) > tolerance))
        .count()
}

/// Distinct colours of an RGBA8 image: a frame that rendered geometry has many.
pub fn colours(rgba: &[u8]) -> usize {
    let mut c: Vec<&[u8]> = rgba.chunks(4).collect();
    c.sort_unstable();
    c.dedup();
    c.len()
}

/// The scene of [`small_options`] (with its lights) in a bare renderer, set up as
/// `meshlight render` sets it up, and the scene's camera.
pub fn bare_renderer() -> (
    meshlight_virtual_geometry::Renderer,
    meshlight::gpu_scene::Camera,
) {
    use meshlight_virtual_geometry::{Renderer, setup};
    let scene = setup(&small_options().scene).unwrap_or_else(|e| panic!("{e}"));
    let mut renderer = Renderer::new(scene.data, scene.settings, &scene.source).expect("renderer");
    renderer.lights = scene.lights;
    (renderer, scene.camera)
}
