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
    /// Build a meshlet LOD asset from a mesh file, or every mesh file under a directory
    /// (mirrored under the output directory, up-to-date outputs skipped).
    Bake(LibraryBakeArgs),
    /// Print an asset's header and DAG statistics and verify its invariants.
    Inspect(meshlight::scene::cli::InspectArgs),
    /// Print the adapter, the features and limits meshlight uses, and which
    /// implementation `auto` picks for each stage on it.
    Info,
}

#[derive(clap::Args)]
struct LibraryBakeArgs {
    #[command(flatten)]
    bake: meshlight::scene::cli::BakeArgs,
    /// Meshes baked at once, and threads in all (default: every core). The outputs are
    /// the same bytes whatever the number.
    #[arg(long, value_parser = clap::value_parser!(u32).range(1..=4096))]
    jobs: Option<u32>,
}

#[derive(clap::Args)]
struct RenderArgs {
    /// Mesh file (.obj, .gltf, .glb, .stl, or a baked .mlasset), or `procedural`.
    #[arg(long, default_value = "procedural")]
    mesh: PathBuf,
    /// Tube segments of the procedural mesh (16 × segments² triangles; 256 ≈ 1M).
    #[arg(long, default_value_t = meshlight::scene::DEFAULT_SEGMENTS)]
    segments: u32,
    /// Copies of the mesh on the ground (1: one copy, framed by the camera).
    #[arg(long, default_value_t = meshlight::virtual_geometry::scenes::DEFAULT_INSTANCES)]
    instances: u32,
    /// Coloured point lights over the field, clustered on the GPU and shaded per pixel
    /// (0: none; a single instance has none). `--view light-count` shows them per froxel.
    /// Default: 256, or 0 with a --pipeline file that clusters no lights (has no
    /// `z_slice` pass).
    #[arg(long)]
    lights: Option<u32>,
    /// A pipeline file to render with instead of the graph built in code, e.g.
    /// pipelines/virtual_geometry.toml or your own composition of the same resources.
    /// The file's own settings stand unless a flag is given (--view overrides its
    /// resolve's `view`, --clusters and --slots its list sizes). The shipped file
    /// clusters the lights as the frame built in code does and renders the same image.
    #[arg(long)]
    pipeline: Option<PathBuf>,
    /// What the image shows (default: shaded, or with --pipeline the view the file's
    /// resolve names). `occlusion`: green where the first culling pass drew the cluster,
    /// blue where the second did, redder the more of the instance occlusion culled (a
    /// still renders one frame before, so the frame has a history to cull against).
    /// `light-count` needs lights.
    #[arg(long, value_parser = view_parser())]
    view: Option<meshlight::resolve::DebugView>,
    /// Image width in pixels.
    #[arg(long, default_value_t = 1280)]
    width: u32,
    /// Image height in pixels.
    #[arg(long, default_value_t = 720)]
    height: u32,
    /// Initial size of the candidate-cluster list (grown when a frame overflows it);
    /// given, it wins over a pipeline file's `clusters`.
    #[arg(long)]
    clusters: Option<u64>,
    /// Initial number of raster slots (grown when a frame overflows them); given, it
    /// wins over a pipeline file's `slots`.
    #[arg(long)]
    slots: Option<u64>,
    /// The software rasteriser: auto (64-bit texture atomics where the adapter has
    /// them), texture or buffer. Ignored with --pipeline (the file names its own).
    #[arg(long, default_value = "auto")]
    sw_raster: String,
    /// The hardware rasteriser: auto (in the adapter class's order: the indirect draw
    /// first where few units run graphics, else mesh shaders where the adapter has
    /// them), mesh_shader or indirect_draw. Ignored with --pipeline.
    #[arg(long, default_value = "auto")]
    hw_raster: String,
    /// Clusters whose screen box is smaller than this many pixels are rasterised in
    /// software (default: the adapter class's, see `meshlight info`).
    #[arg(long)]
    sw_threshold: Option<f32>,
    /// Output PNG (a path ending in .png, or one without an extension).
    #[arg(short, long, default_value = "out/default.png")]
    output: PathBuf,
    /// Also write the graph with this frame's timings and counters as a self-contained
    /// HTML page. Without it, a page beside the output named like it (out/default.html
    /// for out/default.png, left by an earlier render) is rewritten for this render,
    /// so it never describes an image that is gone.
    #[arg(long)]
    html: Option<PathBuf>,
    /// GPU timing: `frame` (one timestamp pair per batch, the default), `passes` (per
    /// pass, for profiling: each pair costs GPU time) or `off`. Default: MESHLIGHT_TIMING.
    #[arg(long, value_parser = parse_timing)]
    timing: Option<meshlight::graph::TimingMode>,
    /// Checked mode: a validation error names the pass that caused it (default: on in
    /// debug builds, or MESHLIGHT_CHECKED).
    #[arg(long)]
    checked: bool,
}

