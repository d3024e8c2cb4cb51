//! The host example (`examples/host`) under an X server of the test's own, on lavapipe:
//! a winit + wgpu application that owns the window, the device and the swapchain draws
//! its triangles and has meshlight draw the scene into the same frame. Its screenshot
//! must be the depth composite of the two: where the host's near triangle covers, its
//! colour; where its far triangle covers and the scene is drawn, the scene; the scene
//! everywhere else it is drawn. The scene's own image and depth come from the library
//! rendering the same scene with the same matrices on a device of its own.

#[path = "../scene.rs"]
#[allow(dead_code)] // the test draws no host triangles itself
mod scene;

use meshlight::gpu_scene::Camera;
use meshlight_virtual_geometry::{FrameSettings, GraphSource, Renderer};
use std::path::{Path, PathBuf};

const W: u32 = 320;
const H: u32 = 200;

/// The example's binary, which cargo builds for this test.
fn example() -> PathBuf {
    PathBuf::from(env!("CARGO_BIN_EXE_host"))
}

fn read_png(path: &Path) -> Vec<u8> {
    let decoder = png::Decoder::new(std::io::BufReader::new(
        std::fs::File::open(path).unwrap_or_else(|e| panic!("{}: {e}", path.display())),
    ));
    let mut reader = decoder.read_info().expect("a PNG");
    let mut rgba = vec![0; reader.output_buffer_size().expect("a size")];
    let info = reader.next_frame(&mut rgba).expect("PNG data");
    assert_eq!((info.width, info.height), (W, H));
    rgba.truncate(info.buffer_size());
    rgba
}

fn rgb(colour: [f32; 3]) -> [u8; 3] {
    colour.map(|c| (c * 255.0).round() as u8)
}

#[test]
fn the_hosts_triangles_and_the_scene_composite_by_depth() {
    let dir = std::env::temp_dir().join(format!("meshlight-host-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let x = meshlight_testing::xvfb::start(&dir);
    let shot = |draw: &str| {
        let path = dir.join(format!("{draw}.png"));
        let out = std::process::Command::new(example())
            .args([
                "--frames",
                "3",
                "--width",
                &W.to_string(),
                "--height",
                &H.to_string(),
            ])
            .args(["--draw", draw, "--screenshot"])
            .arg(&path)
            .env("DISPLAY", &x.display)
            .output()
            .expect("the example runs");
        assert!(
            out.status.success(),
            "--draw {draw}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
        read_png(&path)
    };
    let both = shot("both");
    let host = shot("host");

    // The scene alone, as the library draws it on a device of its own, with its depth.
    let gpu_limits = meshlight::graph::GpuAdapter::select()
        .unwrap_or_else(|e| panic!("{e}"))
        .adapter
        .limits();
    let s = scene::host_scene(W, H, &gpu_limits).unwrap_or_else(|e| panic!("{e}"));
    let camera = Camera::from_matrices(s.view, s.projection).unwrap();
    let settings = FrameSettings {
        depth: true,
        ..FrameSettings::new(W, H)
    };
    let mut r =
        Renderer::new(s.data, settings, &GraphSource::Shipped).unwrap_or_else(|e| panic!("{e}"));
    let still = r.render_still(&camera).unwrap_or_else(|e| panic!("{e}"));
    let depth: Vec<f32> = bytemuck::pod_collect_to_vec(&r.executor.read_texture("depth").unwrap());

    let (near, far) = (rgb(scene::NEAR_COLOUR), rgb(scene::FAR_COLOUR));
    let mut counts = [0usize; 4];
    let mut wrong = Vec::new();
    for (i, got) in both.chunks(4).enumerate() {
        let own = &host[i * 4..i * 4 + 3];
        let drawn = depth[i] > 0.0;
        let (case, want): (usize, &[u8]) = if own == near {
            (0, &near)
        } else if own == far && drawn {
            (1, &still.rgba[i * 4..i * 4 + 3])
        } else if own == far {
            (2, &far)
        } else {
            (3, &still.rgba[i * 4..i * 4 + 3])
        };
        counts[case] += 1;
        // The image passes through an sRGB swapchain: a step of rounding either way.
        if got[..3].iter().zip(want).any(|(g, w)| g.abs_diff(*w) > 1) {
            wrong.push((
                i % W as usize,
                i / W as usize,
                got[..3].to_vec(),
                want.to_vec(),
            ));
        }
    }
    // The near triangle covers part of the mesh, the mesh part of the far triangle.
    let near_over_scene = host
        .chunks(4)
        .zip(&depth)
        .filter(|(p, d)| p[..3] == near && **d > 0.0)
        .count();
    assert!(
        near_over_scene > 200,
        "the near triangle covers {near_over_scene} scene pixels"
    );
    assert!(counts[1] > 500 && counts[2] > 500, "{counts:?}");
    assert!(
        wrong.is_empty(),
        "{} of {} pixels are not the composite, e.g. {:?}",
        wrong.len(),
        W * H,
        &wrong[..wrong.len().min(5)]
    );
}
