//! The window's event loop: input moves the camera or goes to the overlay, every
//! redraw runs one frame, `--frames` ends the run (writing `--screenshot`).

use crate::options::ViewerOptions;
use crate::viewer::{Viewer, ViewerError};
use glam::Vec3;
use std::collections::HashSet;
use std::sync::Arc;
use std::time::Instant;
use winit::application::ApplicationHandler;
use winit::dpi::PhysicalSize;
use winit::event::{ElementState, MouseButton, MouseScrollDelta, WindowEvent};
use winit::event_loop::{ActiveEventLoop, ControlFlow, EventLoop};
use winit::keyboard::{KeyCode, PhysicalKey};
use winit::window::{Window, WindowId};

/// Opens the window and runs until it is closed or `--frames` are done.
pub fn run(options: ViewerOptions) -> Result<(), ViewerError> {
    let event_loop = EventLoop::new().map_err(|e| ViewerError::Other(no_display(&e)))?;
    event_loop.set_control_flow(ControlFlow::Poll);
    let mut app = App {
        options: Some(options),
        viewer: None,
        result: Ok(()),
        held: HashSet::new(),
        looking: false,
        cursor: None,
        last: Instant::now(),
    };
    event_loop
        .run_app(&mut app)
        .map_err(|e| ViewerError::Other(e.to_string()))?;
    app.result
}

fn no_display(e: &dyn std::fmt::Display) -> String {
    format!(
        "cannot open a window ({e}); run under an X server (DISPLAY), e.g. `Xvfb :99 & DISPLAY=:99 meshlight view …` (scripts/ensure-xvfb.sh installs Xvfb)"
    )
}

/// A window for driving a [`Viewer`] from tests: an X11 event loop that may live on any
/// thread, and its window (shown, `width` × `height`). Keep the loop alive as long as the
/// window.
pub fn test_window(width: u32, height: u32) -> Result<(EventLoop<()>, Arc<Window>), ViewerError> {
    use winit::platform::x11::EventLoopBuilderExtX11;
    let event_loop = EventLoop::builder()
        .with_any_thread(true)
        .build()
        .map_err(|e| ViewerError::Other(no_display(&e)))?;
    #[allow(deprecated)]
    let window = event_loop
        .create_window(attributes(width, height))
        .map_err(|e| ViewerError::Other(no_display(&e)))?;
    Ok((event_loop, Arc::new(window)))
}

fn attributes(width: u32, height: u32) -> winit::window::WindowAttributes {
    Window::default_attributes()
        .with_title("meshlight view")
        .with_inner_size(PhysicalSize::new(width, height))
}

struct App {
    options: Option<ViewerOptions>,
    viewer: Option<Viewer>,
    result: Result<(), ViewerError>,
    held: HashSet<KeyCode>,
    looking: bool,
    cursor: Option<(f64, f64)>,
    last: Instant,
}

impl App {
    fn fail(&mut self, event_loop: &ActiveEventLoop, e: ViewerError) {
        self.result = Err(e);
        event_loop.exit();
    }

    fn redraw(&mut self, event_loop: &ActiveEventLoop) {
        let Some(viewer) = &mut self.viewer else {
            return;
        };
        let dt = self.last.elapsed().as_secs_f32().min(0.1);
        self.last = Instant::now();
        let axis = |plus: KeyCode, minus: KeyCode| {
            f32::from(u8::from(self.held.contains(&plus)))
                - f32::from(u8::from(self.held.contains(&minus)))
        };
        let local = Vec3::new(
            axis(KeyCode::KeyD, KeyCode::KeyA),
            axis(KeyCode::KeyE, KeyCode::KeyQ),
            axis(KeyCode::KeyW, KeyCode::KeyS),
        );
        viewer.rig.travel(local, dt);
        if let Err(e) = viewer.frame() {
            return self.fail(event_loop, e);
        }
        let done = viewer.options().frames.is_some_and(|n| viewer.frames >= n);
        if done {
            if let Some(path) = viewer.options().screenshot.clone()
                && let Err(e) = viewer.screenshot(&path)
            {
                return self.fail(event_loop, e);
            }
            event_loop.exit();
        }
    }

