//! The renderer inside a host application, headless (lavapipe in CI): on a device the
//! host created it draws what a renderer that opened its own draws; into the host's own
//! colour and depth textures it draws that image and its depth; a host device without
//! the features the frame needs is refused, naming them and how to ask for them.

mod common;

use common::asset;
use meshlight::gpu_scene::SceneData;
use meshlight::gpu_scene::data::Limits;
use meshlight::graph::{GpuAdapter, GpuContext, GraphError};
use meshlight_virtual_geometry::scenes::{self, Placed};
use meshlight_virtual_geometry::{FrameSettings, GraphSource, HostTargets, Renderer};

const W: u32 = 192;
const H: u32 = 108;

fn field() -> Placed {
    scenes::field(SceneData::new(Limits::default()), asset(), 9).unwrap()
}

/// What a host does: its own instance, adapter and device, with `features`.
fn host_gpu(features: impl FnOnce(&wgpu::Adapter) -> wgpu::Features) -> GpuContext {
    let adapter = GpuAdapter::select().unwrap_or_else(|e| panic!("{e}"));
    let (instance, adapter) = (adapter.instance, adapter.adapter);
    let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
        label: Some("the host's device"),
        required_features: features(&adapter),
        required_limits: Renderer::required_limits(&adapter),
        ..Default::default()
    }))
    .expect("the host's device");
    GpuContext::from_host(instance, adapter, device, queue)
}

fn own_still(placed: &Placed, settings: FrameSettings) -> meshlight_virtual_geometry::Still {
    let mut r = Renderer::new(placed.data.clone(), settings, &GraphSource::Shipped)
        .unwrap_or_else(|e| panic!("{e}"));
    r.render_still(&placed.camera)
        .unwrap_or_else(|e| panic!("{e}"))
}

#[test]
fn a_renderer_on_the_hosts_device_draws_what_one_on_its_own_draws() {
    let placed = field();
    let settings = FrameSettings::new(W, H);
    let want = own_still(&placed, settings.clone());
    let gpu = host_gpu(|a| Renderer::required_features(a, &settings).unwrap());
    let mut r = Renderer::with_gpu(gpu, placed.data.clone(), settings, &GraphSource::Shipped)
        .unwrap_or_else(|e| panic!("{e}"));
    let got = r
        .render_still(&placed.camera)
        .unwrap_or_else(|e| panic!("{e}"));
    assert!(want.counts.visible > 0, "{:?}", want.counts);
    assert_eq!(got.counts, want.counts);
    assert_eq!(got.rgba, want.rgba);
}

#[test]
fn a_host_device_without_the_frames_features_is_refused_naming_them() {
    let placed = field();
    let settings = FrameSettings::new(W, H);
    let needed = {
        let adapter = GpuAdapter::select().unwrap_or_else(|e| panic!("{e}"));
        Renderer::required_features(&adapter.adapter, &settings).unwrap()
    };
    // Every rasteriser needs 64-bit integers in shaders.
    assert!(needed.contains(wgpu::Features::SHADER_INT64), "{needed:?}");
    let gpu = host_gpu(|_| wgpu::Features::empty());
    match Renderer::with_gpu(gpu, placed.data, settings, &GraphSource::Shipped) {
        Err(GraphError::DeviceLacksFeatures { features, instead }) => {
            assert!(features.contains("SHADER_INT64"), "{features}");
            assert!(instead.contains("Renderer::required_features"), "{instead}");
        }
        Err(e) => panic!("another error: {e}"),
        Ok(_) => panic!("a device without 64-bit integers was accepted"),
    }
}

#[test]
fn drawn_into_the_hosts_textures_the_frame_is_the_image_and_its_depth() {
    let placed = field();
    let want = own_still(
        &placed,
        FrameSettings {
            depth: true,
            ..FrameSettings::new(W, H)
        },
    );
    let format = wgpu::TextureFormat::Bgra8UnormSrgb;
    let settings = FrameSettings {
        host: Some(HostTargets {
            color: format,
            depth: true,
        }),
        ..FrameSettings::new(W, H)
    };
    let gpu = host_gpu(|a| Renderer::required_features(a, &settings).unwrap());
    let texture = |format, usage| {
        gpu.device.create_texture(&wgpu::TextureDescriptor {
            label: Some("the host's target"),
            size: wgpu::Extent3d {
                width: W,
                height: H,
                depth_or_array_layers: 1,
            },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format,
            usage: usage | wgpu::TextureUsages::COPY_SRC,
            view_formats: &[],
        })
    };
    let color = texture(format, wgpu::TextureUsages::RENDER_ATTACHMENT);
    let depth = texture(
        wgpu::TextureFormat::Depth32Float,
        wgpu::TextureUsages::RENDER_ATTACHMENT,
    );
    let mut r = Renderer::with_gpu(gpu, placed.data.clone(), settings, &GraphSource::Shipped)
        .unwrap_or_else(|e| panic!("{e}"));
    // A frame may grow its lists: draw until one drops nothing, as a host's loop does.
    for _ in 0..4 {
        r.draw(&placed.camera, &color, Some(&depth)).unwrap();
        r.executor.finish().unwrap();
    }
    // The host's image is BGRA through an sRGB target: the still's bytes, to a step.
    let gpu = &r.executor.gpu;
    let shown = meshlight_testing::read_texture(gpu, &color, wgpu::TextureAspect::All);
    let off = shown
        .chunks(4)
        .zip(want.rgba.chunks(4))
        .filter(|(b, w)| {
            [b[2], b[1], b[0]]
                .iter()
                .zip(&w[..3])
                .any(|(x, y)| x.abs_diff(*y) > 1)
        })
        .count();
    assert_eq!(off, 0, "{off} pixels differ from the still");
    let host_depth = meshlight_testing::read_texture(gpu, &depth, wgpu::TextureAspect::DepthOnly);
    let mut own = Renderer::new(
        placed.data.clone(),
        FrameSettings {
            depth: true,
            ..FrameSettings::new(W, H)
        },
        &GraphSource::Shipped,
    )
    .unwrap();
    own.render_still(&placed.camera).unwrap();
    let own_depth = own.executor.read_texture("depth").unwrap();
    assert!(
        bytemuck::cast_slice::<u8, f32>(&own_depth)
            .iter()
            .any(|d| *d > 0.0),
        "the scene covers nothing"
    );
    assert_eq!(host_depth, own_depth, "the host's depth is not the frame's");
    // Without host targets, `draw` says what to set.
    let mut plain =
        Renderer::new(placed.data, FrameSettings::new(W, H), &GraphSource::Shipped).unwrap();
    match plain.draw(&placed.camera, &color, None) {
        Err(GraphError::Setting { setting, .. }) => assert_eq!(setting, "FrameSettings::host"),
        other => panic!("{:?}", other.err()),
    }
}
