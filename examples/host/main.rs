//! A host application that embeds meshlight: a plain winit + wgpu program that owns the
//! window, the device and the swapchain, draws two triangles of its own with a depth
//! buffer, and has meshlight draw its virtual-geometry scene into the same frame,
//! composited by depth (one triangle in front of the mesh, one behind it).
//!
//!     cargo run --release -p meshlight-example-host [-- --frames N --screenshot out/host.png]
//!
//! `--draw host|meshlight|both` leaves one side out (the test compares the three),
//! `--width`/`--height` size the window. What meshlight needs from the host is marked
//! `meshlight:` below.

mod scene;

use meshlight::gpu_scene::Camera;
use meshlight::graph::GpuContext;
use meshlight_virtual_geometry::{FrameSettings, GraphSource, HostTargets, Renderer};
use std::sync::Arc;
use winit::application::ApplicationHandler;
use winit::event::WindowEvent;
use winit::event_loop::{ActiveEventLoop, EventLoop};
use winit::window::{Window, WindowId};

type Error = Box<dyn std::error::Error>;
const DEPTH: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;

struct Options {
    frames: Option<u64>,
    screenshot: Option<std::path::PathBuf>,
    width: u32,
    height: u32,
    host: bool,
    meshlight: bool,
}

fn options() -> Result<Options, Error> {
    let mut o = Options {
        frames: None,
        screenshot: None,
        width: 960,
        height: 540,
        host: true,
        meshlight: true,
    };
    let mut args = std::env::args().skip(1);
    while let Some(flag) = args.next() {
        let mut value = || args.next().ok_or(format!("{flag} needs a value"));
        match flag.as_str() {
            "--frames" => o.frames = Some(value()?.parse()?),
            "--screenshot" => o.screenshot = Some(value()?.into()),
            "--width" => o.width = value()?.parse()?,
            "--height" => o.height = value()?.parse()?,
            "--draw" => {
                (o.host, o.meshlight) = match value()?.as_str() {
                    "host" => (true, false),
                    "meshlight" => (false, true),
                    "both" => (true, true),
                    other => {
                        return Err(format!("--draw {other}: use host, meshlight or both").into());
                    }
                }
            }
            other => return Err(format!("unknown argument {other}").into()),
        }
    }
    Ok(o)
}

/// Everything the host owns, and the renderer it lends its device to.
struct Host {
    window: Arc<Window>,
    surface: wgpu::Surface<'static>,
    device: wgpu::Device,
    queue: wgpu::Queue,
    depth: wgpu::Texture,
    pipeline: wgpu::RenderPipeline,
    vertices: wgpu::Buffer,
    uniforms: wgpu::BindGroup,
    renderer: Renderer,
    camera: Camera,
    frames: u64,
}

fn new_host(window: Arc<Window>, o: &Options) -> Result<Host, Error> {
    let mut desc = wgpu::InstanceDescriptor::new_without_display_handle();
    desc.backends = wgpu::Backends::from_env().unwrap_or(wgpu::Backends::PRIMARY);
    let instance = wgpu::Instance::new(desc);
    let surface = instance.create_surface(window.clone())?;
    let adapter = pollster::block_on(instance.request_adapter(&wgpu::RequestAdapterOptions {
        compatible_surface: Some(&surface),
        ..Default::default()
    }))?;
    let caps = surface.get_capabilities(&adapter);
    let format = caps
        .formats
        .iter()
        .copied()
        .find(|f| f.is_srgb())
        .unwrap_or(caps.formats[0]);
    // meshlight: the frame's settings name the host's targets; the device gets the
    // features meshlight needs on this adapter.
    let settings = FrameSettings {
        host: Some(HostTargets {
            color: format,
            depth: true,
        }),
        ..FrameSettings::new(o.width, o.height)
    };
    let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
        required_features: Renderer::required_features(&adapter, &settings)?,
        required_limits: Renderer::required_limits(&adapter),
        ..Default::default()
    }))?;
    let mut usage = wgpu::TextureUsages::RENDER_ATTACHMENT;
    if o.screenshot.is_some() {
        usage |= wgpu::TextureUsages::COPY_SRC;
        if !caps.usages.contains(wgpu::TextureUsages::COPY_SRC) {
            return Err("--screenshot: this surface cannot be copied from".into());
        }
    }
    let config = wgpu::SurfaceConfiguration {
        usage,
        format,
        width: o.width,
        height: o.height,
        present_mode: wgpu::PresentMode::AutoVsync,
        desired_maximum_frame_latency: 2,
        alpha_mode: caps.alpha_modes[0],
        view_formats: vec![],
        color_space: wgpu::SurfaceColorSpace::Auto,
    };
    surface.configure(&device, &config);
    let scene = scene::host_scene(o.width, o.height, &device.limits())?;
    let (pipeline, vertices, uniforms) = host_pipeline(&device, format, &scene)?;
    // meshlight: the host's camera, and a renderer on the host's device.
    let camera = Camera::from_matrices(scene.view, scene.projection)?;
    let gpu = GpuContext::from_host(instance, adapter, device.clone(), queue.clone());
    let renderer = Renderer::with_gpu(gpu, scene.data, settings, &GraphSource::Shipped)?;
    Ok(Host {
        depth: depth_texture(&device, o.width, o.height),
        window,
        surface,
        device,
        queue,
        pipeline,
        vertices,
        uniforms,
        renderer,
        camera,
        frames: 0,
    })
}

