//! `meshlight view --frames N --screenshot FILE` from a fixed camera writes the image
//! `Renderer::render_still` renders for that camera and size (what `meshlight render`
//! writes), byte for byte: the window's frames and the still run the same graph from the
//! same camera, and the frames before differ only in the occlusion history they leave,
//! which changes which culling pass draws a cluster, never the pixel.

#[path = "../../viewer/tests/common/mod.rs"]
mod common;

use glam::Vec3;
use meshlight::gpu_scene::Camera;
use meshlight_virtual_geometry::{Renderer, SceneOptions, setup};

#[test]
fn screenshot_equals_the_renderers_still() {
    let x = common::xvfb();
    let dir = common::tempdir("shot");
    let shot = dir.join("shot.png");
    let (position, target) = (Vec3::new(6.0, 3.0, 9.0), Vec3::new(0.0, 0.5, 0.0));
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_meshlight"))
        .args([
            "view",
            "--segments",
            "16",
            "--instances",
            "16",
            "--width",
            "160",
            "--height",
            "96",
            "--frames",
            "4",
            "--no-vsync",
            "--camera",
            "6,3,9:0,0.5,0",
            "--screenshot",
        ])
        .arg(&shot)
        .env("DISPLAY", &x.display)
        .output()
        .expect("cannot run meshlight view");
    assert!(
        out.status.success(),
        "meshlight view failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    // It says what it wrote.
    let said = String::from_utf8_lossy(&out.stdout);
    assert!(
        said.contains("wrote") && said.contains(&shot.display().to_string()),
        "{said}"
    );
    let decoder = png::Decoder::new(std::io::BufReader::new(
        std::fs::File::open(&shot).expect("no screenshot written"),
    ));
    let mut reader = decoder.read_info().expect("not a PNG");
    let mut shown = vec![0; reader.output_buffer_size().expect("a size")];
    let info = reader.next_frame(&mut shown).expect("PNG data");
    shown.truncate(info.buffer_size());
    assert_eq!((info.width, info.height), (160, 96));

    // The still, set up as `meshlight render` sets it up.
    let mut options = SceneOptions::new(160, 96);
    options.segments = 16;
    options.instances = 16;
    let scene = setup(&options).unwrap_or_else(|e| panic!("{e}"));
    let camera = Camera {
        position,
        target,
        ..scene.camera
    };
    let mut renderer = Renderer::new(scene.data, scene.settings, &scene.source).expect("renderer");
    renderer.lights = scene.lights;
    let still = renderer.render_still(&camera).expect("still");
    assert!(
        common::colours(&still.rgba) > 50,
        "the still shows no scene"
    );
    let off = common::differing(&shown, &still.rgba, 0);
    let pixels = 160 * 96;
    assert_eq!(
        off, 0,
        "{off} of {pixels} pixels of the screenshot differ from the renderer's still"
    );
}
