//! Benchmark scenarios of the virtual-geometry frame: per-pass GPU times from
//! timestamps, the frame's counters, and rasteriser throughput with every cluster sent
//! to one rasteriser, all measured in the same run.

use crate::{Row, median, row};
use meshlight::gpu_scene::SceneData;
use meshlight::graph::{GpuTimings, TimingMode};
use meshlight_virtual_geometry::scenes::{self, Placed};
use meshlight_virtual_geometry::{FrameSettings, GraphSource, Renderer};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

type BenchResult = std::result::Result<Vec<Row>, Box<dyn std::error::Error>>;

/// Median GPU times over `frames` back-to-back frames after one still frame (which lets
/// the lists grow to what the view needs). The frame's time comes from the default
/// `frame` timing mode (a timestamp pair per batch, which barely disturbs the frame);
/// the per-pass profile from a second run of as many frames in `passes` mode, which
/// serialises every pass and so adds its own cost to each.
pub struct Measured {
    /// Per pass, from the `passes` timing mode.
    pub passes: Vec<(String, f64)>,
    /// The frame, from the `frame` timing mode (the median frame).
    pub total_ms: f64,
    /// The mean frame of the same frames: with what a frame does now and then (a
    /// probe of adaptive occlusion, a list grown) spread over them.
    pub mean_ms: f64,
    /// The frame as the sum of the `passes`-mode profile, for comparison.
    pub profiled_total_ms: f64,
    pub counts: meshlight_virtual_geometry::FrameCounts,
    pub device: String,
    /// A streamed scene's figures after the timed frames.
    pub stream: Option<meshlight_virtual_geometry::streaming::StreamStats>,
    /// Each shadow cascade's counters, of the last still.
    pub shadow_counts: Vec<meshlight_virtual_geometry::shadows::CascadeCounts>,
}

pub fn measure(
    placed: &Placed,
    settings: FrameSettings,
    frames: u32,
) -> Result<Measured, Box<dyn std::error::Error>> {
    measure_prepared(placed, settings, frames, |_| Ok(()))
}

/// Frames at one camera for a second before anything is timed: a GPU left idle (while a
/// scene loads, or streaming settles a frame at a time) runs its next hundreds of frames
/// at a lower clock. It does not cure a slow first case seen on an NVIDIA H200 in a
/// process that first baked its meshes (docs/BENCHMARKS.md, "Measuring").
pub fn warm_up(
    r: &mut Renderer,
    camera: &meshlight::gpu_scene::Camera,
) -> Result<(), Box<dyn std::error::Error>> {
    let start = std::time::Instant::now();
    while start.elapsed() < std::time::Duration::from_secs(1) {
        r.frame(camera)?;
        r.executor.finish()?;
    }
    Ok(())
}

/// [`measure`], with `prepare` run on the renderer before anything is timed.
pub fn measure_prepared(
    placed: &Placed,
    settings: FrameSettings,
    frames: u32,
    prepare: impl FnOnce(&mut Renderer) -> Result<(), Box<dyn std::error::Error>>,
) -> Result<Measured, Box<dyn std::error::Error>> {
    let mut renderer = Renderer::new(placed.data.clone(), settings, &GraphSource::Shipped)?;
    prepare(&mut renderer)?;
    warm_up(&mut renderer, &placed.camera)?;
    let framed = timed_frames(&mut renderer, &placed.camera, frames, TimingMode::Frame)?;
    let profiled = timed_frames(&mut renderer, &placed.camera, frames, TimingMode::Passes)?;
    // The counters of a frame like the timed ones: with occlusion, the still's are
    // those of a first frame, which has no history to test against.
    let counts = renderer.render_still(&placed.camera)?.counts;
    let mut per_pass: BTreeMap<String, Vec<f64>> = BTreeMap::new();
    let mut order = Vec::new();
    for (k, t) in profiled.iter().enumerate() {
        for (name, us) in &t.passes {
            if !per_pass.contains_key(name) {
                order.push(name.clone());
            }
            // A pass some frames leave out (adaptive occlusion's second pass, a kept
            // shadow cascade) costs those frames nothing.
            let times = per_pass.entry(name.clone()).or_default();
            times.resize(k, 0.0);
            times.push(us / 1e3);
        }
    }
    for times in per_pass.values_mut() {
        times.resize(profiled.len(), 0.0);
    }
    let passes = order
        .into_iter()
        .map(|n| {
            let v = per_pass.remove(&n).unwrap_or_default();
            (n, median(v))
        })
        .collect();
    let total = |t: &[GpuTimings]| median(t.iter().map(|t| t.total_us / 1e3).collect());
    Ok(Measured {
        passes,
        total_ms: total(&framed),
        mean_ms: framed.iter().map(|t| t.total_us / 1e3).sum::<f64>() / framed.len() as f64,
        profiled_total_ms: total(&profiled),
        counts,
        device: renderer.adapter.clone(),
        stream: renderer.streaming.as_ref().map(|s| s.stats()),
        shadow_counts: renderer.shadow_counts.clone(),
    })
}

/// The GPU timings of `frames` back-to-back frames in timing `mode`, after one still
/// frame (which lets the lists grow to what the view needs).
fn timed_frames(
    renderer: &mut Renderer,
    camera: &meshlight::gpu_scene::Camera,
    frames: u32,
    mode: TimingMode,
) -> Result<Vec<GpuTimings>, Box<dyn std::error::Error>> {
    renderer.executor.timing = mode;
    renderer.render_still(camera)?;
    renderer.executor.take_gpu_timings()?;
    for _ in 0..frames {
        renderer.frame(camera)?;
    }
    renderer.executor.finish()?;
    let timings = renderer.executor.take_gpu_timings()?;
    if timings.is_empty() {
        return Err(format!(
            "{} has no GPU timestamps; nothing to measure",
            renderer.adapter
        )
        .into());
    }
    Ok(timings)
}

fn rows_of(scenario: &str, case: &str, m: &Measured) -> Vec<Row> {
    let mut rows: Vec<Row> = m
        .passes
        .iter()
        .filter(|(name, _)| !name.starts_with("readback:"))
        .map(|(name, ms)| {
            row(
                scenario,
                case.into(),
                &format!("GPU {name} (timing mode passes)"),
                *ms,
                "ms",
                &m.device,
            )
        })
        .collect();
    rows.push(row(
        scenario,
        case.into(),
        "GPU frame (timing mode frame)",
        m.total_ms,
        "ms",
        &m.device,
    ));
    rows.push(row(
        scenario,
        case.into(),
        "GPU frame, mean (timing mode frame)",
        m.mean_ms,
        "ms",
        &m.device,
    ));
    rows.push(row(
        scenario,
        case.into(),
        "GPU frame, sum of the per-pass profile (timing mode passes)",
        m.profiled_total_ms,
        "ms",
        &m.device,
    ));
    for (label, value) in m.counts.rows() {
        rows.push(row(
            scenario,
            case.into(),
            label,
            value as f64,
            "",
            &m.device,
        ));
    }
    rows
}

fn pass_ms(m: &Measured, pass: &str) -> f64 {
    ran_ms(m, pass).unwrap_or(f64::NAN)
}

/// `pass`'s time in `m`'s per-pass profile; `None` where the frame did not run it.
fn ran_ms(m: &Measured, pass: &str) -> Option<f64> {
    m.passes.iter().find(|(n, _)| n == pass).map(|(_, ms)| *ms)
}

/// The mesh of the lattice and million scenarios: the first of `meshes`, the Stanford
/// bunny when none is named.
fn mesh_or_bunny(meshes: &[PathBuf]) -> PathBuf {
    meshes
        .first()
        .cloned()
        .unwrap_or_else(|| PathBuf::from("assets/meshes/stanford-bunny.obj"))
}

/// A row's case, alike in every scenario: what the scene holds, its source triangles
/// and the viewport (the charts read the scene's size from the first word).
fn case_label(scene: &str, placed: &Placed, width: u32, height: u32) -> String {
    format!(
        "{scene}, {} source tris, {width}x{height}",
        placed.data.source_triangles()
    )
}

/// The mesh's file name without its extension, as the cases name it.
fn stem(mesh: &Path) -> std::borrow::Cow<'_, str> {
    mesh.file_stem().unwrap_or_default().to_string_lossy()
}

/// The viewports of the field scenes, 1920×1080 and 3840×2160 (1080p alone with
/// `quick`), and the frames each is measured over.
fn screen_sizes(quick: bool) -> (&'static [(u32, u32)], u32) {
    if quick {
        (&[(1920, 1080)], 5)
    } else {
        (&[(1920, 1080), (3840, 2160)], 50)
    }
}

/// The default scene's field of procedural meshes and their count (64 small ones with
/// `quick`).
fn default_field(quick: bool) -> Result<(Placed, u32), Box<dyn std::error::Error>> {
    let (segments, instances) = if quick {
        (64, 64)
    } else {
        (
            meshlight::scene::DEFAULT_SEGMENTS,
            scenes::DEFAULT_INSTANCES,
        )
    };
    let asset = scenes::load_asset(Path::new("procedural"), segments)?;
    let placed = scenes::field(SceneData::new(Default::default()), &asset, instances)?;
    Ok((placed, instances))
}

