//! The sun's shadow through the shipped frame (lavapipe):
//!
//! - spheres over a plane under a known sun: every plane pixel the analytic shadow
//!   puts clearly inside a sphere's shadow is dark in the `shadow` view, every pixel
//!   clearly outside it is lit, in both cascades and on both sides of the seam between
//!   them (a sphere's shadow straddles it);
//! - each cascade's depth map equals the reference: the CPU cull's cut for the cascade's
//!   view, rasterised by the software rasteriser's reference;
//! - without shadows the frame is the unshadowed one (the goldens of
//!   `virtual_geometry.rs` hold it to the images from before the shadow stage); with
//!   them, the shaded image only darkens.

mod common;

use glam::{Mat4, Vec2, Vec3};
use meshlight::cull_lod::Thresholds;
use meshlight::gpu_scene::cascades::CascadeSettings;
use meshlight::gpu_scene::{Camera, Material, SceneData};
use meshlight::resolve::DebugView;
use meshlight::resolve::shadows::{CASCADE_COLORS, SHADOW_MAPS};
use meshlight::scene::terrain::Terrain;
use meshlight::scene::{BuildOptions, Mesh, MeshletAsset, build_asset};
use meshlight::shaders::cpu::layout::Cluster;
use meshlight_virtual_geometry::shadows::{ShadowFrame, ShadowWalk};
use meshlight_virtual_geometry::{FrameSettings, GraphSource, Renderer, ShadowSettings};
use std::sync::OnceLock;

const W: u32 = 320;
const H: u32 = 180;
const RADIUS: f32 = 1.0;
/// Sphere centres: their shadows fall in the first cascade, across the seam, and in the
/// second (see `camera` and `shadow_settings`).
const SPHERES: [Vec3; 4] = [
    Vec3::new(-1.5, 1.5, 5.0),
    Vec3::new(0.5, 1.5, 1.3),
    Vec3::new(-1.0, 1.5, -3.0),
    Vec3::new(1.5, 1.5, -8.0),
];

fn toward_sun() -> Vec3 {
    // From the right: shadows fall to the left of the spheres, where the camera sees them.
    Vec3::new(0.9, 1.0, -0.1).normalize()
}

fn camera() -> Camera {
    Camera::perspective(
        Vec3::new(0.0, 6.0, 8.0),
        Vec3::new(0.0, 0.0, -6.0),
        1.0,
        0.1,
    )
}

/// Two 512² cascades to 30 units, split halfway to logarithmic: the split falls at a
/// view depth of about 8.4, across the second sphere's shadow.
fn shadow_settings() -> ShadowSettings {
    ShadowSettings {
        cascades: CascadeSettings {
            count: 2,
            resolution: 512,
            distance: 30.0,
            split_lambda: 0.5,
            caster_reach: 10.0,
            ..CascadeSettings::default()
        },
        ..ShadowSettings::default()
    }
}

/// A UV sphere of radius [`RADIUS`], 48 segments around and 24 down.
fn sphere_asset() -> &'static MeshletAsset {
    static ASSET: OnceLock<MeshletAsset> = OnceLock::new();
    ASSET.get_or_init(|| {
        let (around, down) = (48u32, 24u32);
        let mut positions = Vec::new();
        for j in 0..=down {
            let theta = std::f32::consts::PI * j as f32 / down as f32;
            for i in 0..around {
                let phi = std::f32::consts::TAU * i as f32 / around as f32;
                positions.push(Vec3::new(
                    theta.sin() * phi.cos(),
                    theta.cos(),
                    -theta.sin() * phi.sin(),
                ));
            }
        }
        let at = |i: u32, j: u32| j * around + i % around;
        let mut indices = Vec::new();
        for j in 0..down {
            for i in 0..around {
                let (a, b, c, d) = (at(i, j), at(i + 1, j), at(i, j + 1), at(i + 1, j + 1));
                if j > 0 {
                    indices.extend([a, c, b]);
                }
                if j + 1 < down {
                    indices.extend([b, c, d]);
                }
            }
        }
        let mesh = Mesh {
            source: "sphere".into(),
            normals: positions.clone(),
            positions: positions.iter().map(|p| *p * RADIUS).collect(),
            uvs: Vec::new(),
            colors: Vec::new(),
            indices,
            materials: Vec::new(),
        };
        build_asset(&mesh, &BuildOptions::default(), &mut |_| {})
            .unwrap()
            .asset
    })
}