const SHADER: &str = "
@group(0) @binding(0) var<uniform> view_projection: mat4x4<f32>;
struct Out { @builtin(position) position: vec4<f32>, @location(0) colour: vec3<f32> }
@vertex fn vs(@location(0) p: vec3<f32>, @location(1) c: vec3<f32>) -> Out {
    return Out(view_projection * vec4(p, 1.0), c);
}
@fragment fn fs(i: Out) -> @location(0) vec4<f32> { return vec4(i.colour, 1.0); }
";

/// The host's own drawing: coloured triangles, depth-tested reverse-Z (nearer is
/// greater) against what is already in the depth buffer.
fn host_pipeline(
    device: &wgpu::Device,
    format: wgpu::TextureFormat,
    scene: &scene::HostScene,
) -> Result<(wgpu::RenderPipeline, wgpu::Buffer, wgpu::BindGroup), Error> {
    use wgpu::util::DeviceExt;
    let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some("host"),
        source: wgpu::ShaderSource::Wgsl(SHADER.into()),
    });
    let pipeline = device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
        label: Some("host triangles"),
        layout: None,
        vertex: wgpu::VertexState {
            module: &module,
            entry_point: Some("vs"),
            compilation_options: Default::default(),
            buffers: &[Some(wgpu::VertexBufferLayout {
                array_stride: 24,
                step_mode: wgpu::VertexStepMode::Vertex,
                attributes: &wgpu::vertex_attr_array![0 => Float32x3, 1 => Float32x3],
            })],
        },
        primitive: wgpu::PrimitiveState::default(),
        depth_stencil: Some(wgpu::DepthStencilState {
            format: DEPTH,
            depth_write_enabled: Some(true),
            depth_compare: Some(wgpu::CompareFunction::Greater),
            stencil: Default::default(),
            bias: Default::default(),
        }),
        multisample: Default::default(),
        fragment: Some(wgpu::FragmentState {
            module: &module,
            entry_point: Some("fs"),
            compilation_options: Default::default(),
            targets: &[Some(format.into())],
        }),
        multiview_mask: None,
        cache: None,
    });
    let init = |label, contents: &[u8], usage| {
        device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some(label),
            contents,
            usage,
        })
    };
    let vertices = init(
        "vertices",
        bytemuck::cast_slice(&scene.vertices),
        wgpu::BufferUsages::VERTEX,
    );
    let matrix = scene.projection * scene.view;
    let uniform = init(
        "view_projection",
        bytemuck::bytes_of(&matrix),
        wgpu::BufferUsages::UNIFORM,
    );
    let uniforms = device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some("host uniforms"),
        layout: &pipeline.get_bind_group_layout(0),
        entries: &[wgpu::BindGroupEntry {
            binding: 0,
            resource: uniform.as_entire_binding(),
        }],
    });
    Ok((pipeline, vertices, uniforms))
}

fn depth_texture(device: &wgpu::Device, width: u32, height: u32) -> wgpu::Texture {
    device.create_texture(&wgpu::TextureDescriptor {
        label: Some("host depth"),
        size: wgpu::Extent3d {
            width,
            height,
            depth_or_array_layers: 1,
        },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format: DEPTH,
        usage: wgpu::TextureUsages::RENDER_ATTACHMENT,
        view_formats: &[],
    })
}