/// The default scene (a field of procedural meshes on the ground) at 1920×1080 and
/// 3840×2160 (1080p alone with `quick`), each also without occlusion and with occlusion
/// tested every frame ([`occlusion_rows`]), and with the hardware rasteriser.
pub fn default_scene(quick: bool) -> BenchResult {
    let (placed, instances) = default_field(quick)?;
    let (sizes, frames) = screen_sizes(quick);
    let mut rows = Vec::new();
    for &(width, height) in sizes {
        let case = case_label(
            &format!("{instances} procedural meshes"),
            &placed,
            width,
            height,
        );
        let settings = FrameSettings::new(width, height);
        let m = measure(&placed, settings.clone(), frames)?;
        rows.extend(rows_of("render", &case, &m));
        rows.extend(occlusion_rows("render", &case, &placed, &settings, frames)?);
        // The same frame with the clusters crossing the near plane (and, on a graphics
        // GPU, the large ones) drawn by the hardware rasteriser.
        let hardware = FrameSettings {
            hardware: Some(true),
            ..FrameSettings::new(width, height)
        };
        let m = measure(&placed, hardware, frames)?;
        rows.extend(rows_of("render", &format!("{case}, with hw_raster"), &m));
    }
    Ok(rows)
}

/// The sun's shadow (`vg-shadows`): the default scene at 1920×1080 and 1,048,576 bunnies
/// at 2560×1440, each without shadows and with four 2048² cascades to the default
/// shadow distance: every cascade drawn every frame (as when the camera moves), and kept
/// while nothing changes (a still camera: the frame then draws no cascade); drawn every
/// frame also with a walk per cascade instead of one walk for all four, and with the
/// camera's walk serving the four too (drawn and kept: one walk for every view); the default
/// scene also with a shadow LOD bias of 1. All in one run. Per case: the frame, the
/// shadow passes' sum and share of the per-pass profile, the walks' sum, and each
/// cascade's clusters and triangles. With `quick`, 64 small meshes and 4,096 bunnies.
pub fn shadows(quick: bool, meshes: &[PathBuf]) -> BenchResult {
    use meshlight_virtual_geometry::setup::ShadowRequest;
    use meshlight_virtual_geometry::shadows::ShadowWalk;
    const ONE: ShadowWalk = ShadowWalk::AsWritten;
    const PER: ShadowWalk = ShadowWalk::PerView;
    const WITH: ShadowWalk = ShadowWalk::WithCamera;
    let (segments, instances) = if quick {
        (64, 64)
    } else {
        (
            meshlight::scene::DEFAULT_SEGMENTS,
            scenes::DEFAULT_INSTANCES,
        )
    };
    let frames = if quick { 5 } else { 50 };
    let asset = scenes::load_asset(Path::new("procedural"), segments)?;
    let default = scenes::field(SceneData::new(Default::default()), &asset, instances)?;
    let mesh = mesh_or_bunny(meshes);
    let bunny = scenes::load_asset(&mesh, 0)?;
    let adapter = meshlight::graph::GpuAdapter::select()?;
    let limits = meshlight::gpu_scene::data::Limits::for_device(&adapter.adapter.limits());
    drop(adapter);
    let copies = if quick { 4096 } else { 1 << 20 };
    let million = scenes::field(SceneData::new(limits), &bunny, copies)?;
    let request = ShadowRequest {
        cascades: Some(4),
        resolution: Some(2048),
        ..ShadowRequest::default()
    };
    let mut rows = Vec::new();
    // (LOD bias, maps kept while nothing changes, how the cascades are walked)
    let cases = [
        (
            &default,
            format!("{instances} procedural meshes"),
            (1920, 1080),
            &[
                (0.0, false, ONE),
                (0.0, false, PER),
                (0.0, false, WITH),
                (0.0, true, ONE),
                (0.0, true, WITH),
                (1.0, false, ONE),
            ][..],
        ),
        (
            &million,
            format!("{copies} {} on the field", stem(&mesh)),
            (2560, 1440),
            &[
                (0.0, false, ONE),
                (0.0, false, PER),
                (0.0, false, WITH),
                (0.0, true, ONE),
                (0.0, true, WITH),
            ][..],
        ),
    ];
    for (placed, scene, (width, height), variants) in cases {
        let case = case_label(&scene, placed, width, height);
        let m = measure(placed, FrameSettings::new(width, height), frames)?;
        rows.extend(rows_of("vg-shadows", &format!("{case}, no shadows"), &m));
        // A moving camera: without shadows, with the shipped (held) cascades, and with
        // cascades fitted to their slices (every move draws them again).
        let shipped = request
            .settings(&placed.data, &placed.camera, [width, height], true)
            .ok_or("no shadows")?;
        let mut fitted = shipped;
        fitted.cascades.hold = 0.0;
        let moving_frames = if quick { 20 } else { 600 };
        for (label, shadows) in [
            ("no shadows", None),
            ("cascades held", Some(shipped)),
            ("cascades fitted", Some(fitted)),
        ] {
            let settings = FrameSettings {
                shadows,
                ..FrameSettings::new(width, height)
            };
            let m = measure_moving(placed, settings, moving_frames, shipped.cascades.distance)?;
            let case = format!("{case}, camera moving, {label}");
            for (what, value, unit) in [
                ("GPU frame, mean (timing mode frame)", m.mean_ms, "ms"),
                (
                    "GPU frame, 95th percentile (timing mode frame)",
                    m.p95_ms,
                    "ms",
                ),
                ("GPU frame, worst (timing mode frame)", m.worst_ms, "ms"),
                ("cascades drawn a frame, mean", m.cascades_drawn, ""),
                ("lists grown along the path", m.growths as f64, ""),
                (
                    "GPU frame held still at the path's end (timing mode frame)",
                    m.still_at_end_ms,
                    "ms",
                ),
            ] {
                rows.push(row(
                    "vg-shadows",
                    case.clone(),
                    what,
                    value,
                    unit,
                    &m.device,
                ));
            }
            for (name, ms) in &m.passes {
                let what = format!("GPU {name}, mean along the path (timing mode passes)");
                rows.push(row("vg-shadows", case.clone(), &what, *ms, "ms", &m.device));
            }
        }
        for &(lod_bias, cache, walk) in variants {
            let mut shadows = ShadowRequest {
                lod_bias,
                ..request
            }
            .settings(&placed.data, &placed.camera, [width, height], true)
            .ok_or("no shadows")?;
            shadows.cache = cache;
            shadows.walk = walk;
            let settings = FrameSettings {
                shadows: Some(shadows),
                ..FrameSettings::new(width, height)
            };
            let m = measure(placed, settings, frames)?;
            let case = format!(
                "{case}, 4 cascades of 2048² to {:.0} units, LOD bias {lod_bias}, {}, {}",
                shadows.cascades.distance,
                if cache {
                    "kept while still"
                } else {
                    "drawn every frame"
                },
                match walk {
                    ShadowWalk::AsWritten => "one walk for all cascades",
                    ShadowWalk::PerView => "a walk per cascade",
                    ShadowWalk::WithCamera => "one walk for the camera and every cascade",
                }
            );
            rows.extend(rows_of("vg-shadows", &case, &m));
            let shadow_ms: f64 = m
                .passes
                .iter()
                .filter(|(n, _)| n.starts_with("shadow_"))
                .map(|(_, ms)| ms)
                .sum();
            let walk_ms: f64 = m
                .passes
                .iter()
                .filter(|(n, _)| n.starts_with("shadow_fill"))
                .map(|(_, ms)| ms)
                .sum();
            // The camera's first walk and the shadow walks: what one walk for every view
            // replaces (its shadow share then holds no walk).
            let first_walks_ms: f64 = m
                .passes
                .iter()
                .filter(|(n, _)| n == "fill" || n.starts_with("shadow_fill"))
                .map(|(_, ms)| ms)
                .sum();
            let device = m.device.as_str();
            rows.push(row(
                "vg-shadows",
                case.clone(),
                "GPU first walks (camera's and shadows'), sum (timing mode passes)",
                first_walks_ms,
                "ms",
                device,
            ));
            rows.push(row(
                "vg-shadows",
                case.clone(),
                "GPU shadow passes, sum (timing mode passes)",
                shadow_ms,
                "ms",
                device,
            ));
            rows.push(row(
                "vg-shadows",
                case.clone(),
                "GPU shadow walks, sum (timing mode passes)",
                walk_ms,
                "ms",
                device,
            ));
            rows.push(row(
                "vg-shadows",
                case.clone(),
                "shadow passes' share of the profiled frame",
                100.0 * shadow_ms / m.profiled_total_ms,
                "%",
                device,
            ));
            for c in &m.shadow_counts {
                let k = c.cascade;
                rows.push(row(
                    "vg-shadows",
                    case.clone(),
                    &format!("shadow cascade {k}: clusters drawn"),
                    f64::from(c.drawn),
                    "",
                    device,
                ));
                rows.push(row(
                    "vg-shadows",
                    case.clone(),
                    &format!("shadow cascade {k}: triangles drawn"),
                    f64::from(c.triangles),
                    "",
                    device,
                ));
            }
        }
    }
    Ok(rows)
}

/// What a camera moving along a path costs: per frame, the `frame` timing mode's time
/// and the cascades drawn.
struct Moving {
    mean_ms: f64,
    p95_ms: f64,
    worst_ms: f64,
    cascades_drawn: f64,
    /// The frame held still at the path's end, for comparison.
    still_at_end_ms: f64,
    /// Lists grown along the path (the first time through).
    growths: usize,
    /// Per pass, the mean along the path again in the `passes` timing mode.
    passes: Vec<(String, f64)>,
    device: String,
}

