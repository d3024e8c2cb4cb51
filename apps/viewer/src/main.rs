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