impl Host {
    /// One frame: meshlight draws the scene into the swapchain image and the depth
    /// buffer, then the host draws over both.
    fn frame(&mut self, o: &Options) -> Result<wgpu::SurfaceTexture, Error> {
        let frame = match self.surface.get_current_texture() {
            wgpu::CurrentSurfaceTexture::Success(t)
            | wgpu::CurrentSurfaceTexture::Suboptimal(t) => t,
            other => return Err(format!("no swapchain image: {other:?}").into()),
        };
        if o.meshlight {
            // meshlight: one call per frame, submitted before the host's commands.
            self.renderer
                .draw(&self.camera, &frame.texture, Some(&self.depth))?;
        }
        // Over what meshlight drew, or over nothing.
        let colour_load = match o.meshlight {
            true => wgpu::LoadOp::Load,
            false => wgpu::LoadOp::Clear(wgpu::Color::BLACK),
        };
        let depth_load = match o.meshlight {
            true => wgpu::LoadOp::Load,
            false => wgpu::LoadOp::Clear(0.0),
        };
        let view = frame.texture.create_view(&Default::default());
        let depth = self.depth.create_view(&Default::default());
        let mut encoder = self.device.create_command_encoder(&Default::default());
        {
            let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("host"),
                color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                    view: &view,
                    depth_slice: None,
                    resolve_target: None,
                    ops: wgpu::Operations {
                        load: colour_load,
                        store: wgpu::StoreOp::Store,
                    },
                })],
                depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                    view: &depth,
                    depth_ops: Some(wgpu::Operations {
                        load: depth_load,
                        store: wgpu::StoreOp::Store,
                    }),
                    stencil_ops: None,
                }),
                timestamp_writes: None,
                occlusion_query_set: None,
                multiview_mask: None,
            });
            if o.host {
                pass.set_pipeline(&self.pipeline);
                pass.set_bind_group(0, &self.uniforms, &[]);
                pass.set_vertex_buffer(0, self.vertices.slice(..));
                pass.draw(0..6, 0..1);
            }
        }
        self.queue.submit([encoder.finish()]);
        self.frames += 1;
        Ok(frame)
    }

    /// The swapchain image as RGBA8 rows, for `--screenshot`.
    fn screenshot(&self, texture: &wgpu::Texture, path: &std::path::Path) -> Result<(), Error> {
        let (w, h) = (texture.width(), texture.height());
        let row = (4 * w).next_multiple_of(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT);
        let buffer = self.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("screenshot"),
            size: u64::from(row * h),
            usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
            mapped_at_creation: false,
        });
        let mut encoder = self.device.create_command_encoder(&Default::default());
        encoder.copy_texture_to_buffer(
            texture.as_image_copy(),
            wgpu::TexelCopyBufferInfo {
                buffer: &buffer,
                layout: wgpu::TexelCopyBufferLayout {
                    offset: 0,
                    bytes_per_row: Some(row),
                    rows_per_image: None,
                },
            },
            texture.size(),
        );
        self.queue.submit([encoder.finish()]);
        buffer.slice(..).map_async(wgpu::MapMode::Read, |_| {});
        self.device.poll(wgpu::PollType::wait_indefinitely())?;
        let bgra = matches!(
            texture.format(),
            wgpu::TextureFormat::Bgra8UnormSrgb | wgpu::TextureFormat::Bgra8Unorm
        );
        let mapped = buffer.get_mapped_range(..)?;
        let mut rgba = Vec::with_capacity((4 * w * h) as usize);
        for y in 0..h {
            for px in mapped[(y * row) as usize..][..(4 * w) as usize].chunks(4) {
                rgba.extend(if bgra {
                    [px[2], px[1], px[0], 255]
                } else {
                    [px[0], px[1], px[2], 255]
                });
            }
        }
        let mut encoder = png::Encoder::new(std::fs::File::create(path)?, w, h);
        encoder.set_color(png::ColorType::Rgba);
        encoder.write_header()?.write_image_data(&rgba)?;
        Ok(())
    }
}

struct App {
    options: Options,
    host: Option<Host>,
    result: Result<(), Error>,
}

impl App {
    fn redraw(&mut self, event_loop: &ActiveEventLoop) -> Result<(), Error> {
        let Some(host) = &mut self.host else {
            return Ok(());
        };
        let frame = host.frame(&self.options)?;
        let last = self.options.frames.is_some_and(|n| host.frames >= n);
        if let (true, Some(path)) = (last, &self.options.screenshot) {
            host.screenshot(&frame.texture, path)?;
        }
        host.window.pre_present_notify();
        host.queue.present(frame);
        if last {
            event_loop.exit();
        }
        Ok(())
    }
}

impl ApplicationHandler for App {
    fn resumed(&mut self, event_loop: &ActiveEventLoop) {
        let size = winit::dpi::PhysicalSize::new(self.options.width, self.options.height);
        let attributes = Window::default_attributes()
            .with_title("meshlight in a host")
            .with_inner_size(size)
            .with_resizable(false);
        let host = event_loop
            .create_window(attributes)
            .map_err(Error::from)
            .and_then(|w| new_host(Arc::new(w), &self.options));
        match host {
            Ok(h) => self.host = Some(h),
            Err(e) => {
                self.result = Err(e);
                event_loop.exit();
            }
        }
    }

    fn window_event(&mut self, event_loop: &ActiveEventLoop, _: WindowId, event: WindowEvent) {
        match event {
            WindowEvent::CloseRequested => event_loop.exit(),
            WindowEvent::RedrawRequested => {
                if let Err(e) = self.redraw(event_loop) {
                    self.result = Err(e);
                    event_loop.exit();
                }
            }
            _ => {}
        }
    }

    fn about_to_wait(&mut self, _: &ActiveEventLoop) {
        if let Some(h) = &self.host {
            h.window.request_redraw();
        }
    }
}

fn main() -> Result<(), Error> {
    let mut app = App {
        options: options()?,
        host: None,
        result: Ok(()),
    };
    EventLoop::new()?.run_app(&mut app)?;
    app.result
}
