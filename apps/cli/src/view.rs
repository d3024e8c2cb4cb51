//! `meshlight view`: the live viewer's options on the command line; the window itself is
//! the `meshlight-viewer` crate.

use crate::args::SceneArgs;
use meshlight_viewer::{CameraSpec, ViewerOptions};
use std::path::PathBuf;

/// The scene of `render`, plus the window's own choices.
#[derive(clap::Args)]
pub struct ViewArgs {
    #[command(flatten)]
    pub scene: SceneArgs,
    /// Exit after this many frames (with --screenshot, the last one is written).
    #[arg(long)]
    pub frames: Option<u64>,
    /// Write the last frame's image (the graph's `color`, without the overlay) as PNG.
    #[arg(long)]
    pub screenshot: Option<PathBuf>,
    /// A fixed camera, `x,y,z:tx,ty,tz` (position and target), instead of the scene's.
    #[arg(long, value_parser = CameraSpec::parse)]
    pub camera: Option<CameraSpec>,
    /// A scripted camera: one revolution around the scene's target every this many
    /// frames (for demos and timing runs; input still works on top).
    #[arg(long)]
    pub orbit_frames: Option<u32>,
    /// No overlay: the window shows the frame alone.
    #[arg(long)]
    pub no_overlay: bool,
    /// Present without waiting for the display (for timing runs).
    #[arg(long)]
    pub no_vsync: bool,
    /// Draw into a texture instead of a window (no display needed: a GPU server) and
    /// print the frames' timings and the memory sampled along them. Needs --frames.
    #[arg(long, requires = "frames")]
    pub offscreen: bool,
    /// With --offscreen: frames run before measuring (pipelines built, lists grown).
    #[arg(long, default_value_t = 60)]
    pub warmup: u64,
}

/// Opens the window and runs it until it is closed (or `--frames` have run).
pub fn view(a: ViewArgs) -> Result<(), Box<dyn std::error::Error>> {
    let scene = a.scene.options();
    // The bounds `render` checks, before the window or the adapter.
    meshlight_cli::render_bounds::RenderNumbers::of_scene(&scene, None, None).check()?;
    if let Some(path) = &a.screenshot {
        meshlight_output::check_png_path(path)?;
        meshlight_output::check_output_path(path)?;
    }
    let options = ViewerOptions {
        scene,
        frames: a.frames,
        screenshot: a.screenshot,
        camera: a.camera,
        orbit_frames: a.orbit_frames,
        no_overlay: a.no_overlay,
        no_vsync: a.no_vsync,
    };
    if !a.offscreen {
        let (screenshot, size) = (
            options.screenshot.clone(),
            (options.scene.width, options.scene.height),
        );
        meshlight_viewer::app::run(options)?;
        if let Some(path) = screenshot {
            meshlight_output::write_stdout(&format!(
                "wrote {} ({} × {}, the last frame without the overlay)\n",
                path.display(),
                size.0,
                size.1
            ))?;
        }
        return Ok(());
    }
    let frames = options.frames.unwrap_or(0);
    let screenshot = options.screenshot.clone();
    let (mut viewer, report) = meshlight_viewer::offscreen::run_offscreen(
        options,
        a.warmup,
        frames,
        (frames / 10).max(1),
    )?;
    if let Some(path) = screenshot {
        viewer.screenshot(&path)?;
    }
    meshlight_output::write_stdout(&report.text())?;
    Ok(())
}