/// A flat 40 × 40 square on the x–z plane at y = 0, facing +y.
fn plane_asset() -> &'static MeshletAsset {
    static ASSET: OnceLock<MeshletAsset> = OnceLock::new();
    ASSET.get_or_init(|| {
        let terrain = Terrain {
            origin: Vec2::new(-20.0, -32.0),
            size: 40.0,
            cells: 64,
            amplitude: 0.0,
            wavelength: 4.0,
            octaves: 1,
            seed: 3,
            uv_scale: 1.0,
            calm_centre: Vec2::ZERO,
            calm_radius: 0.0,
        };
        build_asset(
            &terrain.mesh().unwrap(),
            &BuildOptions::default(),
            &mut |_| {},
        )
        .unwrap()
        .asset
    })
}

fn scene() -> SceneData {
    let mut data = SceneData::new(meshlight::gpu_scene::data::Limits::default());
    let material = data
        .add_material(Material {
            base_color: [0.8; 3],
            checker: false,
            ..Material::default()
        })
        .unwrap();
    let plane = data.add_mesh("plane", plane_asset()).unwrap();
    let sphere = data.add_mesh("sphere", sphere_asset()).unwrap();
    data.add_instance(plane, Mat4::IDENTITY, material).unwrap();
    for c in SPHERES {
        data.add_instance(sphere, Mat4::from_translation(c), material)
            .unwrap();
    }
    data
}

fn renderer(shadows: Option<ShadowSettings>, view: DebugView) -> Renderer {
    renderer_with(shadows, view, true, None)
}

/// With `hierarchy` off, every view lists its candidates with the flat fill.
/// With `hardware`, every cluster to the software rasteriser (`Some(false)`) or the
/// adapter class's split (`None`).
fn renderer_with(
    shadows: Option<ShadowSettings>,
    view: DebugView,
    hierarchy: bool,
    hardware: Option<bool>,
) -> Renderer {
    let settings = FrameSettings {
        shadows,
        sun_direction: Some(toward_sun()),
        keep_visibility: true,
        hierarchy,
        hardware,
        ..FrameSettings::new(W, H).with_view(view)
    };
    Renderer::new(scene(), settings, &GraphSource::Shipped).unwrap_or_else(|e| panic!("{e}"))
}

/// The camera's ray through pixel `(x, y)`'s centre: origin and unit direction.
fn pixel_ray(x: u32, y: u32) -> (Vec3, Vec3) {
    let cam = camera();
    let view = cam.view([W, H], 0, None);
    let inverse = Mat4::from_cols_array_2d(&view.inverse_view_projection);
    let ndc = Vec2::new(
        (x as f32 + 0.5) / W as f32 * 2.0 - 1.0,
        1.0 - (y as f32 + 0.5) / H as f32 * 2.0,
    );
    let far = inverse.project_point3(ndc.extend(0.5));
    (cam.position, (far - cam.position).normalize())
}

/// How far the line from `p` towards the sun passes from the nearest sphere's centre,
/// minus the radius: negative inside a shadow.
fn shadow_margin(p: Vec3) -> f32 {
    let l = toward_sun();
    SPHERES
        .iter()
        .map(|&c| {
            let to = c - p;
            let along = to.dot(l);
            if along <= 0.0 {
                return f32::INFINITY;
            }
            (to - l * along).length() - RADIUS
        })
        .fold(f32::INFINITY, f32::min)
}

