//! `meshlight render`: one still of the scene through the frame graph, its counters and
//! timings on standard output, and optionally the graph's HTML report.

use crate::args::SceneArgs;
use meshlight::graph::dump;
use meshlight::stream::Budget;
use meshlight_cli::render_bounds::{self, RenderNumbers};
use meshlight_output::{check_output_path, write_file, write_png, write_stdout};
use meshlight_virtual_geometry::{Renderer, SceneOptions, SceneSetup, setup};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// Render the default scene (or a mesh) into a PNG.
#[derive(clap::Args)]
#[command(after_help = render_bounds::help())]
pub struct RenderArgs {
    #[command(flatten)]
    pub scene: SceneArgs,
    /// Initial size of the candidate-cluster list (grown when a frame overflows it);
    /// given, it wins over a pipeline file's `clusters`.
    #[arg(long)]
    pub clusters: Option<u64>,
    /// Initial number of raster slots (grown when a frame overflows them); given, it
    /// wins over a pipeline file's `slots`.
    #[arg(long)]
    pub slots: Option<u64>,
    /// The software rasteriser: auto (64-bit texture atomics where the adapter has
    /// them), texture or buffer. Given, it wins over the pipeline's.
    #[arg(long)]
    pub sw_raster: Option<String>,
    /// The hardware rasteriser: auto (in the adapter class's order: the indirect draw
    /// first where few units run graphics, else mesh shaders where the adapter has
    /// them), mesh_shader or indirect_draw. Given, it wins over the pipeline's.
    #[arg(long)]
    pub hw_raster: Option<String>,
    /// Clusters whose screen box is smaller than this many pixels are rasterised in
    /// software (default: the pipeline's; the shipped frame's is the adapter class's,
    /// see `meshlight info`).
    #[arg(long)]
    pub sw_threshold: Option<f32>,
    /// Output PNG (a path ending in .png, or one without an extension).
    #[arg(short, long, default_value = "out/default.png")]
    pub output: PathBuf,
    /// Also write the graph with this frame's timings and counters as a self-contained
    /// HTML page. Without it, a page beside the output named like it (out/default.html
    /// for out/default.png, left by an earlier render) is rewritten for this render,
    /// so it never describes an image that is gone.
    #[arg(long)]
    pub html: Option<PathBuf>,
    /// Also write the frame's GPU timings as a Chrome trace (JSON), which Perfetto
    /// (ui.perfetto.dev) and chrome://tracing open: one event per batch, or per pass with
    /// `--timing passes`.
    #[arg(long)]
    pub trace: Option<PathBuf>,
    /// GPU timing: `frame` (one timestamp pair per batch, the default), `passes` (per
    /// pass, for profiling: each pair costs GPU time) or `off`. Default: MESHLIGHT_TIMING.
    #[arg(long, value_parser = parse_timing)]
    pub timing: Option<meshlight::graph::TimingMode>,
    /// Checked mode: a validation error names the pass that caused it (default: on in
    /// debug builds, or MESHLIGHT_CHECKED).
    #[arg(long)]
    pub checked: bool,
}

/// Threads reading streamed pages.
const STREAM_THREADS: usize = 4;
/// Most frames a still waits for streaming to settle.
const MAX_STREAM_FRAMES: u32 = 600;

