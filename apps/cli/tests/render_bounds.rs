//! The bounds `meshlight render --help` and `meshlight info` print hold: a number at a
//! bound passes the up-front check and the frame built for it fits wgpu's default limits
//! (the frame compiled without a device, and on lavapipe the renderer set up), and one
//! past it is refused before anything is baked or an adapter asked for, with an error
//! naming the flag and the limit that binds.

mod common;

use common::{meshlight, scratch};
use meshlight::gpu_scene::SceneData;
use meshlight::gpu_scene::data::Limits;
use meshlight::graph::{AdapterClass, CompileOptions, GraphError};
use meshlight::scene::{BuildOptions, MeshletAsset, build_asset, procedural_mesh};
use meshlight_cli::render_bounds::{
    self, MAX_RESIDENT_SEGMENTS, OutOfRange, RenderNumbers, max_instances, max_lights, max_pixels,
    max_side,
};
use meshlight_testing::features::lavapipe;
use meshlight_virtual_geometry::frame_graph::frame;
use meshlight_virtual_geometry::setup::clustering_for;
use meshlight_virtual_geometry::{FrameSettings, GraphSource, Renderer, SceneOptions, scenes};
use std::path::Path;

/// The bound numbers, with the limits they are derived from written out: each changes
/// only with the formats or wgpu's defaults, and then the printed ranges change too.
#[test]
fn the_bounds_are_the_limits_they_name() {
    assert_eq!(max_lights(), 1 << 20, "128 bytes of froxel entries a light");
    assert_eq!(
        max_instances(),
        1_198_371,
        "two 128 MiB bindings of 224 bytes, less one"
    );
    assert_eq!(max_pixels(), 1 << 24, "one 128 MiB binding of u64s");
    assert_eq!(max_side(), 8192);
    assert_eq!(MAX_RESIDENT_SEGMENTS, 745);
    assert_eq!(render_bounds::segments(true), 3..=1024);
}

/// Sets the numbers of one case.
type Set = fn(&mut RenderNumbers, u64);

/// For each flag: its printed maximum passes, one more is refused naming the flag, the
/// value, the range and the limit that binds it.
#[test]
fn each_flag_passes_at_its_maximum_and_is_refused_one_past_it() {
    let cases: [(&str, bool, u64, Set, &str); 7] = [
        (
            "segments",
            false,
            MAX_RESIDENT_SEGMENTS,
            |n, v| n.segments = v as u32,
            "payload binding of 33554428 words",
        ),
        (
            "segments",
            true,
            1024,
            |n, v| n.segments = v as u32,
            "`bake`'s range",
        ),
        (
            "instances",
            false,
            max_instances(),
            |n, v| n.instances = v as u32,
            "two storage bindings of 134217728 bytes",
        ),
        (
            "lights",
            false,
            max_lights(),
            |n, v| n.lights = v as u32,
            "froxel entry list (`cluster_objects`)",
        ),
        // One side at the most, the other small: each side's own bound.
        (
            "width",
            false,
            max_side(),
            |n, v| {
                n.width = v as u32;
                n.height = 1
            },
            "max_texture_dimension_2d",
        ),
        (
            "height",
            false,
            max_side(),
            |n, v| {
                n.height = v as u32;
                n.width = 1
            },
            "max_texture_dimension_2d",
        ),
        // The widest image at the pixel bound: 8192 × 2048; one more row is past it.
        (
            "width × height",
            false,
            max_pixels() / max_side(),
            |n, v| {
                n.width = max_side() as u32;
                n.height = v as u32
            },
            "visibility buffer holds 8 bytes a pixel",
        ),
    ];
    for (flag, streamed, max, set, limit) in cases {
        let mut n = RenderNumbers {
            streamed,
            ..RenderNumbers::default()
        };
        set(&mut n, max);
        assert_eq!(n.check(), Ok(()), "{flag} at {max}: {n:?}");
        set(&mut n, max + 1);
        let e: OutOfRange = n.check().unwrap_err();
        let text = e.to_string();
        assert_eq!(e.flags.join(" × "), flag, "{text}");
        assert!(text.contains(limit), "{text}");
        assert!(text.contains(&format!("..={}", e.max)), "{text}");
        match flag {
            "width × height" => {
                assert_eq!(e.requested, max_pixels() + max_side(), "{text}");
                assert!(
                    text.starts_with(&format!("--width {} --height {}", max_side(), max + 1)),
                    "{text}"
                );
            }
            _ => {
                assert_eq!((e.requested, e.max), (max + 1, max), "{text}");
                assert!(text.starts_with(&format!("--{flag} {}", max + 1)), "{text}");
            }
        }
    }
    // A square image at the pixel bound passes; one more column does not.
    let side = max_pixels().isqrt() as u32;
    let square = RenderNumbers {
        width: side,
        height: side,
        ..RenderNumbers::default()
    };
    assert_eq!(square.check(), Ok(()));
    let wider = RenderNumbers {
        width: side + 1,
        ..square
    };
    assert_eq!(wider.check().unwrap_err().flags, &["width", "height"]);
}