/// `frames` frames along a path from `placed.camera`: forward a 2000th of `distance` a
/// frame (at 60 frames a second, the shadow distance in 33 s) while turning 0.05° a
/// frame (3° a second), the `frame` timing mode after a warm-up at the start.
fn measure_moving(
    placed: &Placed,
    settings: FrameSettings,
    frames: u32,
    distance: f32,
) -> Result<Moving, Box<dyn std::error::Error>> {
    let mut r = Renderer::new(placed.data.clone(), settings, &GraphSource::Shipped)?;
    let start = placed.camera;
    let forward = (start.target - start.position).normalize();
    let reach = (start.target - start.position).length();
    let at = |i: u32| {
        let mut c = start;
        c.position = start.position + forward * (distance / 2000.0 * i as f32);
        let turn = glam::Quat::from_rotation_y((0.05 * i as f32).to_radians());
        c.target = c.position + turn * forward * reach;
        c
    };
    warm_up(&mut r, &start)?;
    r.executor.timing = TimingMode::Frame;
    r.render_still(&start)?;
    r.executor.take_gpu_timings()?;
    let mut drawn = 0u64;
    let grown_before = r.growths.len();
    for i in 1..=frames {
        r.frame(&at(i))?;
        drawn += u64::from(r.cascades_drawn);
    }
    r.executor.finish()?;
    let growths = r.growths.len() - grown_before;
    let mut ms: Vec<f64> = r
        .executor
        .take_gpu_timings()?
        .iter()
        .map(|t| t.total_us / 1e3)
        .collect();
    if ms.is_empty() {
        return Err(format!("{} has no GPU timestamps; nothing to measure", r.adapter).into());
    }
    ms.sort_by(f64::total_cmp);
    // Where the moving frame's time goes: the path again from its start, profiled.
    r.executor.timing = TimingMode::Passes;
    r.render_still(&start)?;
    r.executor.take_gpu_timings()?;
    for i in 1..=frames {
        r.frame(&at(i))?;
    }
    r.executor.finish()?;
    let profiled = r.executor.take_gpu_timings()?;
    let mut sums: Vec<(String, f64)> = Vec::new();
    for t in &profiled {
        for (name, us) in &t.passes {
            match sums.iter_mut().find(|(n, _)| n == name) {
                Some((_, sum)) => *sum += us / 1e3,
                None => sums.push((name.clone(), us / 1e3)),
            }
        }
    }
    let passes = sums
        .into_iter()
        .filter(|(name, _)| !name.starts_with("readback:"))
        .map(|(name, sum)| (name, sum / profiled.len().max(1) as f64))
        .collect();
    let still = timed_frames(&mut r, &at(frames), 50, TimingMode::Frame)?;
    Ok(Moving {
        mean_ms: ms.iter().sum::<f64>() / ms.len() as f64,
        p95_ms: ms[(ms.len() * 95 / 100).min(ms.len() - 1)],
        worst_ms: ms[ms.len() - 1],
        cascades_drawn: drawn as f64 / f64::from(frames),
        still_at_end_ms: median(still.iter().map(|t| t.total_us / 1e3).collect()),
        growths,
        passes,
        device: r.adapter.clone(),
    })
}

/// Textures of the `textured` scenario: Spot's own, tinted to as many hues, each
/// uploaded at this side.
const TEXTURED_COUNT: u32 = 64;
const TEXTURED_SIDE: u32 = 512;

/// Spot with its own texture on the default field (1,024 copies; 64 with `quick`),
/// [`TEXTURED_COUNT`] copies of the texture tinted to as many hues (so neighbouring
/// copies read different texels), at 1920×1080 and 3840×2160 (1080p alone with
/// `quick`): the frame and the resolve with textures, and the texture memory; then the
/// same field with MASK materials that cut a quarter of each texture, at the first size.
pub fn textured(quick: bool) -> BenchResult {
    let dir = std::env::temp_dir().join(format!("meshlight-bench-spot-{}", std::process::id()));
    std::fs::create_dir_all(&dir)?;
    let meshes = Path::new("assets/meshes");
    let mut obj = b"mtllib spot.mtl\nusemtl spot\n".to_vec();
    obj.extend(std::fs::read(meshes.join("spot.obj"))?);
    std::fs::write(dir.join("spot.obj"), obj)?;
    for file in ["spot.mtl", "spot_texture.png"] {
        std::fs::copy(meshes.join(file), dir.join(file))?;
    }
    let (asset, materials) = scenes::load_obj_with_materials(&dir.join("spot.obj"))?
        .ok_or("spot.mtl should give Spot its texture")?;
    let spot = materials[0]
        .diffuse_texture
        .clone()
        .ok_or("spot.mtl should name spot_texture.png")?;
    let small = meshlight::scene::texture::resample_square(
        &spot,
        TEXTURED_SIDE,
        meshlight::scene::texture::ColorSpace::Srgb,
    );
    let instances = if quick { 64 } else { scenes::DEFAULT_INSTANCES };
    let (sizes, frames) = screen_sizes(quick);
    let mut rows = Vec::new();
    for masked in [false, true] {
        let (placed, texture_bytes) = textured_field(&asset, &small, instances, masked)?;
        // The masked field once, at the first size: what the cut-out test costs.
        let sizes = if masked { &sizes[..1] } else { sizes };
        for &(width, height) in sizes {
            let what = if masked {
                ", MASK (a quarter of the texels cut)"
            } else {
                ""
            };
            let case = case_label(
                &format!(
                    "{instances} textured Spots ({TEXTURED_COUNT} textures of {TEXTURED_SIDE}²){what}"
                ),
                &placed,
                width,
                height,
            );
            let m = measure(&placed, FrameSettings::new(width, height), frames)?;
            rows.extend(rows_of("textured", &case, &m));
            rows.push(row(
                "textured",
                case,
                "texture memory (RGBA8, mips included)",
                texture_bytes / (1 << 20) as f64,
                "MiB",
                &m.device,
            ));
        }
    }
    std::fs::remove_dir_all(&dir).ok();
    Ok(rows)
}

/// The `textured` field: `asset` placed `instances` times, each copy in one of
/// [`TEXTURED_COUNT`] materials whose base colour is `image` tinted to a hue of its own.
/// `masked`: the materials are MASK (cutoff 0.5) and a quarter of the texels (a grid of
/// square holes, 32 texels a period) have alpha 0, so both rasterisers run the cut-out
/// test on every pixel of the field and leave a quarter of it undrawn. Returns the
/// scene and its texture bytes.
fn textured_field(
    asset: &meshlight::scene::MeshletAsset,
    image: &meshlight::scene::texture::Image,
    instances: u32,
    masked: bool,
) -> Result<(Placed, f64), Box<dyn std::error::Error>> {
    let mut data = SceneData::new(Default::default());
    let mut runs = Vec::new();
    for k in 0..TEXTURED_COUNT {
        let hue = k as f32 / TEXTURED_COUNT as f32 * std::f32::consts::TAU;
        let tint = [0.0f32, 2.1, 4.2].map(|phase| 0.6 + 0.4 * (hue + phase).cos());
        let mut image = image.clone();
        let width = image.width as usize;
        for (i, texel) in image.rgba.chunks_exact_mut(4).enumerate() {
            for c in 0..3 {
                texel[c] = (texel[c] as f32 * tint[c]).round() as u8;
            }
            let (x, y) = (i % width, i / width);
            if masked && x % 32 < 16 && y % 32 < 16 {
                texel[3] = 0;
            }
        }
        let texture = data.add_image(
            &image,
            true,
            [meshlight::shaders::cpu::layout::TextureWrap::Repeat; 2],
        )?;
        let mut maps = [None; meshlight::shaders::cpu::layout::MAP_COUNT];
        maps[meshlight::shaders::cpu::layout::MAP_BASE_COLOR] = Some(texture);
        runs.push(data.add_material(meshlight::gpu_scene::Material {
            checker: false,
            maps,
            alpha_cutoff: masked.then_some(0.5),
            ..Default::default()
        })?);
    }
    let texture_bytes = data.textures.len() as f64 * 4.0;
    let placed = scenes::field_painted(data, asset, instances, scenes::Paint::Own(runs))?;
    Ok((placed, texture_bytes))
}

/// The scene of [`lattice`] and [`rasterisers`]: 15³ copies of a mesh (5³ at 1280×720
/// with `quick`), its viewport, frame count and the case label of its rows.
struct Lattice {
    mesh: PathBuf,
    placed: Placed,
    width: u32,
    height: u32,
    frames: u32,
    case: String,
}

impl Lattice {
    fn new(quick: bool, meshes: &[PathBuf]) -> Result<Self, Box<dyn std::error::Error>> {
        let mesh = mesh_or_bunny(meshes);
        let n = if quick { 5 } else { 15 };
        let asset = scenes::load_asset(&mesh, 0)?;
        let placed = scenes::lattice(SceneData::new(Default::default()), &asset, n)?;
        let (width, height) = if quick { (1280, 720) } else { (2240, 1260) };
        let case = case_label(&format!("{n}³ {}", stem(&mesh)), &placed, width, height);
        Ok(Self {
            mesh,
            placed,
            width,
            height,
            frames: if quick { 5 } else { 50 },
            case,
        })
    }
}

/// The frame of `settings` without occlusion (one culling pass) and with occlusion tested
/// every frame, against which the default (adaptive occlusion, measured by the caller)
/// is judged: with occlusion never slower than without.
fn occlusion_rows(
    scenario: &str,
    case: &str,
    placed: &Placed,
    settings: &FrameSettings,
    frames: u32,
) -> BenchResult {
    let one_pass = FrameSettings {
        occlusion: false,
        ..settings.clone()
    };
    let mut rows = rows_of(
        scenario,
        &format!("{case}, no occlusion"),
        &measure(placed, one_pass, frames)?,
    );
    let always = FrameSettings {
        occlusion_policy: meshlight_virtual_geometry::OcclusionPolicy::ALWAYS,
        ..settings.clone()
    };
    rows.extend(rows_of(
        scenario,
        &format!("{case}, occlusion tested every frame"),
        &measure(placed, always, frames)?,
    ));
    Ok(rows)
}

