//! The `meshlight` command line.

use clap::{Parser, Subcommand, ValueEnum};
use meshlight::graph::{CompileOptions, GraphError, dump};
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
    Render(RenderArgs),
    /// Compile a pipeline file without a GPU and dump the graph.
    Graph(GraphArgs),
    /// Run benchmark scenarios and print a table (and JSON).
    Bench(meshlight::bench::BenchArgs),
    /// Build a meshlet LOD asset from a mesh file.
    Bake(meshlight::scene::cli::BakeArgs),
    /// Print an asset's header and DAG statistics and verify its invariants.
    Inspect(meshlight::scene::cli::InspectArgs),
}

#[derive(clap::Args)]
struct RenderArgs {
    /// Mesh file (.obj, .gltf, .glb, .stl), or `procedural` for the default scene.
    #[arg(long, default_value = "procedural")]
    mesh: PathBuf,
    /// Tube segments of the procedural mesh (16 × segments² triangles; 256 ≈ 1M).
    #[arg(long, default_value_t = meshlight::scene::DEFAULT_SEGMENTS)]
    segments: u32,
    #[arg(long, default_value_t = 1280)]
    width: u32,
    #[arg(long, default_value_t = 720)]
    height: u32,
    /// Output PNG.
    #[arg(short, long, default_value = "out/default.png")]
    output: PathBuf,
    /// Also write the graph with this frame's timings as a self-contained HTML page.
    #[arg(long)]
    html: Option<PathBuf>,
}

#[derive(Clone, Copy, ValueEnum)]
enum Format {
    Dot,
    Json,
    Mermaid,
    Html,
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
}

/// Exit code when no Vulkan adapter exists, so scripts can install lavapipe and retry.
const EXIT_NO_ADAPTER: u8 = 3;

fn main() -> ExitCode {
    env_logger::Builder::from_env(env_logger::Env::default().default_filter_or("warn")).init();
    let cli = Cli::parse();
    let result: Result<(), Box<dyn std::error::Error>> = match cli.command {
        Command::Render(a) => render(a),
        Command::Graph(a) => graph(a),
        Command::Bench(a) => meshlight::bench::run(&a),
        Command::Bake(a) => meshlight::scene::cli::run_bake(&a).map_err(Into::into),
        Command::Inspect(a) => meshlight::scene::cli::run_inspect(&a).map_err(Into::into),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {e}");
            if matches!(
                e.downcast_ref::<GraphError>(),
                Some(GraphError::NoAdapter { .. })
            ) {
                return ExitCode::from(EXIT_NO_ADAPTER);
            }
            ExitCode::FAILURE
        }
    }
}

fn render(a: RenderArgs) -> Result<(), Box<dyn std::error::Error>> {
    let mesh = if a.mesh.as_os_str() == "procedural" {
        meshlight::scene::procedural_mesh(a.segments)
    } else {
        meshlight::scene::load::load_mesh(&a.mesh)?
    };
    let r = meshlight::demo::render(&mesh.positions, &mesh.indices, a.width, a.height)?;
    if let Some(dir) = a.output.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir)?;
    }
    let file = std::io::BufWriter::new(std::fs::File::create(&a.output)?);
    let mut enc = png::Encoder::new(file, r.width, r.height);
    enc.set_color(png::ColorType::Rgba);
    enc.set_depth(png::BitDepth::Eight);
    enc.write_header()?.write_image_data(&r.rgba)?;
    println!(
        "rendered {} ({} triangles) at {}x{} on {} → {}",
        mesh.source,
        mesh.indices.len() / 3,
        r.width,
        r.height,
        r.adapter,
        a.output.display()
    );
    for p in &r.stats.passes {
        let gpu = p
            .gpu_us
            .map(|g| format!("{:.0} µs GPU", g))
            .unwrap_or_else(|| "no timestamps".into());
        println!(
            "  {:<8} {gpu}, {:.0} µs CPU record (first frame: includes pipeline creation)",
            p.name, p.cpu_record_us
        );
    }
    if let Some(html) = a.html {
        std::fs::write(
            &html,
            dump::to_html(&r.plan, "meshlight default scene", Some(&r.stats)),
        )?;
        println!("graph: {}", html.display());
    }
    Ok(())
}

fn graph(a: GraphArgs) -> Result<(), Box<dyn std::error::Error>> {
    let builder = meshlight::graph::file::load_pipeline(&a.pipeline, &meshlight::registry())?;
    // Planning without a device assumes every feature; running checks the real adapter.
    let plan = builder
        .compile(&CompileOptions::new(wgpu::Features::all()))?
        .plan;
    let title = a.pipeline.display().to_string();
    let text = match a.format {
        Format::Dot => dump::to_dot(&plan),
        Format::Json => dump::to_json(&plan, None),
        Format::Mermaid => dump::to_mermaid(&plan),
        Format::Html => dump::to_html(&plan, &title, None),
    };
    match a.output {
        Some(path) => std::fs::write(path, text)?,
        None => print!("{text}"),
    }
    Ok(())
}