fn parse_timing(name: &str) -> Result<meshlight::graph::TimingMode, String> {
    meshlight::graph::TimingMode::parse(name)
        .ok_or_else(|| format!("unknown timing mode `{name}`; use off, frame or passes"))
}

/// The views' names, listed by `render --help` and in the error for one that does not
/// exist, taken from the views the resolve pass has.
fn view_parser() -> impl clap::builder::TypedValueParser<Value = meshlight::resolve::DebugView> {
    use clap::builder::TypedValueParser as _;
    use meshlight::resolve::DebugView;
    clap::builder::PossibleValuesParser::new(DebugView::ALL.map(DebugView::name))
        .try_map(|name| DebugView::parse(&name))
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
    /// Plan for this machine's adapter (its features decide `auto`) instead of one with
    /// every feature.
    #[arg(long)]
    for_adapter: bool,
}

/// Froxel-list entries per light of the field ([`meshlight::virtual_geometry::scenes::field_lights`])
/// the clustering starts with: the default scene's 256 lights fill 5,821 entries (about
/// 23 froxels each, whatever the viewport, as the grid's size is fixed); a frame that
/// needs more still grows the list.
const FIELD_ENTRIES_PER_LIGHT: u64 = 32;

/// Exit code when no Vulkan adapter exists, so scripts can install lavapipe and retry.
const EXIT_NO_ADAPTER: u8 = 3;

/// How the report page at `page` links the image at `image`: by file name beside it,
/// else by absolute path.
fn image_link(page: &std::path::Path, image: &std::path::Path) -> String {
    let folder = |p: &std::path::Path| p.parent().map(std::path::Path::to_path_buf);
    match image.file_name() {
        Some(name) if folder(page) == folder(image) => name.to_string_lossy().into_owned(),
        _ => std::path::absolute(image)
            .unwrap_or_else(|_| image.to_path_buf())
            .display()
            .to_string(),
    }
}