/// 15 × 15 × 15 copies of a mesh (the Stanford bunny unless `meshes` names another) at
/// 2240×1260: the frame, then the same cluster set drawn all in software and all in
/// hardware for each rasteriser's throughput.
pub fn lattice(quick: bool, meshes: &[PathBuf]) -> BenchResult {
    let Lattice {
        mesh,
        placed,
        width,
        height,
        frames,
        case,
    } = Lattice::new(quick, meshes)?;
    let settings = FrameSettings::new(width, height);
    let frame = measure(&placed, settings.clone(), frames)?;
    let mut rows = rows_of("virtual-geometry", &case, &frame);
    // The same frame with one culling pass and no occlusion test.
    let one_pass = FrameSettings {
        occlusion: false,
        ..settings.clone()
    };
    rows.extend(occlusion_rows(
        "virtual-geometry",
        &case,
        &placed,
        &settings,
        frames,
    )?);

    // The same cut, every cluster to one rasteriser.
    let software = measure(
        &placed,
        FrameSettings {
            hardware: Some(false),
            ..settings.clone()
        },
        frames,
    )?;
    // The whole cut, so no occlusion (which would split it over two passes).
    let hardware = measure(
        &placed,
        FrameSettings {
            sw_threshold_px: Some(0.0),
            ..one_pass
        },
        frames,
    )?;
    let sw_rate = software.counts.triangles() as f64 / (pass_ms(&software, "sw_raster") * 1e-3);
    let hw_rate =
        hardware.counts.hardware_triangles as f64 / (pass_ms(&hardware, "hw_raster") * 1e-3);
    let device = frame.device.clone();
    rows.push(row(
        "virtual-geometry",
        format!("{case}, all software"),
        "software raster",
        sw_rate / 1e9,
        "Gtri/s",
        &device,
    ));
    let mut hw_row = row(
        "virtual-geometry",
        format!("{case}, all hardware"),
        "hardware raster",
        hw_rate / 1e9,
        "Gtri/s",
        &device,
    );
    hw_row.vs_baseline = Some(hw_rate / sw_rate);
    rows.push(hw_row);
    let mut ratio = row(
        "virtual-geometry",
        case.clone(),
        "software / hardware throughput",
        sw_rate / hw_rate,
        "x",
        &device,
    );
    ratio.vs_baseline = Some(sw_rate / hw_rate);
    rows.push(ratio);

    // Where to split: the frame at other software thresholds (few units of these GPUs
    // run graphics, so the hardware side may be worth keeping small).
    let thresholds: &[f32] = if quick {
        &[64.0]
    } else {
        &[16.0, 64.0, 128.0, 256.0]
    };
    for &sw_threshold_px in thresholds {
        let m = measure(
            &placed,
            FrameSettings {
                sw_threshold_px: Some(sw_threshold_px),
                ..FrameSettings::new(width, height)
            },
            frames,
        )?;
        let label = format!("GPU frame, sw_threshold_px = {sw_threshold_px}");
        let mut r = row(
            "virtual-geometry",
            case.clone(),
            &label,
            m.total_ms,
            "ms",
            &device,
        );
        r.vs_baseline = Some(frame.total_ms / m.total_ms);
        rows.push(r);
    }

    // What bit-exact division costs the software rasteriser (all software, so every
    // cluster goes through it).
    let exact = measure(
        &placed,
        FrameSettings {
            hardware: Some(false),
            exact_division: Some(true),
            ..FrameSettings::new(width, height)
        },
        frames,
    )?;
    let (fast_ms, exact_ms) = (
        pass_ms(&software, "sw_raster"),
        pass_ms(&exact, "sw_raster"),
    );
    rows.push(row(
        "virtual-geometry",
        format!("{case}, all software"),
        "GPU sw_raster, driver division",
        fast_ms,
        "ms",
        &device,
    ));
    let mut r = row(
        "virtual-geometry",
        format!("{case}, all software"),
        "GPU sw_raster, exact division",
        exact_ms,
        "ms",
        &device,
    );
    r.vs_baseline = Some(fast_ms / exact_ms);
    rows.push(r);

    // What the optional depth targets cost: each is a fullscreen fragment pass.
    for (label, depth, material_depth) in [
        ("GPU frame, with the depth target", true, false),
        (
            "GPU frame, with depth and material-depth targets",
            true,
            true,
        ),
    ] {
        let m = measure(
            &placed,
            FrameSettings {
                depth,
                material_depth,
                ..FrameSettings::new(width, height)
            },
            frames,
        )?;
        let mut r = row(
            "virtual-geometry",
            case.clone(),
            label,
            m.total_ms,
            "ms",
            &device,
        );
        r.vs_baseline = Some(frame.total_ms / m.total_ms);
        rows.push(r);
        let resolve = pass_ms(&m, "resolve");
        rows.push(row(
            "virtual-geometry",
            case.clone(),
            &format!("{label}: GPU resolve"),
            resolve,
            "ms",
            &device,
        ));
    }

    // The baseline: every instance's LOD 0 in one instanced draw, same scene and camera.
    let source = meshlight::scene::load::load_mesh(&mesh)?;
    let baseline_ms = brute_force(&placed, &source, width, height, frames)?;
    rows.push(row(
        "virtual-geometry",
        format!("{case}, brute force"),
        "GPU brute_force (LOD 0, one instanced draw)",
        baseline_ms,
        "ms",
        &device,
    ));
    let mut speedup = row(
        "virtual-geometry",
        case,
        "GPU frame vs brute force",
        baseline_ms / frame.total_ms,
        "x",
        &device,
    );
    speedup.vs_baseline = Some(baseline_ms / frame.total_ms);
    rows.push(speedup);
    Ok(rows)
}

/// How the frame's cost grows with the scene: n³ copies of a mesh (the bunny unless
/// `meshes` names another) for n = 1, 2, 4, 8, 16, 32 (1 to 32,768 copies) at 2240×1260,
/// each framed by the lattice's camera. Per size: the frame's GPU time, the work tested
/// (hierarchy nodes and candidate clusters), the LOD cut and the triangles rasterised;
/// for one copy, the per-pass profile too (the frame's floor).
pub fn scale(quick: bool, meshes: &[PathBuf]) -> BenchResult {
    let mesh = mesh_or_bunny(meshes);
    let asset = scenes::load_asset(&mesh, 0)?;
    let sides: &[u32] = if quick {
        &[1, 2, 4]
    } else {
        &[1, 2, 4, 8, 16, 32]
    };
    let (width, height) = (2240, 1260);
    let frames = if quick { 3 } else { 30 };
    let mut rows = Vec::new();
    for &n in sides {
        let placed = scenes::lattice(SceneData::new(Default::default()), &asset, n)?;
        let case = case_label(&format!("{} copies", n * n * n), &placed, width, height);
        let m = measure(&placed, FrameSettings::new(width, height), frames)?;
        if n == 1 {
            // The floor of the frame, pass by pass: what a nearly empty scene costs.
            rows.extend(
                rows_of("vg-scale", &case, &m)
                    .into_iter()
                    .filter(|r| r.metric.contains("(timing mode passes)")),
            );
        }
        let c = &m.counts;
        let nodes = c.hierarchy.map_or(0, |h| h.nodes_tested);
        for (metric, value, unit) in [
            ("GPU frame (timing mode frame)", m.total_ms, "ms"),
            (
                "nodes + candidate clusters tested",
                (nodes + c.clusters_considered) as f64,
                "",
            ),
            ("clusters in the LOD cut", c.visible as f64, ""),
            ("triangles rasterised", c.triangles() as f64, ""),
        ] {
            rows.push(row(
                "vg-scale",
                case.clone(),
                metric,
                value,
                unit,
                &m.device,
            ));
        }
    }
    Ok(rows)
}

/// 1,048,576 copies of a mesh (the Stanford bunny unless `meshes` names another; 4,096
/// with `quick`) on the default scene's field and ground at 2560×1440: scale, where the
/// instance records alone are 224 MiB. Measured twice: the table in one binding as the
/// adapter's limits allow, and split in two bindings, the first holding wgpu's default
/// binding of 599,186 instances or half the instances, whichever is fewer. The table in
/// one binding also without occlusion and with occlusion tested every frame.
pub fn million(quick: bool, meshes: &[PathBuf]) -> BenchResult {
    let mesh = mesh_or_bunny(meshes);
    let asset = scenes::load_asset(&mesh, 0)?;
    let instances = if quick { 4096 } else { 1 << 20 };
    let adapter = meshlight::graph::GpuAdapter::select()?;
    let whole = meshlight::gpu_scene::data::Limits::for_device(&adapter.adapter.limits());
    drop(adapter);
    let default_binding = meshlight::gpu_scene::data::Limits::default().instances_per_binding;
    let split = meshlight::gpu_scene::data::Limits {
        instances_per_binding: default_binding.min(instances / 2),
        max_instances: whole.max_instances.max(instances + 1),
        ..whole
    };
    let (width, height) = (2560, 1440);
    let frames = if quick { 3 } else { 30 };
    let mut rows = Vec::new();
    for limits in [whole, split] {
        let placed = scenes::field(SceneData::new(limits), &asset, instances)?;
        let mut case = case_label(
            &format!("{instances} {} on the field", stem(&mesh)),
            &placed,
            width,
            height,
        );
        if placed.data.instances_split() {
            case += &format!(
                ", instance table split at {} instances",
                placed.data.instance_split()
            );
        }
        let settings = FrameSettings::new(width, height);
        let m = measure(&placed, settings.clone(), frames)?;
        rows.extend(rows_of("vg-million", &case, &m));
        if !placed.data.instances_split() {
            rows.extend(occlusion_rows(
                "vg-million",
                &case,
                &placed,
                &settings,
                frames,
            )?);
        }
    }
    Ok(rows)
}

