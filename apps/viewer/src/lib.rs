//! meshlight-viewer: a window on the virtual-geometry renderer. The frame graph's
//! `color` is copied into a texture the viewer owns and drawn into the window, with an
//! egui overlay on top: frame times, counters, thresholds, the debug view, and a
//! drop-down per stage with several implementations, which rebuilds the graph live. A
//! pipeline file given with `--pipeline` is watched and reloaded when it changes; an
//! error in it is shown with its line while the last good graph keeps rendering.
//!
//! [`Viewer`] holds all of it and is driven by methods ([`Viewer::select_implementation`],
//! [`Viewer::resize`], [`Viewer::run_frames`], …), so tests need no input events; [`app`]
//! is the window's event loop around it.

pub mod app;
pub mod camera;
pub mod offscreen;
pub mod options;
pub mod overlay;
pub mod present;
pub mod reload;
pub mod viewer;

pub use camera::CameraRig;
pub use options::{CameraSpec, ViewerOptions};
pub use reload::FileError;
pub use viewer::{FrameTime, Viewer, ViewerError};