#[test]
fn spheres_over_a_plane_cast_the_analytic_shadow_in_both_cascades_and_across_the_seam() {
    let shadows = shadow_settings();
    let mut r = renderer(Some(shadows), DebugView::Shadow);
    let still = r.render_still(&camera()).unwrap_or_else(|e| panic!("{e}"));
    let frame = ShadowFrame::new(&camera(), [W, H], toward_sun(), &shadows, 0, 1.0).unwrap();
    let split = frame.cascades[0].far;
    assert!((7.5..9.5).contains(&split), "split at {split}");
    let forward = (camera().target - camera().position).normalize();
    // (shadowed, lit) pixels checked per cascade, and shadowed ones within a unit of the
    // seam on each side.
    let mut checked = [[0usize; 2]; 2];
    let mut seam = [0usize; 2];
    let mut wrong = Vec::new();
    for y in 0..H {
        for x in 0..W {
            let (origin, dir) = pixel_ray(x, y);
            // Pixels showing (or grazing) a sphere are left out.
            let grazes = SPHERES.iter().any(|&c| {
                let to = c - origin;
                (to - dir * to.dot(dir)).length() < RADIUS + 0.05
            });
            if grazes || dir.y >= -1e-3 {
                continue;
            }
            let p = origin + dir * (-origin.y / dir.y);
            if !(-19.0..19.0).contains(&p.x) || !(-31.0..7.0).contains(&p.z) {
                continue;
            }
            let depth = (p - origin).dot(forward);
            let k = usize::from(depth > split);
            if depth > shadows.cascades.distance || (depth - split).abs() < 0.02 {
                continue;
            }
            // The filter reaches 2 texels from the receiver, the offsets one more, and
            // the sphere's facets and LOD a few hundredths of a unit.
            let band = 3.0 * frame.cascades[k].texel_size + 0.03;
            let margin = shadow_margin(p);
            let want_shadow = if margin < -band {
                true
            } else if margin > band {
                false
            } else {
                continue;
            };
            let px = &still.rgba[((y * W + x) * 4) as usize..][..3];
            // The view: the cascade's colour times 0.3 + 0.7 · factor; its brightest
            // channel tells the factor.
            let tint = CASCADE_COLORS[k];
            let channel = if tint.x >= tint.y { 0 } else { 1 };
            let factor = ((px[channel] as f32 / 255.0) / tint[channel] - 0.3) / 0.7;
            let ok = if want_shadow {
                factor < 0.15
            } else {
                factor > 0.85
            };
            if !ok {
                if wrong.len() < 6 {
                    eprintln!("({x}, {y}) depth {depth} split {split} k {k} rgb {px:?} p {p}");
                }
                wrong.push((x, y, k, want_shadow, factor, margin));
            }
            checked[k][usize::from(!want_shadow)] += 1;
            if want_shadow && (depth - split).abs() < 1.0 {
                seam[k] += 1;
            }
        }
    }
    eprintln!("checked (shadowed, lit) per cascade: {checked:?}; shadowed at the seam: {seam:?}");
    assert!(
        wrong.is_empty(),
        "{} of the pixels disagree with the analytic shadow, e.g. {:?}",
        wrong.len(),
        &wrong[..wrong.len().min(8)]
    );
    for k in 0..2 {
        assert!(checked[k][0] > 150 && checked[k][1] > 1000, "{checked:?}");
        assert!(seam[k] > 15, "shadowed pixels at the seam: {seam:?}");
    }
}