/// The 15³ lattice of [`lattice`], once per rasteriser implementation and split:
/// `sw_raster` `buffer` against `texture` with every cluster in software; `hw_raster`
/// `indirect_draw` against `mesh_shader` with every cluster in hardware, and the software
/// rasteriser on the same clusters; then the whole frame (with `auto`'s choices) at each
/// split threshold and all in software. Implementations the adapter lacks are skipped
/// with a note on stderr.
pub fn rasterisers(quick: bool, meshes: &[PathBuf]) -> BenchResult {
    let Lattice {
        placed,
        width,
        height,
        frames,
        case,
        ..
    } = Lattice::new(quick, meshes)?;
    // Every rasteriser draws the whole cut: one culling pass.
    let base = FrameSettings {
        occlusion: false,
        ..FrameSettings::new(width, height)
    };
    let scenario = "rasterisers";
    let mut rows = Vec::new();
    // One measurement, or `None` where the adapter cannot run the implementation.
    let try_measure = |settings: FrameSettings,
                       what: &str|
     -> Result<Option<Measured>, Box<dyn std::error::Error>> {
        match measure(&placed, settings, frames) {
            Ok(m) => Ok(Some(m)),
            Err(e) => match e.downcast_ref::<meshlight::graph::GraphError>() {
                Some(meshlight::graph::GraphError::MissingFeature { .. }) => {
                    eprintln!("{what}: skipped, {e}");
                    Ok(None)
                }
                _ => Err(e),
            },
        }
    };

    // Every registered implementation of both stages (the registry is the one list).
    let registry = meshlight::registry();
    let implementations = |stage: &str| -> Vec<String> {
        registry
            .implementations(stage)
            .into_iter()
            .filter(|i| i != meshlight::graph::file::AUTO)
            .collect()
    };
    // Software rasteriser: every cluster to it, on each target.
    let mut software = Vec::new();
    for sw in implementations(meshlight::sw_raster::STAGE) {
        let settings = FrameSettings {
            hardware: Some(false),
            ..base.clone()
        }
        .with_implementation(meshlight::sw_raster::STAGE, &sw);
        if let Some(m) = try_measure(settings, &format!("sw_raster {sw}"))? {
            software.push((sw, m));
        }
    }
    let buffer_ms = software.first().map(|(_, m)| pass_ms(m, "sw_raster"));
    for (sw, m) in &software {
        let ms = pass_ms(m, "sw_raster");
        let mut r = row(
            scenario,
            format!("{case}, all software"),
            &format!("GPU sw_raster, {sw}"),
            ms,
            "ms",
            &m.device,
        );
        r.vs_baseline = buffer_ms.map(|b| b / ms);
        rows.push(r);
        rows.push(row(
            scenario,
            format!("{case}, all software"),
            &format!("GPU frame, sw_raster {sw}"),
            m.total_ms,
            "ms",
            &m.device,
        ));
    }

    // Hardware rasteriser: every cluster to it, each way of feeding it; the software
    // rasteriser's time on the same clusters is the baseline.
    let fastest_software = software
        .iter()
        .map(|(_, m)| pass_ms(m, "sw_raster"))
        .fold(f64::INFINITY, f64::min);
    for hw in implementations(meshlight::hw_raster::STAGE) {
        let hw = hw.as_str();
        let settings = FrameSettings {
            sw_threshold_px: Some(0.0),
            ..base.clone()
        }
        .with_implementation(meshlight::hw_raster::STAGE, hw);
        let Some(m) = try_measure(settings, &format!("hw_raster {hw}"))? else {
            continue;
        };
        let ms = pass_ms(&m, "hw_raster");
        let mut r = row(
            scenario,
            format!("{case}, all hardware"),
            &format!("GPU hw_raster, {hw}"),
            ms,
            "ms",
            &m.device,
        );
        // Above 1: the software rasteriser is that much faster on the same clusters.
        r.vs_baseline = Some(ms / fastest_software);
        rows.push(r);
        rows.push(row(
            scenario,
            format!("{case}, all hardware"),
            &format!("hw_raster {hw}, triangles"),
            m.counts.hardware_triangles as f64,
            "",
            &m.device,
        ));
    }
    if let Some((_, m)) = software.first() {
        rows.push(row(
            scenario,
            format!("{case}, all software"),
            "GPU sw_raster, fastest target (baseline of the hardware rows)",
            fastest_software,
            "ms",
            &m.device,
        ));
    }

    // The split: the whole frame with `auto`'s implementations at each threshold.
    let thresholds: &[f32] = if quick {
        &[32.0, 128.0]
    } else {
        &[8.0, 16.0, 32.0, 64.0, 128.0, 256.0]
    };
    let mut splits: Vec<(String, Measured)> = Vec::new();
    for &t in thresholds {
        let settings = FrameSettings {
            sw_threshold_px: Some(t),
            ..base.clone()
        };
        if let Some(m) = try_measure(settings, &format!("split {t} px"))? {
            splits.push((format!("sw_threshold_px = {t}"), m));
        }
    }
    let all_software = FrameSettings {
        hardware: Some(false),
        ..base.clone()
    };
    if let Some(m) = try_measure(all_software, "all software")? {
        splits.push(("all software".into(), m));
    }
    let best = splits
        .iter()
        .map(|(_, m)| m.total_ms)
        .fold(f64::INFINITY, f64::min);
    for (label, m) in &splits {
        let mut r = row(
            scenario,
            case.clone(),
            &format!("GPU frame, {label}"),
            m.total_ms,
            "ms",
            &m.device,
        );
        // 1 for the fastest split, above 1 for slower ones.
        r.vs_baseline = Some(m.total_ms / best);
        rows.push(r);
        // A split that sends every cluster to one rasteriser leaves the other out.
        for (pass, ms) in ["sw_raster", "hw_raster"]
            .into_iter()
            .filter_map(|pass| Some((pass, ran_ms(m, pass)?)))
        {
            rows.push(row(
                scenario,
                case.clone(),
                &format!("{label}: GPU {pass}"),
                ms,
                "ms",
                &m.device,
            ));
        }
        rows.push(row(
            scenario,
            case.clone(),
            &format!("{label}: hardware clusters"),
            m.counts.hardware as f64,
            "",
            &m.device,
        ));
    }
    Ok(rows)
}

/// Median GPU time of the brute-force baseline over `frames` frames: `mesh` (the source
/// of the scene's one asset) drawn whole for every instance.
pub fn brute_force(
    placed: &Placed,
    mesh: &meshlight::scene::Mesh,
    width: u32,
    height: u32,
    frames: u32,
) -> Result<f64, Box<dyn std::error::Error>> {
    use meshlight::brute_force::lod0_buffers;
    use meshlight::graph::*;
    let lod0 = lod0_buffers(mesh);
    let mut data = placed.data.clone();
    let usage = wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST;
    let index_usage = wgpu::BufferUsages::INDEX | wgpu::BufferUsages::COPY_DST;
    // The shipped pipeline file, sized for this mesh, scene and viewport.
    let mut pipeline = meshlight::graph::file::Pipeline::parse(
        include_str!("../../../pipelines/brute_force.toml"),
        "pipelines/brute_force.toml",
    )?;
    pipeline.set_params([
        ("width", width as u64),
        ("height", height as u64),
        ("vertices", lod0.positions.len() as u64),
        ("indices", lod0.indices.len() as u64),
        ("instances", data.instances.len() as u64),
    ])?;
    let g = pipeline.build(&meshlight::registry())?;
    let adapter = GpuAdapter::select()?;
    let compiled = g.compile(&CompileOptions::for_adapter(&adapter))?;
    let gpu = adapter.open(compiled.plan.enabled_features)?;
    let scene = meshlight::gpu_scene::GpuScene::new(&gpu, &mut data);
    let positions = gpu.buffer_with_data("positions", lod0.position_bytes(), usage);
    let indices = gpu.buffer_with_data("indices", lod0.index_bytes(), index_usage);
    let imports = scene
        .imports()
        .buffer("positions", &positions)
        .buffer("indices", &indices);
    let mut exec = Executor::new(gpu);
    let view = placed.camera.view([width, height], 0, None);
    let frame = FrameData::new().with("view", bytemuck::bytes_of(&view));
    exec.execute_frame(&compiled, &imports, &frame)?;
    exec.finish()?;
    exec.take_gpu_timings()?;
    for _ in 0..frames {
        exec.execute_frame(&compiled, &imports, &frame)?;
    }
    exec.finish()?;
    let times: Vec<f64> = exec
        .take_gpu_timings()?
        .iter()
        .map(|t| t.total_us / 1e3)
        .collect();
    if times.is_empty() {
        return Err("the adapter has no GPU timestamps; nothing to measure".into());
    }
    Ok(median(times))
}

/// Streaming against the same scene fully resident, in the same run: the default scene
/// at 1920×1080 and the 15³ bunnies at 2240×1260, each drawn resident and streamed
/// through a pool that holds every page (after streaming settled: the steady cost of
/// streaming itself, the walk visiting coarser levels and the cull listing pages).
pub fn stream(quick: bool, meshes: &[PathBuf]) -> BenchResult {
    // A directory of baked assets is flown through (`flight`); a mesh file is the
    // bunnies' mesh.
    let (worlds, meshes): (Vec<PathBuf>, Vec<PathBuf>) =
        meshes.iter().cloned().partition(|m| m.is_dir());
    let mut rows = Vec::new();
    for world in &worlds {
        rows.extend(flight(world, quick)?);
    }
    rows.extend(stream_resident_pool(quick, &meshes)?);
    Ok(rows)
}