/// A small asset: the procedural mesh at 6 segments.
fn small_asset() -> MeshletAsset {
    build_asset(&procedural_mesh(6), &BuildOptions::default(), &mut |_| {})
        .unwrap()
        .asset
}

/// The frame the renderer builds for `data` and `settings`, compiled for lavapipe's
/// features (where the visibility target is a buffer) and wgpu's default limits: the
/// plan checks every buffer bound against the binding limit and every dispatch.
fn compile(data: &SceneData, settings: &FrameSettings) -> Result<(), GraphError> {
    let options = CompileOptions::new(lavapipe()).with_class(AdapterClass::Cpu);
    frame(&GraphSource::Shipped, data, settings)?
        .graph
        .compile(&options)
        .map(|_| ())
}

/// The name of the resource an error says is over a limit, and the limit.
fn over(e: GraphError) -> (String, &'static str) {
    match e {
        GraphError::LimitExceeded { what, limit, .. } => (what, limit),
        other => panic!("not a limit: {other}"),
    }
}

/// The light bound is where the frame's clustering stops fitting: at it the frame (its
/// lists sized by the setup's own [`clustering_for`]) compiles, one light more and the
/// froxel entries are past the binding.
#[test]
fn lights_at_the_bound_fit_the_frame_and_one_more_does_not() {
    let placed = scenes::field(SceneData::new(Limits::default()), &small_asset(), 2).unwrap();
    let lit = |lights: u64| FrameSettings {
        clustering: Some(clustering_for([64, 64], lights)),
        ..FrameSettings::new(64, 64)
    };
    compile(&placed.data, &lit(max_lights())).unwrap_or_else(|e| panic!("{e}"));
    let (what, limit) = over(compile(&placed.data, &lit(max_lights() + 1)).unwrap_err());
    assert!(what.contains("cluster_objects"), "{what}");
    assert_eq!(limit, "max_storage_buffer_binding_size");
}

/// The pixel bound is where the visibility buffer stops fitting one binding: the frame
/// at 8192 × 2048 and at 4096 × 4096 compiles, one more row is past the binding.
#[test]
fn pixels_at_the_bound_fit_the_frame_and_one_more_row_does_not() {
    let placed = scenes::field(SceneData::new(Limits::default()), &small_asset(), 2).unwrap();
    let sized = |width: u64, height: u64| {
        let (w, h) = (width as u32, height as u32);
        FrameSettings {
            clustering: Some(clustering_for([w, h], scenes::DEFAULT_LIGHTS.into())),
            ..FrameSettings::new(w, h)
        }
    };
    let side = max_pixels().isqrt();
    for (w, h) in [(max_side(), max_pixels() / max_side()), (side, side)] {
        compile(&placed.data, &sized(w, h)).unwrap_or_else(|e| panic!("{w} × {h}: {e}"));
    }
    let taller = sized(max_side(), max_pixels() / max_side() + 1);
    let (what, limit) = over(compile(&placed.data, &taller).unwrap_err());
    assert!(what.contains("visbuffer"), "{what}");
    assert_eq!(limit, "max_storage_buffer_binding_size");
}

