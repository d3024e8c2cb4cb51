//! The viewer: a renderer, the graph it runs (rebuilt when a choice changes), the
//! camera, and optionally a window it presents to with the overlay on top. Everything a
//! key or a widget does is a method here, so tests drive it without input events.

use crate::camera::CameraRig;
use crate::options::ViewerOptions;
use crate::overlay::{Overlay, OverlayActions};
use crate::present::{Blit, add_present, present_texture};
use crate::reload::{FileError, PipelineWatch, locate};
use meshlight::gpu_scene::Camera;
use meshlight::graph::{FrameStats, GraphError};
use meshlight::resolve::DebugView;
use meshlight::stream::Budget;
use meshlight_virtual_geometry::{FrameSettings, GraphSource, Renderer, setup};
use std::collections::BTreeMap;
use std::path::Path;
use std::sync::Arc;
use std::time::Instant;
use winit::window::Window;

/// What can stop the viewer (as opposed to an error it shows and renders through).
#[derive(Debug, thiserror::Error)]
pub enum ViewerError {
    #[error(transparent)]
    Graph(#[from] GraphError),
    #[error(transparent)]
    Setup(#[from] meshlight_virtual_geometry::SetupError),
    #[error(transparent)]
    Output(#[from] meshlight_output::OutputError),
    #[error("{0}")]
    Other(String),
}

/// Frame times kept for the overlay's chart.
pub const HISTORY: usize = 240;

/// One frame's figures, for the overlay and for callers.
#[derive(Clone, Copy, Debug, Default)]
pub struct FrameTime {
    /// CPU time of the whole frame on the viewer's side: graph, overlay, present.
    pub cpu_ms: f32,
    /// The GPU time of the newest frame whose timestamps came back.
    pub gpu_ms: Option<f32>,
    /// The part of `cpu_ms` spent on the overlay (egui's pass, tessellation, upload).
    pub overlay_ms: f32,
    /// The part of `cpu_ms` spent in the graph's frame (recording and `queue.submit`,
    /// where a software driver such as lavapipe runs the work).
    pub graph_ms: f32,
}

/// What the image and the overlay are drawn into: the screen, its format (the blit's and
/// egui's), the blit and egui.
struct Target {
    screen: Screen,
    format: wgpu::TextureFormat,
    blit: Blit,
    egui: egui::Context,
    egui_renderer: egui_wgpu::Renderer,
}

/// A window, or a texture where no display exists.
// One per viewer, made once and never moved: boxing the larger variant would buy nothing.
#[allow(clippy::large_enum_variant)]
enum Screen {
    /// The window's surface, presented each frame, and its input for egui.
    Window {
        window: Arc<Window>,
        surface: wgpu::Surface<'static>,
        config: wgpu::SurfaceConfiguration,
        egui_state: egui_winit::State,
    },
    /// A texture of the viewer's own: the same drawing as into a window, nothing
    /// presented, no input. It lets the overlay's cost be measured on a machine with no
    /// display, such as a GPU server.
    Offscreen { texture: wgpu::Texture },
}

/// The format of the off-screen target: what a window's surface offers first here.
const OFFSCREEN_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8Unorm;

fn offscreen_texture(device: &wgpu::Device, width: u32, height: u32) -> wgpu::Texture {
    device.create_texture(&wgpu::TextureDescriptor {
        label: Some("viewer offscreen"),
        size: wgpu::Extent3d {
            width: width.max(1),
            height: height.max(1),
            depth_or_array_layers: 1,
        },
        mip_level_count: 1,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format: OFFSCREEN_FORMAT,
        usage: wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC,
        view_formats: &[],
    })
}

pub struct Viewer {
    pub renderer: Renderer,
    pub rig: CameraRig,
    options: ViewerOptions,
    /// The settings the graph is built with (width, view, thresholds, implementations
    /// chosen in the overlay or through the API).
    settings: FrameSettings,
    present: wgpu::Texture,
    watch: Option<PipelineWatch>,
    /// The last error a rebuild reported; the last good graph keeps rendering meanwhile.
    pub error: Option<String>,
    /// The same, placed in the pipeline file, when the file was at fault.
    pub file_error: Option<FileError>,
    pub times: std::collections::VecDeque<FrameTime>,
    pub last_stats: Option<FrameStats>,
    pub frames: u64,
    pub overlay_on: bool,
    overlay: Overlay,
    target: Option<Target>,
    registry: meshlight::graph::file::Registry,
}

/// Threads reading streamed pages.
const STREAM_THREADS: usize = 4;

impl Viewer {
    /// Builds the scene and the renderer; with a window, presents to it.
    pub fn new(options: ViewerOptions, window: Option<Arc<Window>>) -> Result<Self, ViewerError> {
        let o = &options;
        let scene = setup(&o.scene)?;
        let mut renderer = Renderer::new(scene.data, scene.settings, &scene.source)?;
        renderer.lights = scene.lights;
        if !scene.sources.is_empty() {
            // `--pool-mb`: the scene streams; its pages come from the assets in memory.
            renderer.start_streaming(scene.sources, Budget::default(), STREAM_THREADS)?;
        }
        let camera = match o.camera {
            Some(c) => Camera {
                position: c.position,
                target: c.target,
                ..scene.camera
            },
            None => scene.camera,
        };
        let device = renderer.executor.gpu.device.clone();
        let present = present_texture(&device, o.scene.width, o.scene.height);
        let settings = renderer.settings.clone();
        let mut viewer = Self {
            rig: CameraRig::new(camera),
            settings,
            present,
            watch: o.scene.pipeline.clone().map(PipelineWatch::new),
            error: None,
            file_error: None,
            times: std::collections::VecDeque::with_capacity(HISTORY),
            last_stats: None,
            frames: 0,
            overlay_on: !o.no_overlay,
            overlay: Overlay::default(),
            target: None,
            registry: meshlight::registry(),
            options,
            renderer,
        };
        let texture = viewer.present.clone();
        viewer
            .renderer
            .import_texture(crate::present::PRESENT, &texture);
        // The first graph gets the copy into the viewer's texture.
        viewer
            .apply(viewer.settings.clone())
            .map_err(ViewerError::Other)?;
        if let Some(w) = window {
            viewer.attach(w)?;
        }
        Ok(viewer)
    }

    fn attach(&mut self, window: Arc<Window>) -> Result<(), ViewerError> {
        let gpu = &self.renderer.executor.gpu;
        let surface = gpu
            .instance
            .create_surface(window.clone())
            .map_err(|e| ViewerError::Other(format!("cannot draw into the window: {e}")))?;
        let caps = surface.get_capabilities(&gpu.adapter);
        // The image is sRGB-encoded already: a surface format without the encoding shows
        // its bytes as they are, and egui draws for such a target by default.
        let format = caps
            .formats
            .iter()
            .copied()
            .find(|f| {
                !f.is_srgb()
                    && matches!(
                        f,
                        wgpu::TextureFormat::Bgra8Unorm | wgpu::TextureFormat::Rgba8Unorm
                    )
            })
            .or_else(|| caps.formats.first().map(|f| f.remove_srgb_suffix()))
            .ok_or_else(|| ViewerError::Other("the window's surface offers no format".into()))?;
        let size = window.inner_size();
        let present_mode = if self.options.no_vsync {
            wgpu::PresentMode::AutoNoVsync
        } else {
            wgpu::PresentMode::AutoVsync
        };
        let view_formats = if caps.formats.contains(&format) {
            vec![]
        } else {
            vec![format]
        };
        let surface_format = if caps.formats.contains(&format) {
            format
        } else {
            format.add_srgb_suffix()
        };
        let config = wgpu::SurfaceConfiguration {
            usage: wgpu::TextureUsages::RENDER_ATTACHMENT,
            format: surface_format,
            width: size.width.max(1),
            height: size.height.max(1),
            present_mode,
            desired_maximum_frame_latency: 2,
            alpha_mode: caps
                .alpha_modes
                .first()
                .copied()
                .unwrap_or(wgpu::CompositeAlphaMode::Auto),
            view_formats,
            color_space: wgpu::SurfaceColorSpace::Auto,
        };
        surface.configure(&gpu.device, &config);
        let egui = egui::Context::default();
        let egui_state = egui_winit::State::new(
            egui.clone(),
            egui::ViewportId::ROOT,
            &window,
            Some(window.scale_factor() as f32),
            None,
            Some(gpu.device.limits().max_texture_dimension_2d as usize),
        );
        let screen = Screen::Window {
            window,
            surface,
            config,
            egui_state,
        };
        self.target = Some(Target::new(&gpu.device, screen, format, egui));
        Ok(())
    }

    /// A viewer drawing into a texture of its own instead of a window: every frame runs
    /// the graph, the blit and (unless `no_overlay`) the overlay as a window would, and
    /// presents nothing. For timing and memory runs on machines without a display.
    pub fn offscreen(options: ViewerOptions) -> Result<Self, ViewerError> {
        let mut viewer = Self::new(options, None)?;
        let device = &viewer.renderer.executor.gpu.device;
        let (width, height) = viewer.size();
        let screen = Screen::Offscreen {
            texture: offscreen_texture(device, width, height),
        };
        viewer.target = Some(Target::new(
            device,
            screen,
            OFFSCREEN_FORMAT,
            egui::Context::default(),
        ));
        Ok(viewer)
    }

    /// The window, when there is one.
    pub fn window(&self) -> Option<&Arc<Window>> {
        match &self.target.as_ref()?.screen {
            Screen::Window { window, .. } => Some(window),
            Screen::Offscreen { .. } => None,
        }
    }

    /// The settings the current graph was built with.
    pub fn settings(&self) -> &FrameSettings {
        &self.settings
    }

    /// The size the frame renders at.
    pub fn size(&self) -> (u32, u32) {
        (self.settings.width, self.settings.height)
    }

    /// Stage → implementation of every pass in the current plan (first pass of a stage).
    pub fn implementations(&self) -> BTreeMap<String, String> {
        let mut m = BTreeMap::new();
        for p in &self.renderer.compiled.plan.passes {
            m.entry(p.stage.to_string())
                .or_insert_with(|| p.implementation.to_string());
        }
        m
    }

    /// Stages of the current plan with more than one registered implementation, and
    /// those implementations.
    pub fn choices(&self) -> Vec<(String, Vec<String>)> {
        self.implementations()
            .into_keys()
            .filter_map(|stage| {
                let names = self.registry.implementations(&stage);
                (names.len() > 1).then_some((stage, names))
            })
            .collect()
    }

    /// Runs `stage` with `implementation` from now on. On an error (the adapter cannot
    /// run it, the pipeline has no such stage) the error is kept in [`Self::error`] and
    /// returned, and the last good graph keeps rendering.
    pub fn select_implementation(
        &mut self,
        stage: &str,
        implementation: &str,
    ) -> Result<(), String> {
        let s = self
            .settings
            .clone()
            .with_implementation(stage, implementation);
        self.apply(s)
    }

    /// Shows `view` (rebuilds the graph).
    pub fn set_view(&mut self, view: DebugView) -> Result<(), String> {
        let s = self.settings.clone().with_view(view);
        self.apply(s)
    }

    /// Sets the LOD threshold and the software/hardware split (pixels) and rebuilds.
    pub fn set_thresholds(&mut self, lod_px: f32, sw_px: f32) -> Result<(), String> {
        let mut s = self.settings.clone();
        s.lod_threshold_px = Some(lod_px);
        s.sw_threshold_px = Some(sw_px);
        self.apply(s)
    }

    /// Renders at `width` × `height` from the next frame (the graph rebuilt at that size;
    /// the window's surface follows when there is one).
    pub fn resize(&mut self, width: u32, height: u32) -> Result<(), String> {
        let (width, height) = (width.max(1), height.max(1));
        let device = &self.renderer.executor.gpu.device;
        match self.target.as_mut().map(|t| &mut t.screen) {
            Some(Screen::Window {
                surface, config, ..
            }) => {
                config.width = width;
                config.height = height;
                surface.configure(device, config);
            }
            Some(Screen::Offscreen { texture }) => {
                *texture = offscreen_texture(device, width, height);
            }
            None => {}
        }
        if (width, height) == self.size() {
            return Ok(());
        }
        let mut s = self.settings.clone();
        s.width = width;
        s.height = height;
        if let Some(c) = &mut s.clustering {
            c.viewport = [width, height];
        }
        self.apply(s)
    }

    /// Places the camera (a camera cut for the renderer).
    pub fn set_camera(&mut self, position: glam::Vec3, target: glam::Vec3) {
        self.rig.look_at(position, target);
        self.renderer.camera_cut();
    }

    /// Re-reads the pipeline file now (as a change of it does), rebuilding the graph;
    /// an error is shown and returned, the last good graph kept.
    pub fn reload_pipeline(&mut self) -> Result<(), String> {
        self.apply(self.settings.clone())
    }

    /// Builds the graph for `settings`; only a success replaces the current graph and
    /// settings.
    fn apply(&mut self, settings: FrameSettings) -> Result<(), String> {
        let result = self.try_apply(&settings);
        match result {
            Ok(()) => {
                self.settings = settings;
                self.error = None;
                self.file_error = None;
                Ok(())
            }
            Err(message) => {
                self.error = Some(message.clone());
                Err(message)
            }
        }
    }

    fn try_apply(&mut self, settings: &FrameSettings) -> Result<(), String> {
        let source = match &self.options.scene.pipeline {
            None => GraphSource::Shipped,
            Some(path) => GraphSource::File(path.clone()),
        };
        let size_changed =
            (settings.width, settings.height) != (self.present.width(), self.present.height());
        let present = if size_changed {
            present_texture(
                &self.renderer.executor.gpu.device,
                settings.width,
                settings.height,
            )
        } else {
            self.present.clone()
        };
        let rebuilt = self
            .renderer
            .rebuild(&source, settings.clone(), &add_present);
        if let Err(e) = rebuilt {
            let message = e.to_string();
            if let Some(path) = &self.options.scene.pipeline {
                let prefix = format!("pipeline file {}: ", path.display());
                let message = message.strip_prefix(&prefix).unwrap_or(&message);
                let text = std::fs::read_to_string(path).unwrap_or_default();
                let located = locate(path, &text, message);
                let shown = located.to_string();
                self.file_error = Some(located);
                return Err(shown);
            }
            return Err(message);
        }
        if size_changed {
            self.present = present;
            let texture = self.present.clone();
            self.renderer
                .import_texture(crate::present::PRESENT, &texture);
        }
        Ok(())
    }

    /// Polls the pipeline file; a change rebuilds the graph (an error is shown).
    pub fn poll_pipeline(&mut self, force: bool) -> bool {
        let changed = self.watch.as_mut().is_some_and(|w| w.changed(force));
        if changed {
            let _ = self.reload_pipeline();
        }
        changed
    }

    /// One frame: the scripted camera moved, the pipeline file polled, the graph run,
    /// and, with a window, the image and the overlay presented.
    pub fn frame(&mut self) -> Result<(), ViewerError> {
        let start = Instant::now();
        self.poll_pipeline(false);
        if let Some(n) = self.options.orbit_frames {
            let turn = std::f32::consts::TAU / n.max(1) as f32;
            if !self.rig.orbit {
                self.rig.toggle_orbit();
            }
            self.rig.rotate(turn / 0.004, 0.0);
        }
        let camera = self.rig.camera();
        let graph_start = Instant::now();
        let stats = self.renderer.frame(&camera)?;
        let graph_ms = graph_start.elapsed().as_secs_f32() * 1000.0;
        let gpu_ms = stats
            .gpu_latest
            .as_ref()
            .map(|t| t.frame_us as f32 / 1000.0);
        self.last_stats = Some(stats);
        let (actions, overlay_ms) = self.present_to_window()?;
        self.frames += 1;
        if self.times.len() == HISTORY {
            self.times.pop_front();
        }
        self.times.push_back(FrameTime {
            cpu_ms: start.elapsed().as_secs_f32() * 1000.0,
            gpu_ms,
            overlay_ms,
            graph_ms,
        });
        self.act(actions);
        if self.frames.is_multiple_of(100)
            && let Some(s) = &self.last_stats
        {
            log::info!(
                "frame {}: CPU {:.2} ms, graph {graph_ms:.2} ms, overlay {overlay_ms:.2} ms, RSS {} KiB, {} in flight, {} allocations, {} bind groups, pool {} B",
                self.frames,
                start.elapsed().as_secs_f32() * 1000.0,
                resident_kib().unwrap_or(0),
                s.frames_in_flight,
                s.allocations,
                s.bind_groups_created,
                s.pool_bytes_held
            );
        }
        Ok(())
    }

    /// Runs `n` frames.
    pub fn run_frames(&mut self, n: u64) -> Result<(), ViewerError> {
        for _ in 0..n {
            self.frame()?;
        }
        Ok(())
    }

    fn act(&mut self, actions: OverlayActions) {
        if let Some(v) = actions.view {
            let _ = self.set_view(v);
        }
        if let Some((lod, sw)) = actions.thresholds {
            let _ = self.set_thresholds(lod, sw);
        }
        if let Some((stage, name)) = actions.implementation {
            let _ = self.select_implementation(&stage, &name);
        }
    }

    /// Draws the frame and the overlay into the target and presents a window's; returns
    /// what the overlay asked for and the milliseconds the overlay took.
    fn present_to_window(&mut self) -> Result<(OverlayActions, f32), ViewerError> {
        let choices = if self.overlay_on && self.target.is_some() {
            self.choices_with_current()
        } else {
            Vec::new()
        };
        let Some(t) = &mut self.target else {
            return Ok((OverlayActions::default(), 0.0));
        };
        let gpu = &self.renderer.executor.gpu;
        let (frame, view, size) = match &mut t.screen {
            Screen::Window {
                surface, config, ..
            } => {
                let frame = match surface.get_current_texture() {
                    wgpu::CurrentSurfaceTexture::Success(t)
                    | wgpu::CurrentSurfaceTexture::Suboptimal(t) => t,
                    wgpu::CurrentSurfaceTexture::Outdated | wgpu::CurrentSurfaceTexture::Lost => {
                        surface.configure(&gpu.device, config);
                        return Ok((OverlayActions::default(), 0.0));
                    }
                    other => {
                        log::warn!("no surface texture this frame: {other:?}");
                        return Ok((OverlayActions::default(), 0.0));
                    }
                };
                let view = frame.texture.create_view(&wgpu::TextureViewDescriptor {
                    format: Some(t.format),
                    ..Default::default()
                });
                (Some(frame), view, [config.width, config.height])
            }
            Screen::Offscreen { texture } => (
                None,
                texture.create_view(&Default::default()),
                [texture.width(), texture.height()],
            ),
        };
        let mut encoder = gpu
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("viewer"),
            });
        let mut actions = OverlayActions::default();
        let mut paint = None;
        let overlay_start = Instant::now();
        if self.overlay_on {
            let input = match &mut t.screen {
                Screen::Window {
                    window, egui_state, ..
                } => egui_state.take_egui_input(window),
                Screen::Offscreen { .. } => egui::RawInput {
                    screen_rect: Some(egui::Rect::from_min_size(
                        egui::Pos2::ZERO,
                        egui::vec2(size[0] as f32, size[1] as f32),
                    )),
                    ..Default::default()
                },
            };
            let facts = crate::overlay::Facts {
                renderer: &self.renderer,
                settings: &self.settings,
                times: &self.times,
                stats: self.last_stats.as_ref(),
                error: self.error.as_deref(),
                choices,
                pipeline: self.options.scene.pipeline.as_deref(),
                rig: &self.rig,
            };
            let mut output = t.egui.run_ui(input, |ui| {
                actions = self.overlay.draw(ui, &facts);
            });
            if let Screen::Window {
                window, egui_state, ..
            } = &mut t.screen
            {
                egui_state.handle_platform_output(window, output.platform_output);
            }
            let jobs = t.egui.tessellate(output.shapes, output.pixels_per_point);
            let set = std::mem::take(&mut output.textures_delta.set);
            let free = std::mem::take(&mut output.textures_delta.free);
            for (id, deltas) in &set {
                for delta in deltas {
                    t.egui_renderer
                        .update_texture(&gpu.device, &gpu.queue, *id, delta);
                }
            }
            let screen = egui_wgpu::ScreenDescriptor {
                size_in_pixels: size,
                pixels_per_point: output.pixels_per_point,
            };
            let extra = t.egui_renderer.update_buffers(
                &gpu.device,
                &gpu.queue,
                &mut encoder,
                &jobs,
                &screen,
            );
            paint = Some((jobs, screen, extra, free));
        }
        // Without the overlay, nothing of its cost is counted.
        let mut overlay_ms = match paint {
            Some(_) => overlay_start.elapsed().as_secs_f32() * 1000.0,
            None => 0.0,
        };
        {
            let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("viewer present"),
                color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                    view: &view,
                    depth_slice: None,
                    resolve_target: None,
                    ops: wgpu::Operations {
                        load: wgpu::LoadOp::Clear(wgpu::Color::BLACK),
                        store: wgpu::StoreOp::Store,
                    },
                })],
                ..Default::default()
            });
            t.blit.draw(&gpu.device, &mut pass, &self.present);
            if let Some((jobs, screen, _, _)) = &paint {
                let drawing = Instant::now();
                let mut pass = pass.forget_lifetime();
                t.egui_renderer.render(&mut pass, jobs, screen);
                overlay_ms += drawing.elapsed().as_secs_f32() * 1000.0;
            }
        }
        let mut buffers = Vec::new();
        let mut free = Default::default();
        if let Some((_, _, extra, f)) = paint {
            buffers = extra;
            free = f;
        }
        buffers.push(encoder.finish());
        gpu.queue.submit(buffers);
        if let (Some(frame), Screen::Window { window, .. }) = (frame, &t.screen) {
            window.pre_present_notify();
            gpu.queue.present(frame);
        }
        for id in free {
            t.egui_renderer.free_texture(&id);
        }
        Ok((actions, overlay_ms))
    }

    fn choices_with_current(&self) -> Vec<(String, Vec<String>, String)> {
        let current = self.implementations();
        self.choices()
            .into_iter()
            .map(|(stage, names)| {
                let now = self
                    .settings
                    .implementations
                    .get(&stage)
                    .cloned()
                    .or_else(|| current.get(&stage).cloned())
                    .unwrap_or_default();
                (stage, names, now)
            })
            .collect()
    }

    /// Lets egui see a window event; true when it used it (the camera then ignores it).
    pub fn on_window_event(&mut self, event: &winit::event::WindowEvent) -> bool {
        match self.target.as_mut().map(|t| &mut t.screen) {
            Some(Screen::Window {
                window, egui_state, ..
            }) if self.overlay_on => egui_state.on_window_event(window, event).consumed,
            _ => false,
        }
    }

    /// The last frame's image (the graph's `color`), waiting for the GPU: RGBA8 rows.
    pub fn read_image(&mut self) -> Result<(u32, u32, Vec<u8>), ViewerError> {
        self.renderer.executor.finish()?;
        let rgba = self.renderer.executor.read_texture("color")?;
        Ok((self.settings.width, self.settings.height, rgba))
    }

    /// Writes the last frame's image as PNG.
    pub fn screenshot(&mut self, path: &Path) -> Result<(), ViewerError> {
        meshlight_output::check_png_path(path).map_err(|e| ViewerError::Other(e.to_string()))?;
        let (w, h, rgba) = self.read_image()?;
        meshlight_output::write_png(path, w, h, &rgba)?;
        Ok(())
    }

    /// Writes the current plan, with the last frame's timings, as a self-contained page.
    pub fn write_html(&self, path: &Path) -> Result<(), ViewerError> {
        let facts = (self.renderer.streaming.as_ref())
            .map(|s| s.stats().rows())
            .unwrap_or_default();
        let page = meshlight::graph::dump::to_html_report(
            &self.renderer.compiled.plan,
            &format!("meshlight view: {}", self.options.scene.mesh.display()),
            &meshlight::graph::dump::Report {
                last_frame: self.last_stats.as_ref(),
                image: None,
                facts: &facts,
            },
        );
        meshlight_output::write_file(path, page.as_bytes())?;
        Ok(())
    }

    /// Writes the GPU timings of the frames since the last trace (up to the executor's
    /// last 256) as a Chrome trace, which Perfetto opens; waits for the frames in flight.
    pub fn write_trace(&mut self, path: &Path) -> Result<(), ViewerError> {
        self.renderer.executor.finish()?;
        let timings = self.renderer.executor.take_gpu_timings()?;
        if timings.is_empty() {
            return Err(ViewerError::Other(
                "no GPU timings to trace: the adapter has no timestamps, or timing is off (MESHLIGHT_TIMING)".into(),
            ));
        }
        let trace =
            meshlight::graph::dump::to_chrome_trace(&timings, Some(&self.renderer.compiled.plan));
        meshlight_output::write_file(path, trace.as_bytes())?;
        Ok(())
    }

    /// The camera the next frame uses.
    pub fn camera(&self) -> Camera {
        self.rig.camera()
    }

    /// The options the viewer was opened with.
    pub fn options(&self) -> &ViewerOptions {
        &self.options
    }
}

impl Target {
    fn new(
        device: &wgpu::Device,
        screen: Screen,
        format: wgpu::TextureFormat,
        egui: egui::Context,
    ) -> Self {
        Self {
            screen,
            format,
            blit: Blit::new(device, format),
            egui,
            egui_renderer: egui_wgpu::Renderer::new(
                device,
                format,
                egui_wgpu::RendererOptions::default(),
            ),
        }
    }
}

/// The process's resident memory in KiB (Linux), for the log and the tests.
pub fn resident_kib() -> Option<u64> {
    let statm = std::fs::read_to_string("/proc/self/statm").ok()?;
    let pages: u64 = statm.split_whitespace().nth(1)?.parse().ok()?;
    Some(pages * 4)
}