/// The camera of a scripted flight over a scene's bounds at `t` in 0..1: just above the
/// highest point, along the scene in a gentle S, looking ahead and down, so the ground
/// below is drawn fine and the far scene coarse, and new ground comes into view all the
/// way.
pub fn flight_camera(lo: glam::Vec3, hi: glam::Vec3, t: f32) -> meshlight::gpu_scene::Camera {
    use glam::Vec3;
    let size = hi - lo;
    let at = |t: f32| {
        Vec3::new(
            lo.x + size.x * (0.1 + 0.8 * t),
            hi.y + 0.01 * size.x.max(size.z),
            lo.z + size.z * (0.5 + 0.3 * (std::f32::consts::TAU * t).sin()),
        )
    };
    let eye = at(t);
    let ahead = (at(t + 0.01) - eye).normalize_or(Vec3::X);
    let reach = 0.1 * size.x.max(size.z);
    meshlight::gpu_scene::Camera::perspective(
        eye,
        eye + ahead * reach - Vec3::Y * (0.35 * reach),
        60f32.to_radians(),
        1e-4 * size.x.max(size.z),
    )
}

/// Pages resident while a page they need is not: a hole in the cut. The streamer never
/// allows one (the tests check the drawn cuts); the flight counts them every frame.
fn holes(data: &SceneData) -> u64 {
    let Some(s) = data.streaming() else { return 0 };
    s.pages
        .iter()
        .filter(|p| p.resident_at.is_some())
        .filter(|p| {
            p.parents
                .iter()
                .any(|&q| s.pages[q as usize].resident_at.is_none())
        })
        .count() as u64
}

/// A scripted flight over a directory of baked assets (`meshlight generate` and `bake
/// DIR`), at 1920×1080, the same path drawn fully resident and streamed from the files
/// through a pool of an eighth of the assets' bytes, in the same run: the frames' GPU
/// time and triangles along the path (a streamed cut refines a level per round trip, so
/// while flying it lags the resident one), the cold start, the streamer's CPU on the
/// render thread and on the readers, the bytes uploaded against the budget, pages read
/// and evicted, the LOD scale from pressure and holes; then, at stops along the path,
/// the steady frame once streaming has settled against the resident frame there. The
/// streamed flight runs with one and with three levels prefetched below each request.
/// A scene too large to be resident (its payload past what one binding holds) is flown
/// streamed only, and says so.
fn flight(dir: &Path, quick: bool) -> BenchResult {
    use meshlight::gpu_scene::data::Limits;
    use meshlight::stream::Budget;
    let (width, height) = if quick { (1280, 720) } else { (1920, 1080) };
    let frames = if quick { 60 } else { 600 };
    let stops = [0.25f32, 0.5, 0.75];
    let stop_frames = if quick { 5 } else { 30 };
    let adapter = meshlight::graph::GpuAdapter::select()?;
    let limits = Limits::for_device(&adapter.adapter.limits());
    drop(adapter);
    let opened = scenes::load_library(dir, true)?;
    let asset_bytes: u64 = (opened.iter())
        .map(|(_, a)| {
            let h = a.header();
            u64::from(h.file_size[0]) | (u64::from(h.file_size[1]) << 32)
        })
        .sum();
    let (mut lo, mut hi) = (glam::Vec3::splat(f32::MAX), glam::Vec3::splat(f32::MIN));
    for (_, a) in &opened {
        lo = lo.min(glam::Vec3::from(a.header().bounds_min));
        hi = hi.max(glam::Vec3::from(a.header().bounds_max));
    }
    // An eighth of the assets, in whole 64 KiB (a small scene's: 1 MiB at least).
    let pool = ((asset_bytes / 8) & !0xffff).max(1 << 20);
    let mut streamed = scenes::library(SceneData::streamed(limits), &opened)?;
    drop(opened);
    streamed.data.reserve_pool(pool)?;
    let camera = |frame: u32| flight_camera(lo, hi, frame as f32 / frames as f32);
    let stop_camera = |t: f32| flight_camera(lo, hi, t);
    let settings = FrameSettings::new(width, height);
    let scene = format!(
        "{} assets, {:.2} GB ({})",
        streamed.data.meshes.len(),
        asset_bytes as f64 / 1e9,
        dir.file_name()
            .map_or(String::new(), |n| n.to_string_lossy().into())
    );
    let case = format!("{scene}, {width}×{height}, {frames}-frame flight");
    let mut rows = Vec::new();
    type Each<'a> = &'a mut dyn FnMut(&Renderer);
    // The path's frames in `frame` timing mode; `each` sees the renderer after each.
    let fly = |r: &mut Renderer, each: Each| -> Result<Vec<f64>, Box<dyn std::error::Error>> {
        r.executor.timing = TimingMode::Frame;
        r.executor.finish()?;
        r.executor.take_gpu_timings()?;
        for frame in 0..frames {
            r.frame(&camera(frame))?;
            each(r);
        }
        r.executor.finish()?;
        Ok((r.executor.take_gpu_timings()?.iter())
            .map(|t| t.total_us / 1e3)
            .collect())
    };
    // The median GPU frame of `stop_frames` frames at one camera.
    let hold = |r: &mut Renderer,
                camera: &meshlight::gpu_scene::Camera|
     -> Result<f64, Box<dyn std::error::Error>> {
        r.executor.finish()?;
        r.executor.take_gpu_timings()?;
        for _ in 0..stop_frames {
            r.frame(camera)?;
        }
        r.executor.finish()?;
        Ok(median(
            (r.executor.take_gpu_timings()?.iter())
                .map(|t| t.total_us / 1e3)
                .collect(),
        ))
    };
    // Per pass, the median GPU time of `stop_frames` frames at one camera in `passes`
    // timing mode: where a settled frame's time goes (the mode adds its own cost).
    let profile = |r: &mut Renderer,
                   camera: &meshlight::gpu_scene::Camera|
     -> Result<Vec<(String, f64)>, Box<dyn std::error::Error>> {
        r.executor.finish()?;
        r.executor.take_gpu_timings()?;
        r.executor.timing = TimingMode::Passes;
        for _ in 0..stop_frames {
            r.frame(camera)?;
        }
        r.executor.finish()?;
        let timings = r.executor.take_gpu_timings()?;
        r.executor.timing = TimingMode::Frame;
        let mut per_pass: Vec<(String, Vec<f64>)> = Vec::new();
        for t in &timings {
            for (name, us) in &t.passes {
                match per_pass.iter_mut().find(|(n, _)| n == name) {
                    Some((_, v)) => v.push(us / 1e3),
                    None => per_pass.push((name.clone(), vec![us / 1e3])),
                }
            }
        }
        Ok(per_pass.into_iter().map(|(n, v)| (n, median(v))).collect())
    };
    let warm = warm_up;
    let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len().max(1) as f64;
    let worst = |v: &[f64]| v.iter().copied().fold(0.0, f64::max);
    // Progress, stamped with the wall clock (to line up with a log of the GPU's clocks).
    let note = |what: &str| {
        let now = std::time::SystemTime::now()
            .duration_since(std::time::UNIX_EPOCH)
            .unwrap_or_default();
        eprintln!("vg-stream at {:.3} s: {what}", now.as_secs_f64());
    };
    let triangles = |r: &Renderer| r.latest_counts().map_or(0.0, |c| c.triangles() as f64);
    // Resident, where it fits.
    let resident = scenes::load_library(dir, false)
        .map_err(|e| e.to_string())
        .and_then(|assets| {
            scenes::library(SceneData::new(limits), &assets).map_err(|e| e.to_string())
        });
    let mut baseline = None;
    let mut stop_baselines = Vec::new();
    let mut device = String::new();
    match resident {
        Ok(placed) => {
            let mut r = Renderer::new(placed.data, settings.clone(), &GraphSource::Shipped)?;
            r.render_still(&camera(0))?;
            warm(&mut r, &camera(0))?;
            note("resident: the flight");
            let mut drawn = Vec::new();
            let times = fly(&mut r, &mut |r| drawn.push(triangles(r)))?;
            device = r.adapter.clone();
            baseline = Some(median(times.clone()));
            let case = format!("{case}, resident");
            for (metric, value, unit) in [
                (
                    "GPU frame, median over the flight",
                    median(times.clone()),
                    "ms",
                ),
                ("GPU frame, mean over the flight", mean(&times), "ms"),
                ("GPU frame, worst of the flight", worst(&times), "ms"),
                (
                    "triangles rasterised, mean over the flight",
                    mean(&drawn),
                    "",
                ),
            ] {
                rows.push(row("vg-stream", case.clone(), metric, value, unit, &device));
            }
            note("resident: the stops");
            for &t in &stops {
                warm(&mut r, &stop_camera(t))?;
                let ms = hold(&mut r, &stop_camera(t))?;
                stop_baselines.push(ms);
                let metric = format!("GPU frame at the stop {:.0} % along", t * 100.0);
                rows.push(row("vg-stream", case.clone(), &metric, ms, "ms", &device));
            }
            for (pass, ms) in profile(&mut r, &stop_camera(stops[1]))? {
                let metric = format!("GPU {pass} at the middle stop (timing mode passes)");
                rows.push(row("vg-stream", case.clone(), &metric, ms, "ms", &device));
            }
        }
        Err(why) => {
            eprintln!("{scene} cannot be drawn resident, so it is flown streamed only: {why}");
        }
    }
    // Streamed: the default budget and reader threads; two readers; 64 installs a
    // frame (the render thread's worst frame against the cold start); three levels
    // prefetched.
    let threads = std::thread::available_parallelism().map_or(4, |n| n.get().clamp(2, 8));
    let configs = [
        (Budget::default(), threads),
        (Budget::default(), 2),
        (
            Budget {
                installs_per_frame: 64,
                ..Budget::default()
            },
            threads,
        ),
        (
            Budget {
                prefetch_levels: 3,
                ..Budget::default()
            },
            threads,
        ),
    ];
    for (budget, threads) in configs {
        let (installs, prefetch_levels) = (budget.installs_per_frame, budget.prefetch_levels);
        let mut r = Renderer::new(
            streamed.data.clone(),
            settings.clone(),
            &GraphSource::Shipped,
        )?;
        r.start_streaming(streamed.sources.clone(), budget, threads)?;
        note(&format!(
            "streamed, {installs} installs, {prefetch_levels} level(s): cold start"
        ));
        let cold = r.settle_streaming(&camera(0), 600)?;
        warm(&mut r, &camera(0))?;
        if device.is_empty() {
            device = r.adapter.clone();
        }
        let mut per_frame = Vec::new();
        let mut drawn = Vec::new();
        let mut hole_count = 0;
        let start = r.streaming.as_ref().map(|s| s.stats()).unwrap_or_default();
        note("streamed: the flight");
        let times = fly(&mut r, &mut |r| {
            per_frame.push(r.streaming.as_ref().map(|s| s.stats()).unwrap_or_default());
            drawn.push(triangles(r));
            hole_count += holes(&r.data);
        })?;
        let last = per_frame.last().copied().unwrap_or_default();
        let ms = |d: std::time::Duration| d.as_secs_f64() * 1e3;
        let render_thread: Vec<f64> = per_frame.iter().map(|s| ms(s.cpu)).collect();
        let readers: Vec<f64> = per_frame.iter().map(|s| ms(s.readers)).collect();
        let uploaded: Vec<f64> = (per_frame.iter())
            .map(|s| s.frame.bytes_uploaded as f64 / (1u64 << 20) as f64)
            .collect();
        let scales: Vec<f64> = (per_frame.iter())
            .map(|s| f64::from(s.frame.lod_scale))
            .collect();
        let streamed_case = format!(
            "{case}, streamed ({:.1} MiB pool, {threads} readers, {installs} installs a frame, {prefetch_levels} level(s) prefetched)",
            pool as f64 / (1u64 << 20) as f64
        );
        let mut stream_rows = Vec::new();
        let mut push = |metric: &str, value: f64, unit: &str| {
            stream_rows.push(row(
                "vg-stream",
                streamed_case.clone(),
                metric,
                value,
                unit,
                &device,
            ));
        };
        push(
            "GPU frame, median over the flight",
            median(times.clone()),
            "ms",
        );
        push("GPU frame, mean over the flight", mean(&times), "ms");
        push("GPU frame, worst of the flight", worst(&times), "ms");
        push(
            "triangles rasterised, mean over the flight",
            mean(&drawn),
            "",
        );
        push(
            "assets per pool byte",
            asset_bytes as f64 / pool as f64,
            "×",
        );
        push(
            "frames to settle from an empty pool (cold start)",
            f64::from(cold),
            "",
        );
        push(
            "streamer CPU on the render thread, worst frame",
            worst(&render_thread),
            "ms",
        );
        push(
            "streamer CPU on the render thread, mean",
            mean(&render_thread),
            "ms",
        );
        push(
            "streamer CPU on the readers, worst frame",
            worst(&readers),
            "ms",
        );
        push("streamer CPU on the readers, mean", mean(&readers), "ms");
        // Where the time goes: each step's mean and worst frame.
        let steps = |s: &meshlight_virtual_geometry::streaming::StreamStats| {
            let r = s.reader_steps;
            let readers = [
                ("readers: read", r.read),
                ("readers: checksum", r.checksum),
                ("readers: check", r.check),
            ];
            (s.phases.named().into_iter())
                .map(|(name, d)| (format!("render thread: {name}"), d))
                .chain(readers.into_iter().map(|(n, d)| (n.to_string(), d)))
                .collect::<Vec<_>>()
        };
        for (i, (name, _)) in steps(&last).iter().enumerate() {
            let each: Vec<f64> = per_frame.iter().map(|s| ms(steps(s)[i].1)).collect();
            push(&format!("streamer CPU, {name}, mean"), mean(&each), "ms");
            push(
                &format!("streamer CPU, {name}, worst frame"),
                worst(&each),
                "ms",
            );
        }
        let busiest = (0..per_frame.len())
            .max_by(|&a, &b| per_frame[a].cpu.cmp(&per_frame[b].cpu))
            .map(|i| per_frame[i]);
        if let Some(b) = busiest {
            push(
                "the render thread's worst frame: pages installed",
                f64::from(b.frame.installed),
                "",
            );
            push(
                "the render thread's worst frame: pages evicted",
                f64::from(b.frame.evicted),
                "",
            );
            push(
                "the render thread's worst frame: pages listed by the GPU",
                f64::from(b.listed),
                "",
            );
        }
        let listed: Vec<f64> = per_frame.iter().map(|s| f64::from(s.listed)).collect();
        push("pages listed by the GPU a frame, mean", mean(&listed), "");
        push(
            "uploaded, worst frame (budget 32 MiB)",
            worst(&uploaded),
            "MiB",
        );
        push("uploaded, mean a frame", mean(&uploaded), "MiB");
        push(
            "pages read in the flight",
            (last.loaded_total - start.loaded_total) as f64,
            "",
        );
        push(
            "pages evicted in the flight",
            (last.evicted_total - start.evicted_total) as f64,
            "",
        );
        push("pages refused", last.failed_total as f64, "");
        push(
            "pool used at the end",
            last.frame.pool_used as f64 / (1u64 << 20) as f64,
            "MiB",
        );
        push("LOD scale from pressure, largest", worst(&scales), "×");
        push("LOD scale from pressure, mean", mean(&scales), "×");
        push(
            "holes (resident pages missing a parent, all frames)",
            hole_count as f64,
            "",
        );
        let mut at_stops = Vec::new();
        note("streamed: the stops");
        for &t in &stops {
            let settled = r.settle_streaming(&stop_camera(t), 600)?;
            warm(&mut r, &stop_camera(t))?;
            at_stops.push((t, settled, hold(&mut r, &stop_camera(t))?));
        }
        let passes = profile(&mut r, &stop_camera(stops[1]))?;
        note("streamed: done");
        for &(t, settled, frame_ms) in &at_stops {
            let at = format!("{:.0} % along", t * 100.0);
            push(
                &format!("frames to settle at the stop {at}"),
                f64::from(settled),
                "",
            );
            push(&format!("GPU frame at the stop {at}"), frame_ms, "ms");
        }
        for (pass, ms) in passes {
            push(
                &format!("GPU {pass} at the middle stop (timing mode passes)"),
                ms,
                "ms",
            );
        }
        for (i, &(_, _, frame_ms)) in at_stops.iter().enumerate() {
            let Some(&b) = stop_baselines.get(i) else {
                continue;
            };
            let metric = format!("GPU frame at the stop {:.0} % along", stops[i] * 100.0);
            if let Some(r) = stream_rows.iter_mut().find(|r| r.metric == metric) {
                r.vs_baseline = Some(frame_ms / b);
            }
        }
        if let Some(b) = baseline {
            for r in &mut stream_rows {
                if r.metric.starts_with("GPU frame, median") {
                    r.vs_baseline = Some(r.value / b);
                }
            }
        }
        rows.extend(stream_rows);
    }
    note("cold reads");
    rows.extend(cold_reads(&streamed, &case, &device)?);
    Ok(rows)
}

