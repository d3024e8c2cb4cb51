//! The `meshlight` command line.

mod args;
mod render;
mod view;

use clap::{Parser, Subcommand, ValueEnum};

/// The system allocator, counting what Rust code holds, so `view --offscreen` can tell
/// the renderer's heap from the driver's; a relaxed atomic add per call costs nothing
/// measurable beside the allocation itself.
#[global_allocator]
static ALLOCATOR: meshlight_viewer::offscreen::CountingAllocator =
    meshlight_viewer::offscreen::CountingAllocator;
use meshlight::graph::{GraphError, dump};
use std::path::PathBuf;
use std::process::ExitCode;

#[derive(Parser)]
#[command(
    name = "meshlight",
    version,
    about = "GPU render graphs on wgpu: virtual geometry and light clustering as swappable passes"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Render the default scene (or a mesh) into a PNG.
    Render(render::RenderArgs),
    /// Compile a pipeline file without a GPU and dump the graph.
    Graph(GraphArgs),
    /// Run benchmark scenarios and print a table (and JSON).
    Bench(args::BenchArgs),
    /// Build a meshlet LOD asset from a mesh file, or every mesh file under a directory
    /// (mirrored under the output directory, up-to-date outputs skipped).
    Bake(args::BakeArgs),
    /// Write a generated world of unique geometry (a grid of terrain tiles, a knot of its
    /// own shape on each) as mesh files under a directory, to bake with `bake DIR -o OUT`
    /// and draw with `render --mesh OUT`: a scene larger than GPU memory for streaming.
    Generate(args::GenerateArgs),
    /// Print an asset's header and DAG statistics and verify its invariants.
    Inspect {
        /// Asset file written by `meshlight bake`.
        file: PathBuf,
    },
    /// Print the adapter, the features and limits meshlight uses, and which
    /// implementation `auto` picks for each stage on it.
    Info,
    /// Open a window on the scene: fly through it, switch views and implementations in
    /// the overlay, and edit the pipeline file while it runs (saved changes rebuild the
    /// graph). Keys: WASD/QE move, right-drag looks, scroll sets the speed, O orbits, R
    /// resets the camera, P or F12 writes a screenshot, H the HTML report, Tab hides the
    /// overlay.
    View(view::ViewArgs),
}

#[derive(Clone, Copy, ValueEnum)]
enum Format {
    Dot,
    Json,
    Mermaid,
    Html,
    Svg,
}

#[derive(clap::Args)]
struct GraphArgs {
    /// Pipeline file (TOML), e.g. pipelines/prefix_sum.toml.
    #[arg(long)]
    pipeline: PathBuf,
    #[arg(long, value_enum, default_value_t = Format::Dot)]
    format: Format,
    /// Write to this file instead of standard output.
    #[arg(short, long)]
    output: Option<PathBuf>,
    /// Plan for this machine's adapter (its features and class decide `auto`) instead of
    /// one with every feature.
    #[arg(long)]
    for_adapter: bool,
    /// Plan for an adapter of this class: graphics (the default without an adapter),
    /// few-graphics-units (an NVIDIA H100 or H200) or cpu (lavapipe). `meshlight info`
    /// names this machine's.
    #[arg(long, value_parser = meshlight_cli::graph::parse_class)]
    class: Option<meshlight::graph::AdapterClass>,
}

/// Exit code when no Vulkan adapter exists, so scripts can install lavapipe and retry.
const EXIT_NO_ADAPTER: u8 = 3;

fn main() -> ExitCode {
    quiet_on_closed_stdout();
    env_logger::Builder::from_env(env_logger::Env::default().default_filter_or("warn")).init();
    let cli = Cli::parse();
    let result: Result<(), Box<dyn std::error::Error>> = match cli.command {
        Command::Render(a) => render::render(a),
        Command::Graph(a) => graph(a),
        Command::Bench(a) => meshlight_bench::run(&a.options()),
        Command::Bake(a) => bake(a),
        Command::Generate(a) => generate(a),
        Command::Inspect { file } => meshlight_cli::inspect::run(&file).map_err(Into::into),
        Command::Info => meshlight_cli::info::report()
            .and_then(|text| meshlight_output::write_stdout(&text).map_err(Into::into)),
        Command::View(a) => view::view(a),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            if no_adapter(e.as_ref()) {
                return ExitCode::from(EXIT_NO_ADAPTER);
            }
            ExitCode::FAILURE
        }
    }
}

