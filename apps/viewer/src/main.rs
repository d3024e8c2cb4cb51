//! `meshlight-view`: the live viewer's command line.

use clap::Parser;
use std::process::ExitCode;

#[derive(Parser)]
#[command(
    name = "meshlight-view",
    version,
    about = "A live window on meshlight's virtual-geometry renderer"
)]
struct Cli {
    #[command(flatten)]
    options: meshlight_viewer::ViewerOptions,
}

fn main() -> ExitCode {
    usable_runtime_dir();
    env_logger::Builder::from_env(env_logger::Env::default().default_filter_or("warn")).init();
    let cli = Cli::parse();
    if let Some(path) = &cli.options.screenshot
        && let Err(e) = meshlight::output::check_png_path(path)
    {
        eprintln!("error: {e}");
        return ExitCode::FAILURE;
    }
    match meshlight_viewer::app::run(cli.options) {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::FAILURE
        }
    }
}

/// The Vulkan loader's Wayland probe prints `XDG_RUNTIME_DIR is invalid or not set` once
/// per probe where the variable is unset or names no directory (a container, a remote
/// shell, Xvfb). As `meshlight` does, the variable is then pointed at a private directory
/// (mode 0700) of this user under the temporary directory, before any thread exists.
fn usable_runtime_dir() {
    use std::os::unix::fs::{DirBuilderExt, MetadataExt, PermissionsExt};
    const VAR: &str = "XDG_RUNTIME_DIR";
    let valid = std::env::var_os(VAR)
        .map(std::path::PathBuf::from)
        .is_some_and(|dir| dir.is_absolute() && dir.is_dir());
    if valid {
        return;
    }
    let Ok(uid) = std::fs::metadata("/proc/self").map(|m| m.uid()) else {
        return;
    };
    let dir = std::env::temp_dir().join(format!("meshlight-runtime-{uid}"));
    let _ = std::fs::DirBuilder::new().mode(0o700).create(&dir);
    let ours = std::fs::symlink_metadata(&dir)
        .is_ok_and(|m| m.is_dir() && m.uid() == uid && m.permissions().mode() & 0o077 == 0);
    if ours {
        // SAFETY: called first in `main`, before any thread exists.
        unsafe { std::env::set_var(VAR, &dir) };
    }
}