/// The instance bound is what the field places with its ground in a scene sized for
/// wgpu's default limits, and the frame over that scene (its instances over two
/// bindings) compiles; one copy more and the scene refuses the ground.
#[test]
fn instances_at_the_bound_fit_the_scene_and_the_frame_and_one_more_does_not() {
    let asset = small_asset();
    let copies = u32::try_from(max_instances()).unwrap();
    let placed = scenes::field(SceneData::new(Limits::default()), &asset, copies)
        .unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(placed.data.instances.len() as u64, max_instances() + 1);
    assert!(placed.data.instances_split());
    compile(&placed.data, &FrameSettings::new(64, 64)).unwrap_or_else(|e| panic!("{e}"));
    drop(placed);
    let e = scenes::field(SceneData::new(Limits::default()), &asset, copies + 1)
        .err()
        .expect("one copy past the bound is refused");
    assert!(e.to_string().contains("instances"), "{e}");
}

/// On the device (lavapipe, whose binding limit is wgpu's default): the renderer is set
/// up for the most lights, and refuses one more naming the froxel entries. A frame of a
/// million lights takes minutes on a CPU adapter, so none is drawn.
#[test]
fn the_renderer_sets_up_the_most_lights_on_the_device() {
    let renderer = |lights: u64| {
        let options = SceneOptions {
            segments: 3,
            instances: 2,
            lights: Some(u32::try_from(lights).unwrap()),
            ..SceneOptions::new(16, 16)
        };
        let s = meshlight_virtual_geometry::setup(&options).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(s.lights.len() as u64, lights);
        Renderer::new(s.data, s.settings, &s.source)
    };
    let at = renderer(max_lights()).unwrap_or_else(|e| panic!("{} lights: {e}", max_lights()));
    let device = at
        .executor
        .gpu
        .device
        .limits()
        .max_storage_buffer_binding_size;
    drop(at);
    if device != wgpu::Limits::default().max_storage_buffer_binding_size {
        eprintln!("this device binds {device} bytes, not the default: one more light fits");
        return;
    }
    let past = renderer(max_lights() + 1)
        .err()
        .expect("one light more is refused");
    let (what, limit) = over(past);
    assert!(what.contains("cluster_objects"), "{what}");
    assert_eq!(limit, "max_storage_buffer_binding_size");
}

/// `render --help` and `info` print the bounds the check uses, line for line.
#[test]
fn help_and_info_print_the_checked_bounds() {
    let help = String::from_utf8_lossy(&meshlight(&["render", "--help"]).stdout).into_owned();
    let out = meshlight(&["info"]);
    let info = String::from_utf8_lossy(&out.stdout).into_owned();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    for line in render_bounds::lines() {
        assert!(help.contains(&line), "{line}\nnot in:\n{help}");
        assert!(info.contains(&line), "{line}\nnot in:\n{info}");
    }
    for bound in render_bounds::bounds(false) {
        let range = format!("{}..={}", bound.range.start(), bound.range.end());
        assert!(help.contains(&format!("{} ", bound.name())), "{help}");
        assert!(help.contains(&range), "{range}: {help}");
    }
}