/// Whether `e` is the adapter missing, however the command wrapped it.
fn no_adapter(e: &(dyn std::error::Error + 'static)) -> bool {
    use meshlight_viewer::ViewerError;
    use meshlight_virtual_geometry::SetupError;
    let graph = e
        .downcast_ref::<GraphError>()
        .or_else(|| match e.downcast_ref::<SetupError>()? {
            SetupError::Graph(g) => Some(g),
            _ => None,
        })
        .or_else(|| match e.downcast_ref::<ViewerError>()? {
            ViewerError::Graph(g) | ViewerError::Setup(SetupError::Graph(g)) => Some(g),
            _ => None,
        });
    matches!(graph, Some(GraphError::NoAdapter { .. }))
}

/// Rust ignores SIGPIPE, so a write to a closed pipe (`meshlight inspect … | head -1`)
/// returns an error that `print!` turns into a panic. The default action ends the
/// process quietly with the status a shell expects of a broken pipe, as other tools do.
fn quiet_on_closed_stdout() {
    #[cfg(unix)]
    // SAFETY: called first in `main`, before any thread exists; SIG_DFL is a valid action.
    unsafe {
        libc::signal(libc::SIGPIPE, libc::SIG_DFL);
    }
}

/// A directory is baked as a library; a file (or `procedural`) as before. Both run in a
/// pool of `--jobs` threads.
fn bake(a: args::BakeArgs) -> Result<(), Box<dyn std::error::Error>> {
    let threads = match a.jobs {
        Some(n) => n as usize,
        None => std::thread::available_parallelism().map_or(1, |n| n.get()),
    };
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .map_err(|e| {
            format!(
                "bake: {threads} threads could not be started ({e}); this system allows fewer \
                 (see `ulimit -u` and the memory for their stacks): give a smaller --jobs"
            )
        })?;
    if a.input.is_dir() {
        let options = meshlight::scene::BuildOptions {
            grouping: a.grouping,
            position_bits: a.position_bits,
            ..Default::default()
        };
        pool.install(|| meshlight_cli::bake_library::run(&a.input, &a.output, &options, threads))
            .map_err(Into::into)
    } else {
        meshlight_output::check_output_path(&a.output)?;
        pool.install(|| meshlight_cli::bake_file::run(&a.options()))
            .map_err(Into::into)
    }
}

/// Writes the world's meshes and a line saying what was written.
fn generate(a: args::GenerateArgs) -> Result<(), Box<dyn std::error::Error>> {
    let world = a.world();
    world.check()?;
    let start = std::time::Instant::now();
    let bytes = world.write(&a.output, &|_, _| {})?;
    meshlight_output::write_stdout(&format!(
        "{}: {} meshes, {} triangles, {:.1} MiB of glTF in {:.1} s; bake with `meshlight bake {} -o ASSETS`\n",
        a.output.display(),
        world.mesh_count(),
        world.triangle_count(),
        bytes as f64 / (1u64 << 20) as f64,
        start.elapsed().as_secs_f64(),
        a.output.display(),
    ))?;
    Ok(())
}

fn graph(a: GraphArgs) -> Result<(), Box<dyn std::error::Error>> {
    if let Some(path) = &a.output {
        meshlight_output::check_output_path(path)?;
    }
    let options = meshlight_cli::graph::options(a.for_adapter, a.class)?;
    let plan = meshlight_cli::graph::plan(&a.pipeline, &options)?;
    let title = a.pipeline.display().to_string();
    let text = match a.format {
        Format::Dot => dump::to_dot(&plan),
        Format::Json => dump::to_json(&plan, None),
        Format::Mermaid => dump::to_mermaid(&plan),
        Format::Html => dump::to_html(&plan, &title, None),
        Format::Svg => dump::to_svg(&plan),
    };
    match a.output {
        Some(path) => meshlight_output::write_file(&path, text.as_bytes())?,
        None => meshlight_output::write_stdout(&text)?,
    }
    Ok(())
}