fn main() -> ExitCode {
    quiet_on_closed_stdout();
    usable_runtime_dir();
    env_logger::Builder::from_env(env_logger::Env::default().default_filter_or("warn")).init();
    let cli = Cli::parse();
    let result: Result<(), Box<dyn std::error::Error>> = match cli.command {
        Command::Render(a) => render(a),
        Command::Graph(a) => graph(a),
        Command::Bench(a) => meshlight::bench::run(&a),
        Command::Bake(a) => bake(a),
        Command::Inspect(a) => meshlight::scene::cli::run_inspect(&a).map_err(Into::into),
        Command::Info => meshlight::info::report()
            .and_then(|text| meshlight::output::write_stdout(&text).map_err(Into::into)),
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

/// The Vulkan loader's window-system probing (libwayland) prints `error:
/// XDG_RUNTIME_DIR is invalid or not set in the environment.` to standard error once per
/// probe when the variable is unset or not an absolute path, as on a fresh container or a
/// remote shell. meshlight opens no window, so the message only alarms: where the
/// variable is unset or does not name a directory, it is pointed at a private directory
/// (mode 0700, as the XDG spec asks) under the temporary directory before any wgpu call.
/// A valid value is left as it is.
fn usable_runtime_dir() {
    const VAR: &str = "XDG_RUNTIME_DIR";
    let valid = std::env::var_os(VAR)
        .map(PathBuf::from)
        .is_some_and(|dir| dir.is_absolute() && dir.is_dir());
    if valid {
        return;
    }
    #[cfg(unix)]
    {
        use std::os::unix::fs::{DirBuilderExt, MetadataExt};
        // SAFETY: getuid has no preconditions and cannot fail.
        let uid = unsafe { libc::getuid() };
        let dir = std::env::temp_dir().join(format!("meshlight-runtime-{uid}"));
        let made = std::fs::DirBuilder::new()
            .mode(0o700)
            .create(&dir)
            .or_else(|e| match e.kind() {
                std::io::ErrorKind::AlreadyExists => Ok(()),
                _ => Err(e),
            });
        // Only a directory this user owns is used; otherwise the loader's message stays,
        // which costs nothing but noise.
        let ours = made.is_ok()
            && std::fs::symlink_metadata(&dir).is_ok_and(|m| m.is_dir() && m.uid() == uid);
        if ours {
            // SAFETY: called at the start of `main`, before any thread exists.
            unsafe { std::env::set_var(VAR, &dir) };
        }
    }
}

/// A directory is baked as a library; a file (or `procedural`) as before. Both run in a
/// pool of `--jobs` threads.
fn bake(a: LibraryBakeArgs) -> Result<(), Box<dyn std::error::Error>> {
    let threads = match a.jobs {
        Some(n) => n as usize,
        None => std::thread::available_parallelism().map_or(1, |n| n.get()),
    };
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()?;
    if a.bake.input.is_dir() {
        let options = meshlight::scene::BuildOptions {
            grouping: a.bake.grouping,
            position_bits: a.bake.position_bits,
            ..Default::default()
        };
        pool.install(|| {
            meshlight::bake_library::run(&a.bake.input, &a.bake.output, &options, threads)
        })
        .map_err(Into::into)
    } else {
        pool.install(|| meshlight::scene::cli::run_bake(&a.bake))
            .map_err(Into::into)
    }
}

fn render(a: RenderArgs) -> Result<(), Box<dyn std::error::Error>> {
    use meshlight::output::{create_parent, write_file, write_png, write_stdout};
    use meshlight::virtual_geometry::{FrameSettings, GraphSource, Renderer, scenes};
    use std::fmt::Write as _;
    // Everything the command line bounds is checked before a mesh is baked or an adapter
    // requested, and the outputs' directories are made, so a mistake costs no render.
    // A pipeline file that clusters no lights renders without them unless they are
    // asked for, which is refused below; one that does gets the default scene's.
    let file_clusters_lights = a
        .pipeline
        .as_deref()
        .is_none_or(meshlight::virtual_geometry::frame_graph::file_clusters_lights);
    let lights_asked = a.lights.unwrap_or(if file_clusters_lights {
        scenes::DEFAULT_LIGHTS
    } else {
        0
    });
    meshlight::render_bounds::RenderNumbers {
        segments: a.segments,
        instances: a.instances,
        lights: lights_asked,
        width: a.width,
        height: a.height,
        clusters: a.clusters,
        slots: a.slots,
    }
    .check()?;
    meshlight::output::check_png_path(&a.output)?;
    if let Some(path) = &a.pipeline {
        meshlight::graph::file::read_pipeline_text(path)?;
        if lights_asked > 0 && a.instances > 1 && !file_clusters_lights {
            return Err(GraphError::PipelineFile {
                file: path.display().to_string(),
                message: format!(
                    "--lights {lights_asked}: the file clusters no lights (it has no `z_slice` pass); render with --lights 0 (its default), or add the light clustering's passes as pipelines/virtual_geometry.toml does"
                ),
            }
            .into());
        }
    }
    // Without --html, a page beside the output named like it is this image's report
    // from an earlier render: rewritten, so it never describes an image that is gone.
    let html = a.html.clone().or_else(|| {
        let beside = a.output.with_extension("html");
        (beside != a.output && beside.is_file()).then_some(beside)
    });
    create_parent(&a.output)?;
    if let Some(html) = &html {
        create_parent(html)?;
    }
    let asset = scenes::load_asset(&a.mesh, a.segments)?;
    // The scene's buffers are bound whole: sized for the adapter the frame will run on.
    let adapter = meshlight::graph::GpuAdapter::select()?;
    let limits = meshlight::gpu_scene::data::Limits::for_device(&adapter.adapter.limits());
    drop(adapter);
    let data = meshlight::gpu_scene::SceneData::new(limits);
    let placed = if a.instances == 1 {
        scenes::single(data, &asset)?
    } else {
        scenes::field(data, &asset, a.instances)?
    };
    let mut settings = FrameSettings::new(a.width, a.height);
    // A view given wins over a pipeline file's; none given leaves the file's.
    settings.view = a.view.unwrap_or_default();
    settings.keep_file_view = a.view.is_none();
    let lights = if a.instances > 1 {
        scenes::field_lights(&placed, lights_asked)
    } else {
        Vec::new()
    };
    if !lights.is_empty() || a.view.is_some_and(|v| v.needs_lights()) {
        let mut clustering = meshlight::light_clustering::ClusteringSettings::new(
            [a.width, a.height],
            lights.len().max(1) as u64,
        );
        // The froxel lists start large enough for the field's lights, so the default
        // render runs one frame rather than warning that its lists grew.
        clustering.entries = clustering
            .entries
            .max(lights.len() as u64 * FIELD_ENTRIES_PER_LIGHT);
        settings.clustering = Some(clustering);
    }
    settings.sw_raster = a.sw_raster.clone();
    settings.hw_raster = a.hw_raster.clone();
    settings.sw_threshold_px = a.sw_threshold;
    settings.clusters = a.clusters.unwrap_or(settings.clusters);
    settings.slots = a.slots.unwrap_or(settings.slots);
    // Sizes given win over a pipeline file's; none given leaves the file's.
    settings.keep_file_lists = meshlight::virtual_geometry::frame_graph::KeepFileLists {
        clusters: a.clusters.is_none(),
        slots: a.slots.is_none(),
    };
    let source = match &a.pipeline {
        Some(path) => GraphSource::File(path.clone()),
        None => GraphSource::Code,
    };
    let skipped = placed.data.skipped_instances();
    let instances = placed.data.instances.len();
    let source_triangles = placed.data.source_triangles();
    let light_count = lights.len();
    let mut renderer = Renderer::new(placed.data, settings, &source)?;
    renderer.lights = lights;
    if let Some(mode) = a.timing {
        renderer.executor.timing = mode;
    }
    renderer.executor.checked |= a.checked;
    let still = renderer.render_still(&placed.camera)?;
    write_png(&a.output, still.width, still.height, &still.rgba)?;
    // Written at once, so that a failing standard output is one error naming it.
    let mut report = String::new();
    let _ = writeln!(
        report,
        "rendered {instances} instances of {} ({source_triangles} source triangles) at {}x{} on {} → {}",
        a.mesh.display(),
        still.width,
        still.height,
        renderer.adapter,
        a.output.display()
    );
    for p in &renderer.compiled.plan.passes {
        if let Some(reason) = p.choice_reason() {
            let _ = writeln!(
                report,
                "  {:<22} {}: {reason}",
                p.name,
                p.implementation_label()
            );
        }
    }
    if light_count > 0 {
        let _ = writeln!(report, "  {light_count} point lights clustered on the GPU");
    }
    if skipped > 0 {
        let _ = writeln!(
            report,
            "  {skipped} instances skipped: their transforms were singular or not finite"
        );
    }
    if still.frames > 1 {
        let _ = writeln!(
            report,
            "  {} frames: the lists grew ({})",
            still.frames,
            renderer
                .growths
                .iter()
                .map(|g| (g.param, g.from, g.to))
                .chain(
                    renderer
                        .clustering
                        .growths
                        .iter()
                        .map(|g| (g.param, g.from, g.to))
                )
                .map(|(param, from, to)| format!("{param} {from} → {to}"))
                .collect::<Vec<_>>()
                .join(", ")
        );
    }
    for (label, value) in still.counts.rows() {
        let _ = writeln!(report, "  {label:<30} {value}");
    }
    let _ = writeln!(
        report,
        "  {:<30} {:.2}",
        meshlight::virtual_geometry::counts::PER_PIXEL,
        still.counts.triangles_per_pixel(a.width, a.height)
    );
    for p in &still.stats.passes {
        let gpu = p
            .gpu_us
            .map(|g| format!("{g:.0} µs GPU"))
            .unwrap_or_else(|| "no timestamps".into());
        let _ = writeln!(report, "  {:<22} {gpu}", p.name);
    }
    for b in &still.stats.batches {
        if let Some(us) = b.gpu_us {
            let _ = writeln!(
                report,
                "  {:<22} {us:.0} µs GPU ({})",
                b.label,
                b.passes.join(", ")
            );
        }
    }
    if let Some(total) = still.stats.gpu_frame_us {
        let _ = writeln!(
            report,
            "  {:<22} {total:.0} µs GPU (timing mode {})",
            "frame",
            still.stats.timing.name()
        );
    }
    if let Some(html) = html {
        let image = image_link(&html, &a.output);
        let page = dump::to_html_report(
            &renderer.compiled.plan,
            &format!("meshlight: {}", a.mesh.display()),
            &dump::Report {
                last_frame: Some(&still.stats),
                image: Some(&image),
            },
        );
        let page = match page.rfind("</body>") {
            Some(at) => format!(
                "{}{}{}",
                &page[..at],
                still.counts.html_table(Some((a.width, a.height))),
                &page[at..]
            ),
            None => page + &still.counts.html_table(Some((a.width, a.height))),
        };
        write_file(&html, page.as_bytes())?;
        let _ = writeln!(report, "graph: {}", html.display());
    }
    write_stdout(&report)?;
    Ok(())
}

fn graph(a: GraphArgs) -> Result<(), Box<dyn std::error::Error>> {
    let builder = meshlight::graph::file::load_pipeline(&a.pipeline, &meshlight::registry())?;
    // Planning without a device assumes every feature; running checks the real adapter.
    let options = if a.for_adapter {
        CompileOptions::for_adapter(&meshlight::graph::GpuAdapter::select()?)
    } else {
        CompileOptions::new(wgpu::Features::all())
    };
    let plan = builder.compile(&options)?.plan;
    let title = a.pipeline.display().to_string();
    let text = match a.format {
        Format::Dot => dump::to_dot(&plan),
        Format::Json => dump::to_json(&plan, None),
        Format::Mermaid => dump::to_mermaid(&plan),
        Format::Html => dump::to_html(&plan, &title, None),
        Format::Svg => dump::to_svg(&plan),
    };
    match a.output {
        Some(path) => meshlight::output::write_file(&path, text.as_bytes())?,
        None => meshlight::output::write_stdout(&text)?,
    }
    Ok(())
}