#[test]
fn each_cascades_depth_map_is_the_references_cut_rasterised() {
    let shadows = shadow_settings();
    // Every cluster in software: the software rasteriser's reference, bit for bit.
    for hierarchy in [true, false] {
        let mut r = renderer_with(Some(shadows), DebugView::Shaded, hierarchy, Some(false));
        r.render_still(&camera()).unwrap_or_else(|e| panic!("{e}"));
        check_maps(&mut r, &camera(), &shadows, hierarchy, 0.0);
    }
    // A walk per cascade instead of one for both: the same maps.
    let per_view = ShadowSettings {
        walk: ShadowWalk::PerView,
        ..shadows
    };
    let mut r = renderer_with(Some(per_view), DebugView::Shaded, true, Some(false));
    assert!(
        r.pipeline
            .passes
            .iter()
            .any(|p| p.name == "shadow_fill_{view}"),
        "the walk was not split per cascade"
    );
    r.render_still(&camera()).unwrap_or_else(|e| panic!("{e}"));
    check_maps(&mut r, &camera(), &per_view, true, 0.0);
    // The adapter class's split (lavapipe: the casters crossing a cascade's near plane
    // in hardware): the hardware rasteriser interpolates depth in floats, within 1e-5
    // of the reference (its own test's tolerance on lavapipe).
    let mut r = renderer_with(Some(shadows), DebugView::Shaded, true, None);
    r.render_still(&camera()).unwrap_or_else(|e| panic!("{e}"));
    check_maps(&mut r, &camera(), &shadows, true, 1e-5);
}

/// The camera's first walk serving the cascades too (one walk for every view, the
/// default) against the file's passes as written (the cascades' own walk): the same
/// maps, and the camera's list (then in the shadow stage's buffers) the same, so the same
/// image and counters; with a LOD bias (applied through the cascades' views) too, and
/// with four cascades, the most one walk serves besides the camera.
#[test]
fn the_cameras_walk_serving_the_cascades_draws_the_same_maps_and_image() {
    let shadows = shadow_settings();
    assert_eq!(shadows.walk, ShadowWalk::WithCamera, "the default walk");
    let mut drawn_in_two = Vec::new();
    for (cascades, lod_bias) in [(2, 0.0), (2, 1.0), (4, 0.5)] {
        let mut with_camera = ShadowSettings {
            lod_bias,
            ..shadows
        };
        with_camera.cascades.count = cascades;
        let as_written = ShadowSettings {
            walk: ShadowWalk::AsWritten,
            ..with_camera
        };
        let mut r = renderer_with(Some(with_camera), DebugView::Shaded, true, Some(false));
        let fills: Vec<_> = r
            .pipeline
            .passes
            .iter()
            .filter(|p| p.stage == meshlight::fill_clusters::STAGE)
            .map(|p| {
                (
                    p.name.clone(),
                    p.param("views").and_then(|v| v.as_integer()),
                )
            })
            .collect();
        assert_eq!(
            fills,
            [
                ("fill".to_string(), Some(i64::from(cascades) + 1)),
                ("fill_second".to_string(), None)
            ],
            "the camera's walk serves the cascades and itself; no other first walk"
        );
        let got = r.render_still(&camera()).unwrap_or_else(|e| panic!("{e}"));
        let mut plain = renderer_with(Some(as_written), DebugView::Shaded, true, Some(false));
        let want = plain.render_still(&camera()).unwrap();
        let maps = |r: &mut Renderer| {
            let buffer = r
                .shadow_maps()
                .expect("the renderer keeps the maps")
                .clone();
            r.executor
                .gpu
                .read_buffer(&buffer, 0, buffer.size())
                .unwrap()
        };
        let case = format!("{cascades} cascades, LOD bias {lod_bias}");
        assert!(maps(&mut r) == maps(&mut plain), "{case}: the maps differ");
        let counts = |c: &meshlight_virtual_geometry::FrameCounts| {
            (
                c.clusters_requested,
                c.clusters_considered,
                c.visible,
                c.software,
            )
        };
        assert_eq!(
            counts(&got.counts),
            counts(&want.counts),
            "{case}: the camera's counters"
        );
        assert!(
            got.counts.clusters_considered > 0,
            "{case}: the camera listed nothing"
        );
        assert!(got.rgba == want.rgba, "{case}: the image differs");
        let drawn = |r: &Renderer| {
            let mut c: Vec<_> = r
                .shadow_counts
                .iter()
                .map(|c| (c.cascade, c.drawn))
                .collect();
            c.sort();
            c
        };
        assert_eq!(drawn(&r), drawn(&plain), "{case}: the cascades' counters");
        if cascades == 2 {
            drawn_in_two.push(drawn(&r).iter().map(|c| c.1).sum::<u32>());
        }
        if cascades == 2 && lod_bias == 0.0 {
            check_maps(&mut r, &camera(), &with_camera, true, 0.0);
        }
    }
    assert!(
        drawn_in_two[1] < drawn_in_two[0],
        "a LOD bias of 1 drew no fewer clusters into the maps: {drawn_in_two:?}"
    );
}