/// Pages read by the loader's threads from the files with the OS's cache of them dropped
/// first, plainly and with read-ahead advice (the streamer's reads when the world is not
/// in memory), against the same reads from the cache: the same spread sample of pages
/// each time, each mode twice, alternating.
fn cold_reads(streamed: &Placed, case: &str, device: &str) -> BenchResult {
    use meshlight::stream::loader::{Loader, ReadJob};
    use meshlight_virtual_geometry::streaming::PageSource;
    use std::time::{Duration, Instant};
    let Some(s) = streamed.data.streaming() else {
        return Ok(Vec::new());
    };
    let files: Vec<_> = (streamed.sources.iter())
        .filter_map(|source| match source {
            PageSource::File { file, .. } => Some(std::sync::Arc::clone(file)),
            PageSource::Memory(_) => None,
        })
        .collect();
    if files.len() != streamed.sources.len() || s.pages.is_empty() {
        return Ok(Vec::new());
    }
    const SAMPLE: usize = 4096;
    let step = s.pages.len().div_ceil(SAMPLE).max(1);
    let jobs: Vec<ReadJob> = (s.pages.iter().enumerate().step_by(step))
        .map(|(i, p)| ReadJob {
            page: i as u32,
            file: std::sync::Arc::clone(&files[p.mesh as usize]),
            offset: p.file_offset,
            bytes: u64::from(p.words) * 4,
            checksum: Some(p.checksum),
            check: None,
        })
        .collect();
    let bytes: u64 = jobs.iter().map(|j| j.bytes).sum();
    let threads = std::thread::available_parallelism().map_or(4, |n| n.get().clamp(2, 8));
    let mut rows = Vec::new();
    let mut times: BTreeMap<&str, Vec<f64>> = BTreeMap::new();
    for (mode, cold, ahead) in [
        ("from the OS's cache", false, false),
        ("cold", true, false),
        ("cold, with read-ahead", true, true),
        ("cold", true, false),
        ("cold, with read-ahead", true, true),
    ] {
        if cold {
            for file in &files {
                if let Err(e) = file.forget_cached() {
                    eprintln!(
                        "the OS's cache of {} cannot be dropped ({e}): no cold reads",
                        file.path().display()
                    );
                    return Ok(rows);
                }
            }
        }
        let loader = Loader::with_read_ahead(threads, ahead)?;
        let start = Instant::now();
        loader.submit_all(jobs.iter().cloned());
        for _ in 0..jobs.len() {
            if let Some((page, Err(e))) = loader.wait(Duration::from_secs(60)) {
                return Err(format!("page {page}: {e}").into());
            }
        }
        times
            .entry(mode)
            .or_default()
            .push(start.elapsed().as_secs_f64());
    }
    let case = format!(
        "{case}, {} pages ({:.1} MiB) read by {threads} threads",
        jobs.len(),
        bytes as f64 / (1u64 << 20) as f64
    );
    let baseline = times.get("cold").map(|t| median(t.clone()));
    for (mode, t) in times {
        let seconds = median(t);
        let mut r = row(
            "vg-stream",
            case.clone(),
            &format!("page reads, {mode}"),
            jobs.len() as f64 / seconds,
            "pages/s",
            device,
        );
        if mode == "cold, with read-ahead" {
            r.vs_baseline = baseline.map(|b| b / seconds);
        }
        rows.push(r);
        rows.push(row(
            "vg-stream",
            case.clone(),
            &format!("page bytes read, {mode}"),
            bytes as f64 / seconds / (1u64 << 20) as f64,
            "MiB/s",
            device,
        ));
    }
    Ok(rows)
}