    fn key(&mut self, code: KeyCode, pressed: bool) {
        let Some(viewer) = &mut self.viewer else {
            return;
        };
        if pressed {
            self.held.insert(code);
        } else {
            self.held.remove(&code);
            return;
        }
        let stamp = format!("meshlight-view-{}", viewer.frames);
        let done = match code {
            KeyCode::KeyR => {
                viewer.rig.reset();
                viewer.renderer.camera_cut();
                Ok(())
            }
            KeyCode::KeyO => {
                viewer.rig.toggle_orbit();
                Ok(())
            }
            KeyCode::F12 | KeyCode::KeyP => {
                let path = std::path::PathBuf::from(format!("{stamp}.png"));
                viewer
                    .screenshot(&path)
                    .map(|()| log::warn!("wrote {}", path.display()))
            }
            KeyCode::KeyH => {
                let path = std::path::PathBuf::from(format!("{stamp}.html"));
                viewer
                    .write_html(&path)
                    .map(|()| log::warn!("wrote {}", path.display()))
            }
            KeyCode::KeyT => {
                let path = std::path::PathBuf::from(format!("{stamp}.trace.json"));
                viewer
                    .write_trace(&path)
                    .map(|()| log::warn!("wrote {}", path.display()))
            }
            KeyCode::Tab => {
                viewer.overlay_on = !viewer.overlay_on;
                Ok(())
            }
            _ => Ok(()),
        };
        if let Err(e) = done {
            viewer.error = Some(e.to_string());
        }
    }
}

impl ApplicationHandler for App {
    fn resumed(&mut self, event_loop: &ActiveEventLoop) {
        let Some(options) = self.options.take() else {
            return;
        };
        let window =
            match event_loop.create_window(attributes(options.scene.width, options.scene.height)) {
                Ok(w) => Arc::new(w),
                Err(e) => return self.fail(event_loop, ViewerError::Other(no_display(&e))),
            };
        match Viewer::new(options, Some(window)) {
            Ok(v) => self.viewer = Some(v),
            Err(e) => self.fail(event_loop, e),
        }
        self.last = Instant::now();
    }

    fn window_event(&mut self, event_loop: &ActiveEventLoop, _: WindowId, event: WindowEvent) {
        let used = self
            .viewer
            .as_mut()
            .is_some_and(|v| v.on_window_event(&event));
        match event {
            WindowEvent::CloseRequested => event_loop.exit(),
            WindowEvent::RedrawRequested => self.redraw(event_loop),
            WindowEvent::Resized(size) => {
                if let Some(v) = &mut self.viewer
                    && size.width > 0
                    && size.height > 0
                {
                    let _ = v.resize(size.width, size.height);
                }
            }
            WindowEvent::KeyboardInput { event, .. }
                if !used || event.state == ElementState::Released =>
            {
                if let PhysicalKey::Code(code) = event.physical_key {
                    self.key(code, event.state == ElementState::Pressed);
                }
            }
            WindowEvent::MouseInput {
                button: MouseButton::Right,
                state,
                ..
            } => {
                self.looking = state == ElementState::Pressed && !used;
            }
            WindowEvent::CursorMoved { position, .. } => {
                if let (true, Some((x, y)), Some(v)) = (self.looking, self.cursor, &mut self.viewer)
                {
                    v.rig
                        .rotate((position.x - x) as f32, (position.y - y) as f32);
                }
                self.cursor = Some((position.x, position.y));
            }
            WindowEvent::MouseWheel { delta, .. } if !used => {
                let notches = match delta {
                    MouseScrollDelta::LineDelta(_, y) => y,
                    MouseScrollDelta::PixelDelta(p) => p.y as f32 / 40.0,
                };
                if let Some(v) = &mut self.viewer {
                    v.rig.scale_speed(notches);
                }
            }
            WindowEvent::Focused(false) => self.held.clear(),
            _ => {}
        }
    }

    fn about_to_wait(&mut self, _: &ActiveEventLoop) {
        if let Some(w) = self.viewer.as_ref().and_then(Viewer::window) {
            w.request_redraw();
        }
    }
}