/// The renderer's maps against the reference's, cascade by cascade: every depth within
/// `tolerance`, nothing drawn where the reference draws nothing.
fn check_maps(
    r: &mut Renderer,
    camera: &Camera,
    shadows: &ShadowSettings,
    hierarchy: bool,
    tolerance: f32,
) {
    let buffer = r
        .shadow_maps()
        .expect("the renderer keeps the maps")
        .clone();
    let maps: Vec<u32> = bytemuck::pod_collect_to_vec(
        &r.executor
            .gpu
            .read_buffer(&buffer, 0, buffer.size())
            .unwrap(),
    );
    let frame = ShadowFrame::new(camera, [W, H], toward_sun(), shadows, 0, 1.0).unwrap();
    let side = shadows.cascades.resolution;
    let layer = (side * side) as usize;
    let thresholds = Thresholds {
        lod_threshold_px: 1.0,
        hardware: false,
        ..Thresholds::default()
    };
    let data = &r.data;
    for (k, cascade) in frame.cascades.iter().enumerate() {
        let mut cut = Vec::new();
        for (i, instance) in data.instances.iter().enumerate() {
            for m in instance.first_meshlet..instance.first_meshlet + instance.meshlet_count {
                let cluster = Cluster {
                    instance: i as u32,
                    meshlet: m,
                };
                let d =
                    meshlight::cull_lod::cpu::classify(data, &cascade.view, cluster, &thresholds);
                if d.in_frustum && d.in_cut {
                    cut.push(cluster);
                }
            }
        }
        let want: Vec<u32> =
            meshlight::sw_raster::cpu::rasterize(data, &cascade.view, &cut, side, side)
                .iter()
                .map(|&v| (v >> 32) as u32)
                .collect();
        let got = &maps[k * layer..(k + 1) * layer];
        let drawn = want.iter().filter(|&&d| d != 0).count();
        // Most of the map holds the plane (the box reaches an eighth past its slice).
        assert!(
            drawn > layer / 6,
            "cascade {k}: the reference covers only {drawn} texels"
        );
        let differ = got
            .iter()
            .zip(&want)
            .filter(|(g, w)| {
                let (g, w) = (f32::from_bits(**g), f32::from_bits(**w));
                (g == 0.0) != (w == 0.0) || (g - w).abs() > tolerance
            })
            .count();
        assert_eq!(
            differ, 0,
            "cascade {k} (walk: {hierarchy}): {differ} of {layer} depths differ from the reference"
        );
        // The cascade's counters came back: its cut, all drawn in software.
        let counts = r
            .shadow_counts
            .iter()
            .find(|c| c.cascade == k as u32)
            .copied();
        let counts = counts.unwrap_or_else(|| panic!("cascade {k}'s counters did not come back"));
        assert_eq!(counts.drawn as usize, cut.len(), "cascade {k}: {counts:?}");
    }
}

#[test]
fn shadows_only_darken_the_shaded_image_and_without_them_the_stage_is_gone() {
    let mut plain = renderer(None, DebugView::Shaded);
    assert!(
        !plain
            .pipeline
            .passes
            .iter()
            .any(|p| p.name.starts_with("shadow_")),
        "the shadow stage stayed without shadows"
    );
    assert!(plain.pipeline.resource(SHADOW_MAPS).is_none());
    let unshadowed = plain.render_still(&camera()).unwrap().rgba;
    let mut shadowed = renderer(Some(shadow_settings()), DebugView::Shaded);
    let image = shadowed.render_still(&camera()).unwrap().rgba;
    let mut darker = 0;
    for (a, b) in image.chunks(4).zip(unshadowed.chunks(4)) {
        for c in 0..3 {
            assert!(
                a[c] <= b[c].saturating_add(1),
                "a pixel got brighter: {a:?} over {b:?}"
            );
        }
        darker += usize::from(u32::from(a[0]) + 10 < u32::from(b[0]));
    }
    assert!(darker > 1000, "only {darker} pixels are in shadow");
}