/// Streaming against the same scene fully resident, every page in the pool (see
/// [`stream`]).
fn stream_resident_pool(quick: bool, meshes: &[PathBuf]) -> BenchResult {
    use meshlight::stream::Budget;
    let (segments, instances) = if quick {
        (64, 64)
    } else {
        (
            meshlight::scene::DEFAULT_SEGMENTS,
            scenes::DEFAULT_INSTANCES,
        )
    };
    let procedural = scenes::load_asset(Path::new("procedural"), segments)?;
    let bunny_mesh = mesh_or_bunny(meshes);
    let bunny = scenes::load_asset(&bunny_mesh, 0)?;
    let n = if quick { 5 } else { 15 };
    let frames = if quick { 5 } else { 50 };
    type Make<'a> =
        Box<dyn Fn(SceneData) -> Result<Placed, meshlight::gpu_scene::SceneDataError> + 'a>;
    let scenes: [(String, Make, (u32, u32)); 2] = [
        (
            format!("{instances} procedural meshes"),
            Box::new(|data| scenes::field(data, &procedural, instances)),
            (1920, 1080),
        ),
        (
            format!("{n}³ {}", stem(&bunny_mesh)),
            Box::new(|data| scenes::lattice(data, &bunny, n)),
            if quick { (1280, 720) } else { (2240, 1260) },
        ),
    ];
    let mut rows = Vec::new();
    for (scene, make, (width, height)) in scenes {
        let resident = make(SceneData::new(Default::default()))?;
        let mut streamed = make(SceneData::streamed(Default::default()))?;
        let pages: u64 = (streamed
            .data
            .streaming()
            .expect("a streamed scene")
            .pages
            .iter())
        .map(|p| u64::from(p.words) * 4)
        .sum();
        // Every page fits, with the allocator's rounding.
        let pool = pages + pages / 8 + (1 << 20);
        streamed.data.reserve_pool(pool)?;
        let case = case_label(&scene, &resident, width, height);
        let settings = FrameSettings::new(width, height);
        let m = measure(&resident, settings.clone(), frames)?;
        let baseline = m.total_ms;
        rows.extend(rows_of("vg-stream", &format!("{case}, resident"), &m));
        let camera = streamed.camera;
        // Cold start without reading each requested page's children along with it.
        let settled_alone = {
            let mut r = Renderer::new(
                streamed.data.clone(),
                settings.clone(),
                &GraphSource::Shipped,
            )?;
            let budget = Budget {
                prefetch_levels: 0,
                ..Budget::default()
            };
            r.start_streaming(streamed.sources.clone(), budget, 4)?;
            r.settle_streaming(&camera, 600)?
        };
        let sources = streamed.sources.clone();
        let mut settled = 0;
        let m = measure_prepared(&streamed, settings, frames, |r| {
            r.start_streaming(sources, Budget::default(), 4)?;
            settled = r.settle_streaming(&camera, 600)?;
            Ok(())
        })?;
        let streamed_case = format!("{case}, streamed (every page in a {} MiB pool)", pool >> 20);
        let mut streamed_rows = rows_of("vg-stream", &streamed_case, &m);
        for r in &mut streamed_rows {
            if r.metric == "GPU frame (timing mode frame)" {
                r.vs_baseline = Some(r.value / baseline);
            }
        }
        rows.extend(streamed_rows);
        let s = m.stream.unwrap_or_default();
        for (metric, value, unit) in [
            (
                "frames to settle from an empty pool",
                f64::from(settled),
                "",
            ),
            (
                "frames to settle from an empty pool, children not prefetched",
                f64::from(settled_alone),
                "",
            ),
            (
                "pool used",
                s.frame.pool_used as f64 / (1u64 << 20) as f64,
                "MiB",
            ),
            ("pages resident", f64::from(s.frame.resident_pages), ""),
            ("streamer CPU, last frame", s.cpu.as_secs_f64() * 1e3, "ms"),
        ] {
            rows.push(row(
                "vg-stream",
                streamed_case.clone(),
                metric,
                value,
                unit,
                &m.device,
            ));
        }
    }
    Ok(rows)
}

/// The LOD thresholds `lod-quality` compares, in pixels.
const LOD_THRESHOLDS: [f32; 5] = [0.25, 0.5, 1.0, 2.0, 4.0];

/// The LOD's quality (`lod-quality`), measured rather than assumed: per LOD threshold, the
/// triangles rasterised per pixel, the frame, and the shaded and normal images against
/// the same frame at threshold 0 (every cluster at LOD 0, through the same passes, so
/// that only the LOD differs): SSIM and PSNR of the shaded image, SSIM of the normals.
/// The default scene at 1920×1080 and the 15³ bunnies at 2240×1260 (with `quick`, thresholds 1
/// and 4 of the small scenes).
pub fn lod_quality(quick: bool, meshes: &[PathBuf]) -> BenchResult {
    let (field, instances) = default_field(quick)?;
    let (width, height) = if quick { (1280, 720) } else { (1920, 1080) };
    let field_case = case_label(
        &format!("{instances} procedural meshes"),
        &field,
        width,
        height,
    );
    let lattice = Lattice::new(quick, meshes)?;
    let thresholds: &[f32] = if quick { &[1.0, 4.0] } else { &LOD_THRESHOLDS };
    let mut rows = Vec::new();
    for (placed, case, width, height, frames) in [
        (&field, field_case, width, height, lattice.frames),
        (
            &lattice.placed,
            lattice.case.clone(),
            lattice.width,
            lattice.height,
            lattice.frames,
        ),
    ] {
        let at = |lod: f32, view| FrameSettings {
            lod_threshold_px: Some(lod),
            view,
            ..FrameSettings::new(width, height)
        };
        let normal = Some(meshlight::resolve::DebugView::Normal);
        // One renderer (one device, the scene uploaded once), its frame rebuilt for each
        // threshold and view.
        let mut r = Renderer::new(placed.data.clone(), at(1.0, None), &GraphSource::Shipped)?;
        let still =
            |r: &mut Renderer, settings: FrameSettings| -> Result<_, Box<dyn std::error::Error>> {
                r.rebuild(&GraphSource::Shipped, settings, &|_, _| Ok(()))?;
                let still = r.render_still(&placed.camera)?;
                if still.counts.overflowed() {
                    return Err(
                        format!("{case}: the lists still overflow; no image to compare").into(),
                    );
                }
                Ok(still)
            };
        // Coarsest first, LOD 0 last: the lists only grow, so each threshold is timed
        // with the lists it needs rather than LOD 0's.
        let mut drawn = Vec::new();
        for &lod in thresholds.iter().rev().chain(std::iter::once(&0.0)) {
            let normals = still(&mut r, at(lod, normal))?;
            let shaded = still(&mut r, at(lod, None))?;
            // The frame as `measure` times it, at the shaded view just built; fewer frames
            // at threshold 0, where LOD 0 of a whole scene is slow to draw.
            let frames = if lod == 0.0 { frames.min(5) } else { frames };
            warm_up(&mut r, &placed.camera)?;
            let times: Vec<f64> = timed_frames(&mut r, &placed.camera, frames, TimingMode::Frame)?
                .iter()
                .map(|t| t.total_us / 1e3)
                .collect();
            // The counters of a frame like the timed ones (with history to test
            // occlusion against; the still's first frame after a rebuild has none).
            let counts = r.render_still(&placed.camera)?.counts;
            drawn.push((lod, shaded, normals, median(times), counts));
        }
        drawn.reverse();
        let (shaded0, normals0) = (&drawn[0].1.rgba, &drawn[0].2.rgba);
        let mut table = format!(
            "{case}\n  threshold  tris/px  frame ms  SSIM shaded  PSNR shaded  SSIM normals\n"
        );
        for (lod, shaded, normals, frame_ms, counts) in &drawn {
            let per_pixel = counts.triangles_per_pixel(width, height);
            let (w, h) = (width as usize, height as usize);
            let ssim_shaded = crate::image_metric::ssim(&shaded.rgba, shaded0, w, h);
            let psnr_shaded = crate::image_metric::psnr(&shaded.rgba, shaded0);
            let ssim_normals = crate::image_metric::ssim(&normals.rgba, normals0, w, h);
            table += &format!(
                "  {lod:9}  {per_pixel:7.2}  {frame_ms:8.3}  {ssim_shaded:11.4}  {psnr_shaded:11.2}  {ssim_normals:12.4}\n"
            );
            let case = format!("{case}, LOD threshold {lod} px");
            for (metric, value, unit) in [
                ("triangles rasterised per pixel", per_pixel, ""),
                ("GPU frame (timing mode frame)", *frame_ms, "ms"),
                ("SSIM of the shaded image against LOD 0", ssim_shaded, ""),
                ("PSNR of the shaded image against LOD 0", psnr_shaded, "dB"),
                ("SSIM of the normal view against LOD 0", ssim_normals, ""),
            ] {
                rows.push(row(
                    "lod-quality",
                    case.clone(),
                    metric,
                    value,
                    unit,
                    &r.adapter,
                ));
            }
        }
        println!("{table}");
    }
    Ok(rows)
}