pub fn render(a: RenderArgs) -> Result<(), Box<dyn std::error::Error>> {
    let scene = a.scene.options();
    // Everything the command line bounds is checked before a mesh is baked or an adapter
    // requested, and the outputs' directories are made, so a mistake costs no render.
    check_bounds(&a, &scene)?;
    meshlight_output::check_png_path(&a.output)?;
    scene.check_pipeline()?;
    // Without --html, a page beside the output named like it is this image's report
    // from an earlier render: rewritten, so it never describes an image that is gone.
    let html = a.html.clone().or_else(|| {
        let beside = a.output.with_extension("html");
        (beside != a.output && beside.is_file()).then_some(beside)
    });
    for path in std::iter::once(&a.output).chain(&html).chain(&a.trace) {
        check_output_path(path)?;
    }
    let SceneSetup {
        data,
        camera,
        mut settings,
        lights,
        source,
        sources,
    } = setup(&scene)?;
    // What is given wins over the pipeline's; what is not leaves the pipeline's.
    for (stage, implementation) in [
        (meshlight::sw_raster::STAGE, &a.sw_raster),
        (meshlight::hw_raster::STAGE, &a.hw_raster),
    ] {
        if let Some(i) = implementation {
            settings = settings.with_implementation(stage, i);
        }
    }
    settings.sw_threshold_px = a.sw_threshold.or(settings.sw_threshold_px);
    settings.clusters = a.clusters;
    settings.slots = a.slots;
    let skipped = data.skipped_instances();
    let instances = data.instances.len();
    let source_triangles = data.source_triangles();
    let light_count = lights.len();
    let mut renderer = Renderer::new(data, settings, &source)?;
    renderer.lights = lights;
    if let Some(mode) = a.timing {
        renderer.executor.timing = mode;
    }
    renderer.executor.checked |= a.checked;
    let streamed_frames = match sources.is_empty() {
        true => 0,
        false => {
            renderer.start_streaming(sources, Budget::default(), STREAM_THREADS)?;
            renderer.settle_streaming(&camera, MAX_STREAM_FRAMES)?
        }
    };
    let still = renderer.render_still(&camera)?;
    write_png(&a.output, still.width, still.height, &still.rgba)?;
    // Written at once, so that a failing standard output is one error naming it.
    let mut report = String::new();
    let _ = writeln!(
        report,
        "rendered {instances} instances of {} ({source_triangles} source triangles) at {}x{} on {} → {}",
        scene.mesh.display(),
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
    if let Some(s) = renderer.streaming.as_ref().map(|s| s.stats()) {
        let f = s.frame;
        let _ = writeln!(
            report,
            "  streamed: settled after {streamed_frames} frames; pool {:.1} of {:.1} MiB, {} pages resident, {} read, {} evicted, {} refused; LOD scale {:.2} from pool pressure",
            f.pool_used as f64 / (1u64 << 20) as f64,
            f.pool_bytes as f64 / (1u64 << 20) as f64,
            f.resident_pages,
            s.loaded_total,
            s.evicted_total,
            s.failed_total,
            f.lod_scale
        );
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
    if let Some(s) = &renderer.settings.shadows {
        let c = s.cascades;
        let _ = writeln!(
            report,
            "  sun shadow: {} cascades of {}², to {:.1} units (split λ {}), casters {:.1} units towards the sun, held {}",
            c.count, c.resolution, c.distance, c.split_lambda, c.caster_reach, c.hold
        );
        let lists = meshlight_virtual_geometry::shadows::list_count(&renderer.pipeline, c.count);
        if lists > c.count {
            let _ = writeln!(
                report,
                "  one walk serves the camera and the cascades: its instance and hierarchy counts above are theirs together"
            );
        }
    }
    for c in &renderer.shadow_counts {
        let _ = writeln!(
            report,
            "  {:<30} {} clusters, {} triangles",
            format!("shadow cascade {}", c.cascade),
            c.drawn,
            c.triangles
        );
    }
    let _ = writeln!(
        report,
        "  {:<30} {:.2}",
        meshlight_virtual_geometry::counts::PER_PIXEL,
        still.counts.triangles_per_pixel(scene.width, scene.height)
    );
    // Per pass only where measured per pass (`--timing passes`); per batch otherwise.
    for p in &still.stats.passes {
        if let Some(us) = p.gpu_us {
            let _ = writeln!(report, "  {:<22} {us:.0} µs GPU", p.name);
        }
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
    match still.stats.gpu_frame_us {
        Some(total) => {
            let _ = writeln!(
                report,
                "  {:<22} {total:.0} µs GPU (timing mode {})",
                "frame",
                still.stats.timing.name()
            );
        }
        None => {
            let _ = writeln!(
                report,
                "  no GPU timings: timing mode {} on {}",
                still.stats.timing.name(),
                if renderer
                    .executor
                    .gpu
                    .features
                    .contains(wgpu::Features::TIMESTAMP_QUERY)
                {
                    "this adapter"
                } else {
                    "an adapter without timestamps"
                }
            );
        }
    }
    if let Some(path) = &a.trace {
        let timings = renderer.executor.take_gpu_timings()?;
        let frame: Vec<_> = timings
            .into_iter()
            .filter(|t| t.frame == still.stats.frame)
            .collect();
        if frame.is_empty() {
            return Err(format!(
                "--trace: frame {} has no GPU timings (timing mode {}); use --timing frame or passes on an adapter with timestamps",
                still.stats.frame,
                still.stats.timing.name()
            )
            .into());
        }
        let trace = dump::to_chrome_trace(&frame, Some(&renderer.compiled.plan));
        write_file(path, trace.as_bytes())?;
        let _ = writeln!(report, "trace: {}", path.display());
    }
    if let Some(html) = html {
        let image = image_link(&html, &a.output);
        let page = dump::to_html_report(
            &renderer.compiled.plan,
            &format!("meshlight: {}", scene.mesh.display()),
            &dump::Report {
                last_frame: Some(&still.stats),
                image: Some(&image),
                facts: &renderer
                    .streaming
                    .as_ref()
                    .map(|s| s.stats().rows())
                    .unwrap_or_default(),
            },
        );
        let page = match page.rfind("</body>") {
            Some(at) => format!(
                "{}{}{}",
                &page[..at],
                still.counts.html_table(Some((scene.width, scene.height))),
                &page[at..]
            ),
            None => page + &still.counts.html_table(Some((scene.width, scene.height))),
        };
        write_file(&html, page.as_bytes())?;
        let _ = writeln!(report, "graph: {}", html.display());
    }
    write_stdout(&report)?;
    Ok(())
}

/// The numbers the command line bounds, checked against the limits of the formats and
/// buffers they size.
fn check_bounds(a: &RenderArgs, scene: &SceneOptions) -> Result<(), Box<dyn std::error::Error>> {
    RenderNumbers::of_scene(scene, a.clusters, a.slots).check()?;
    Ok(())
}

fn parse_timing(name: &str) -> Result<meshlight::graph::TimingMode, String> {
    meshlight::graph::TimingMode::parse(name)
        .ok_or_else(|| format!("unknown timing mode `{name}`; use off, frame or passes"))
}

/// How the report page at `page` links the image at `image`: by file name beside it,
/// else by absolute path.
fn image_link(page: &Path, image: &Path) -> String {
    let folder = |p: &Path| p.parent().map(Path::to_path_buf);
    match image.file_name() {
        Some(name) if folder(page) == folder(image) => name.to_string_lossy().into_owned(),
        _ => std::path::absolute(image)
            .unwrap_or_else(|_| image.to_path_buf())
            .display()
            .to_string(),
    }
}