/// One past each bound, the binary refuses the number before baking (the cache stays
/// empty) or asking for an adapter (one that cannot exist is named, which would end
/// with exit code 3); at the bounds it goes on to ask for the adapter.
#[test]
fn the_binary_refuses_past_the_bounds_before_any_work() {
    let dir = scratch("bounds-binary");
    let cache = dir.join("cache");
    let run_as = |command: &str, args: &[&str]| {
        let mut cmd = common::command(&[&[command][..], args].concat());
        cmd.env("MESHLIGHT_CACHE_DIR", &cache)
            .env("MESHLIGHT_ADAPTER", "no adapter is called this");
        let out = cmd.output().expect("runs");
        (
            out.status.code(),
            String::from_utf8_lossy(&out.stderr).into_owned(),
        )
    };
    let run = |args: &[&str]| run_as("render", args);
    let side = max_side().to_string();
    let one_past = |max: u64| (max + 1).to_string();
    let lights = one_past(max_lights());
    let instances = one_past(max_instances());
    let segments = one_past(MAX_RESIDENT_SEGMENTS);
    let rows = one_past(max_pixels() / max_side());
    let cases: [(&[&str], String); 5] = [
        (
            &["--lights", &lights],
            format!("--lights {lights} is outside 0..={}", max_lights()),
        ),
        (
            &["--instances", &instances],
            format!("--instances {instances} is outside 0..={}", max_instances()),
        ),
        (
            &["--segments", &segments],
            format!("--segments {segments} is outside 3..={MAX_RESIDENT_SEGMENTS}"),
        ),
        (
            &["--segments", "1025", "--pool-mb", "64"],
            "--segments 1025 is outside 3..=1024".into(),
        ),
        (
            &["--width", &side, "--height", &rows],
            format!(
                "--width {side} --height {rows} ({} pixels) is outside 1..={}",
                max_pixels() + max_side(),
                max_pixels()
            ),
        ),
    ];
    // `view` shares the flags and refuses the same, before a window or an adapter.
    for command in ["render", "view"] {
        for (args, expected) in &cases {
            let (code, err) = run_as(command, args);
            assert_eq!(code, Some(1), "{command} {args:?}: {err}");
            assert!(err.contains(expected.as_str()), "{command} {args:?}: {err}");
            assert!(!cache.exists(), "{command} {args:?} baked before refusing");
        }
    }
    // At the bounds (a tiny mesh, so the bake before the adapter is quick).
    let lights = max_lights().to_string();
    let instances = max_instances().to_string();
    let rows = (max_pixels() / max_side()).to_string();
    let square = max_pixels().isqrt().to_string();
    let small = ["--segments", "3", "--width", "8", "--height", "8"];
    let at: [&[&str]; 4] = [
        &[&small[..], &["--lights", &lights]].concat(),
        &[&small[..], &["--instances", &instances]].concat(),
        &["--segments", "3", "--width", &side, "--height", &rows],
        &["--segments", "3", "--width", &square, "--height", &square],
    ];
    for args in at {
        let (code, err) = run(args);
        assert_eq!(code, Some(3), "{args:?}: {err}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// The resident segment bound is where the procedural mesh and the field's largest
/// ground stop fitting the scene's payload binding with wgpu's default limits: at
/// [`MAX_RESIDENT_SEGMENTS`] the field places, with the ground of several copy counts,
/// and one segment more it cannot place the ground of the default scene. Bakes two
/// meshes of 8.9 M triangles (under a minute each in a release build).
#[test]
#[ignore = "bakes two meshes of 8.9 M triangles: run with `cargo test --release -p meshlight-cli --test render_bounds -- --ignored`"]
fn the_segment_bound_is_where_the_mesh_and_the_ground_stop_fitting() {
    let procedural = Path::new("procedural");
    let at = scenes::open_asset(procedural, MAX_RESIDENT_SEGMENTS as u32, false).unwrap();
    let limits = Limits::default();
    for copies in [1, scenes::DEFAULT_INSTANCES, 16_384, max_instances() as u32] {
        let placed = scenes::field(SceneData::new(limits), &at, copies)
            .unwrap_or_else(|e| panic!("{copies} copies: {e}"));
        let words = placed.data.payload.len();
        let left = limits.max_payload_words as usize - words;
        eprintln!("{copies} copies: {words} payload words, {left} left");
    }
    drop(at);
    let past = scenes::open_asset(procedural, MAX_RESIDENT_SEGMENTS as u32 + 1, false).unwrap();
    let e = scenes::field(SceneData::new(limits), &past, scenes::DEFAULT_INSTANCES)
        .err()
        .expect("one segment more does not fit beside the ground");
    assert!(e.to_string().contains("payload words"), "{e}");
}