/// A cascade whose view and scene did not change is not drawn again, and the image is the
/// same; moving an instance or the camera draws the cascades again.
#[test]
fn unchanged_cascades_keep_their_maps_and_a_change_draws_them_again() {
    let shadows = shadow_settings();
    let mut r = renderer(Some(shadows), DebugView::Shaded);
    let first = r.render_still(&camera()).unwrap().rgba;
    assert_eq!(r.cascades_drawn, 2, "the first frame draws every cascade");
    let again = r.render_still(&camera()).unwrap().rgba;
    assert_eq!(
        r.cascades_drawn, 0,
        "a still of an unchanged view drew cascades again"
    );
    assert!(first == again, "the kept maps shade differently");
    // A sphere moved: every cascade is drawn again, and the shadow follows it.
    let moved = Mat4::from_translation(SPHERES[1] + Vec3::new(0.0, 0.0, -2.0));
    r.set_transform(meshlight::gpu_scene::data::InstanceId(2), moved)
        .unwrap();
    let after = r.render_still(&camera()).unwrap().rgba;
    assert!(after != again, "the image did not change with the sphere");
    let mut fresh = renderer(Some(shadows), DebugView::Shaded);
    fresh
        .set_transform(meshlight::gpu_scene::data::InstanceId(2), moved)
        .unwrap();
    let want = fresh.render_still(&camera()).unwrap().rgba;
    assert!(after == want, "the kept maps missed the move");
    // The camera moved: a cascade is drawn again exactly when its view changed. Held
    // boxes (the default) keep their views over a small move; boxes fitted to their
    // slices (hold 0) move with the camera.
    let views = |camera: &Camera, s: &ShadowSettings| -> Vec<Vec<u8>> {
        let frame = ShadowFrame::new(camera, [W, H], toward_sun(), s, 0, 1.0).unwrap();
        frame
            .cascades
            .iter()
            .map(|c| bytemuck::bytes_of(&c.view).to_vec())
            .collect()
    };
    let mut drawn = Vec::new();
    for (hold, step) in [
        (shadows.cascades.hold, 0.05),
        (shadows.cascades.hold, 3.0),
        (0.0, 0.05),
    ] {
        let mut held = shadows;
        held.cascades.hold = hold;
        let mut r = renderer(Some(held), DebugView::Shaded);
        r.render_still(&camera()).unwrap();
        let mut moved = camera();
        moved.position.x += step;
        moved.target.x += step;
        r.frame(&moved).unwrap();
        let changed = views(&camera(), &held)
            .iter()
            .zip(views(&moved, &held))
            .filter(|(a, b)| **a != *b)
            .count() as u32;
        assert_eq!(r.cascades_drawn, changed, "hold {hold}, a move of {step}");
        drawn.push(changed);
    }
    // A small move keeps both held cascades; a move of 3 draws the near one, whose grid
    // step is shorter, but not the far one; fitted boxes draw both.
    let frame = ShadowFrame::new(&camera(), [W, H], toward_sun(), &shadows, 0, 1.0).unwrap();
    let hold = shadows.cascades.hold;
    let steps: Vec<f32> = frame
        .cascades
        .iter()
        .map(|c| c.texel_size * shadows.cascades.resolution as f32 * hold / (1.0 + hold))
        .collect();
    assert!(steps[0] < 3.0 && steps[1] > 3.0, "grid steps {steps:?}");
    assert_eq!(drawn, [0, 1, 2], "cascades drawn after each move");
    let camera = {
        let mut c = camera();
        c.position.x += 0.5;
        c
    };
    // Without the cache every frame draws them all.
    let mut uncached = renderer(
        Some(ShadowSettings {
            cache: false,
            ..shadows
        }),
        DebugView::Shaded,
    );
    uncached.render_still(&camera).unwrap();
    uncached.frame(&camera).unwrap();
    assert_eq!(uncached.cascades_drawn, 2);
}

/// What a caller who asks for nothing gets: four cascades where the pipeline has the
/// stage (none where it has not, none for 0), maps as wide as the viewport's longer side
/// within 256..=2048, and shadows as far as the median instance spans 8 pixels.
#[test]
fn the_defaults_follow_the_pipeline_the_viewport_and_the_scene() {
    use meshlight_virtual_geometry::setup::{ShadowRequest, default_resolution};
    use meshlight_virtual_geometry::shadows::{SHADOWED_PIXELS, scene_reach, shadow_distance};
    assert_eq!(default_resolution([1280, 720]), 1280);
    assert_eq!(default_resolution([96, 64]), 256);
    assert_eq!(default_resolution([3840, 2160]), 2048);
    assert_eq!(default_resolution([1001, 10]), 1008);
    let data = scene();
    let ask = ShadowRequest::default();
    let s = ask.settings(&data, &camera(), [W, H], true).unwrap();
    assert_eq!((s.cascades.count, s.cascades.resolution), (4, 320));
    assert!(ask.settings(&data, &camera(), [W, H], false).is_none());
    assert!(
        ShadowRequest::off()
            .settings(&data, &camera(), [W, H], true)
            .is_none()
    );
    // Four spheres and the plane: the median bounding radius is a sphere's, which spans
    // 2 · r · H / 2 · cot(fov / 2) / d pixels at distance d; here that is past the
    // plane's far side, where the scene ends.
    let r = data.meshes[1].bounding_sphere[3];
    let pixels_at_one = 0.5 * H as f32 / (0.5f32).tan();
    let eight_pixels = 2.0 * r * pixels_at_one / SHADOWED_PIXELS;
    let reach = scene_reach(&data, camera().position);
    assert!(eight_pixels > reach, "{eight_pixels} {reach}");
    let got = shadow_distance(&data, &camera(), [W, H]);
    assert_eq!(got, reach);
    // 36 pixels high, the spheres reach 8 pixels before the scene ends.
    let small = shadow_distance(&data, &camera(), [W / 5, H / 5]);
    let want = eight_pixels / 5.0;
    assert!((small - want).abs() < 1e-3 * want, "{small} against {want}");
    assert_eq!(s.cascades.distance, got);
    // A number out of range is refused before any work, by name.
    let bad = ShadowRequest {
        resolution: Some(100),
        ..ShadowRequest::default()
    };
    let e = bad.check([W, H]).unwrap_err().to_string();
    assert!(
        e.contains("resolution = 100") && e.contains("multiple of 8"),
        "{e}"
    );
}

/// The one-pass frame (`pipelines/virtual_geometry_one_pass.toml`, occlusion off) carries
/// the same shadow stage: its maps equal the two-pass frame's.
#[test]
fn the_one_pass_frame_draws_the_same_shadow_maps() {
    let maps = |occlusion: bool| {
        let settings = FrameSettings {
            shadows: Some(shadow_settings()),
            sun_direction: Some(toward_sun()),
            occlusion,
            ..FrameSettings::new(W, H)
        };
        let mut r = Renderer::new(scene(), settings, &GraphSource::Shipped)
            .unwrap_or_else(|e| panic!("{e}"));
        r.render_still(&camera()).unwrap_or_else(|e| panic!("{e}"));
        let buffer = r
            .shadow_maps()
            .expect("the renderer keeps the maps")
            .clone();
        let bytes = r
            .executor
            .gpu
            .read_buffer(&buffer, 0, buffer.size())
            .unwrap();
        bytemuck::pod_collect_to_vec::<u8, u32>(&bytes)
    };
    let two_pass = maps(true);
    assert!(two_pass.iter().filter(|&&d| d != 0).count() > two_pass.len() / 4);
    assert!(maps(false) == two_pass, "the one-pass frame's maps differ");
}
