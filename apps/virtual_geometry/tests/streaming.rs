//! The whole frame on a streamed scene (lavapipe in CI): pages asked for by the cull,
//! read back, streamed and installed until the view's cut is resident, and then the
//! image of the fully resident scene; a pool smaller than what the view wants coarsens
//! the cut instead of thrashing; a damaged page is refused and drawn at its parent's
//! level.

mod common;

use std::sync::Arc;

use common::asset;
use meshlight::cull_lod::cpu::lod_test;
use meshlight::glam::Vec3;
use meshlight::gpu_scene::data::Limits;
use meshlight::gpu_scene::{Camera, SceneData};
use meshlight::scene::MeshletAsset;
use meshlight::scene::asset::format::{NO_GROUP, SECTION_PAYLOAD};
use meshlight::shaders::cpu::layout::{Cluster, View};
use meshlight::shaders::cpu::rng::Rng;
use meshlight::stream::cut::check;
use meshlight::stream::{Budget, MeshDag};
use meshlight_virtual_geometry::scenes::{self, Placed};
use meshlight_virtual_geometry::streaming::PageSource;
use meshlight_virtual_geometry::{FrameSettings, GraphSource, Renderer, Still};

const W: u32 = 192;
const H: u32 = 108;

/// The field of copies, resident or streamed through a pool of `pool` bytes.
fn field(pool: Option<u64>) -> Placed {
    let data = match pool {
        Some(_) => SceneData::streamed(Limits::default()),
        None => SceneData::new(Limits::default()),
    };
    let mut placed = scenes::field(data, asset(), 9).unwrap();
    if let Some(bytes) = pool {
        placed.data.reserve_pool(bytes).unwrap();
    }
    placed
}

fn all_pages() -> u64 {
    // The ground's pages too: the field's last mesh.
    2 * asset().bytes().len() as u64 + (4 << 20)
}

fn differing(a: &[u8], b: &[u8], tolerance: u8) -> usize {
    a.chunks(4)
        .zip(b.chunks(4))
        .filter(|(p, q)| p.iter().zip(*q).any(|(x, y)| x.abs_diff(*y) > tolerance))
        .count()
}

/// Renders frames of the same view until the streamer has nothing pending for
/// `settle` frames in a row (at most `limit` frames), then a still.
fn settle(r: &mut Renderer, placed: &Placed, limit: u32) -> (Still, u32) {
    let mut quiet = 0;
    for frame in 1..=limit {
        r.frame(&placed.camera).unwrap();
        let s = r.streaming.as_ref().unwrap().stats();
        let busy = s.frame.requested > 0 || s.frame.in_flight > 0 || s.frame.installed > 0;
        quiet = if busy { 0 } else { quiet + 1 };
        if quiet == 6 {
            return (r.render_still(&placed.camera).unwrap(), frame);
        }
    }
    panic!(
        "still streaming after {limit} frames: {:?}",
        r.streaming.as_ref().unwrap().stats()
    );
}

fn sources(placed: &Placed) -> Vec<PageSource> {
    // The field holds the copies' mesh, then the ground's; both from memory here.
    let radius = placed.data.meshes[0].bounding_sphere[3].max(1e-6);
    let ground = scenes::ground_asset(&scenes::field_ground(radius, 9)).unwrap();
    vec![
        PageSource::Memory(Arc::new(asset().clone())),
        PageSource::Memory(Arc::new(ground)),
    ]
}

#[test]
fn a_streamed_scene_settles_on_the_resident_image() {
    let resident = field(None);
    let mut r = Renderer::new(
        resident.data.clone(),
        FrameSettings::new(W, H),
        &GraphSource::Shipped,
    )
    .unwrap();
    let want = r.render_still(&resident.camera).unwrap();

    let streamed = field(Some(all_pages()));
    let mut r = Renderer::new(
        streamed.data.clone(),
        FrameSettings::new(W, H),
        &GraphSource::Shipped,
    )
    .unwrap();
    // Frames are refused until the renderer knows where pages come from.
    let err = r.frame(&streamed.camera).unwrap_err().to_string();
    assert!(err.contains("start_streaming"), "{err}");
    r.start_streaming(sources(&streamed), Budget::default(), 2)
        .unwrap();
    let (got, frames) = settle(&mut r, &streamed, 200);
    let stats = r.streaming.as_ref().unwrap().stats();
    eprintln!("settled after {frames} frames: {stats:?}");
    assert!(stats.loaded_total > 10, "{stats:?}");
    assert_eq!(stats.frame.lod_scale, 1.0);
    let diff = differing(&got.rgba, &want.rgba, 2);
    eprintln!("{diff} pixels differ by more than 2/255 from the resident image");
    assert!(diff * 200 <= (W * H) as usize, "{diff} pixels differ");
    assert_eq!(
        got.counts.software + got.counts.hardware,
        want.counts.software + want.counts.hardware
    );
}

/// The meshes of the field, in the order it adds them: the copies' and the ground's.
fn field_assets(placed: &Placed) -> Vec<Arc<MeshletAsset>> {
    let radius = placed.data.meshes[0].bounding_sphere[3].max(1e-6);
    let ground = scenes::ground_asset(&scenes::field_ground(radius, 9)).unwrap();
    vec![Arc::new(asset().clone()), Arc::new(ground)]
}

/// Checks that the scene as the last frame drew it encodes, for every instance, a
/// complete cut over the resident pages: the renderer's LOD test on the rewritten records
/// (`cull_lod::cpu::lod_test`, which the GPU's is tested against) draws, on every path
/// from a LOD-0 meshlet up to a root, exactly one meshlet, and only meshlets of resident
/// pages. Returns how many meshlets of pages (not roots) the cuts drew.
fn check_complete_cuts(r: &Renderer, dags: &[MeshDag], view: &View) -> usize {
    let data = &r.data;
    let pages = &data.streaming().unwrap().pages;
    let mut paged = 0;
    for (i, instance) in data.instances.iter().enumerate() {
        let mesh = instance.mesh as usize;
        let first = data.meshes[mesh].first_meshlet as usize;
        let dag = &dags[mesh];
        let group_base = data.meshlets[first..]
            .iter()
            .zip(&dag.parent)
            .find(|&(_, &p)| p != NO_GROUP)
            .map_or(0, |(m, &p)| m.parent_group - p);
        let drawn: Vec<bool> = (0..dag.meshlet_count())
            .map(|k| {
                let cluster = Cluster {
                    instance: i as u32,
                    meshlet: (first + k) as u32,
                };
                lod_test(data, view, cluster, 1.0).0
            })
            .collect();
        let resident = |g: u32| pages[(group_base + g) as usize].resident_at.is_some();
        if let Err(hole) = check(dag, &drawn, resident) {
            panic!("instance {i}: {hole}");
        }
        paged += drawn
            .iter()
            .zip(&dag.parent)
            .filter(|&(&d, &p)| d && p != NO_GROUP)
            .count();
    }
    paged
}

/// A camera somewhere over the field, looking at a point on it.
fn wander(placed: &Placed, rng: &mut Rng) -> Camera {
    let radius = placed.data.meshes[0].bounding_sphere[3];
    let extent = 3.0 * 2.6 * radius;
    let target = Vec3::new(rng.range(0.0, extent), 0.0, rng.range(0.0, extent));
    let eye = target
        + Vec3::new(
            rng.range(-1.0, 1.0),
            rng.range(0.2, 1.0),
            rng.range(-1.0, 1.0),
        )
        .normalize()
            * radius
            * rng.range(0.5, 12.0);
    Camera::perspective(eye, target, 55f32.to_radians(), radius * 0.05)
}

/// Frames from random cameras over the field through a pool of a sixth of its pages:
/// after every frame, every instance's cut over what is resident is complete, pages
/// are evicted and read again, and the pressure coarsens the cut when the view wants
/// more than the pool.
#[test]
fn a_flight_through_a_small_pool_never_shows_a_hole() {
    let full = field(Some(all_pages()));
    let total: u64 = full
        .data
        .streaming()
        .unwrap()
        .pages
        .iter()
        .map(|p| u64::from(p.words) * 4)
        .sum();
    let placed = field(Some(total / 6));
    let assets = field_assets(&placed);
    let dags: Vec<MeshDag> = assets.iter().map(|a| MeshDag::of_asset(a)).collect();
    let mut r = Renderer::new(
        placed.data.clone(),
        FrameSettings::new(W, H),
        &GraphSource::Shipped,
    )
    .unwrap();
    let sources = assets
        .iter()
        .map(|a| PageSource::Memory(Arc::clone(a)))
        .collect();
    r.start_streaming(sources, Budget::default(), 2).unwrap();
    let mut rng = Rng(77);
    let mut camera = wander(&placed, &mut rng);
    let (mut paged, mut max_scale) = (0, 1.0f32);
    for frame in 0..120u32 {
        if frame % 6 == 0 {
            camera = wander(&placed, &mut rng);
        }
        r.frame(&camera).unwrap();
        let s = r.streaming.as_ref().unwrap();
        let mut view = camera.view([W, H], frame, None);
        view.lod_scale /= s.lod_scale();
        max_scale = max_scale.max(s.lod_scale());
        paged += check_complete_cuts(&r, &dags, &view);
    }
    let stats = r.streaming.as_ref().unwrap().stats();
    eprintln!("{stats:?}, largest LOD scale {max_scale}, {paged} paged meshlets drawn");
    assert!(stats.evicted_total > 0, "nothing evicted: {stats:?}");
    assert!(paged > 1000, "the cuts drew {paged} meshlets of pages");
}

/// A page whose bytes on disk fail its checksum, or pass it (resealed, as a hostile
/// writer would) but fail the checks of its contents, is refused, named, never
/// installed, and neither is anything that needs it; the frames go on drawing complete
/// cuts. The asset is opened for streaming: only its resident part is read up front.
#[test]
fn a_damaged_page_is_refused_and_its_group_drawn_coarser() {
    let assets = field_assets(&field(None));
    let dags: Vec<MeshDag> = assets.iter().map(|a| MeshDag::of_asset(a)).collect();
    let dir = std::env::temp_dir().join(format!("meshlight-stream-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    // The coarsest page of the copies' mesh is damaged on disk.
    let graph = dags[0].pages();
    let damaged = (0..graph.len() as u32)
        .find(|&p| graph.parents(p).is_empty())
        .unwrap();
    let payload = asset().header().sections[SECTION_PAYLOAD].offset as usize;
    let range = asset().pages()[damaged as usize].range();
    let first = payload + range.start;
    // One byte flipped: the page's checksum refuses it.
    let mut flipped: Vec<u32> = bytemuck::cast_slice(asset().bytes()).to_vec();
    flipped[first] ^= 0x4000_0000;
    // The first bit flip whose page the content checks refuse, the checksums resealed.
    let mut resealed: Vec<u32> = bytemuck::cast_slice(asset().bytes()).to_vec();
    let bit = (0..range.len() * 32)
        .find(|&b| {
            let mut page = asset().payload()[range.clone()].to_vec();
            page[b / 32] ^= 1 << (b % 32);
            asset().check_page(damaged as usize, &page).is_err()
        })
        .expect("a flip the page checks refuse");
    resealed[first + bit / 32] ^= 1 << (bit % 32);
    meshlight::scene::asset::checksum::seal(&mut resealed);
    for (name, words, says) in [
        ("copies.mlasset", flipped, "fails its checksum"),
        ("resealed.mlasset", resealed, "is corrupt"),
    ] {
        let path = dir.join(name);
        std::fs::write(&path, bytemuck::cast_slice::<u32, u8>(&words)).unwrap();
        // The scene holds the file's resident part, as `render --pool-mb` does.
        let opened = Arc::new(MeshletAsset::open_resident(&path).unwrap());
        let mut placed = scenes::field(SceneData::streamed(Limits::default()), &opened, 9).unwrap();
        placed.data.reserve_pool(all_pages()).unwrap();
        let mut r =
            Renderer::new(placed.data, FrameSettings::new(W, H), &GraphSource::Shipped).unwrap();
        let sources = vec![
            PageSource::of(&opened).unwrap(),
            PageSource::Memory(Arc::clone(&assets[1])),
        ];
        assert!(matches!(sources[0], PageSource::File { .. }));
        r.start_streaming(sources, Budget::default(), 2).unwrap();
        let mut failures = Vec::new();
        for frame in 0..40u32 {
            r.frame(&placed.camera).unwrap();
            let s = r.streaming.as_mut().unwrap();
            failures.extend(s.take_failures());
            let mut view = placed.camera.view([W, H], frame, None);
            view.lod_scale /= s.lod_scale();
            check_complete_cuts(&r, &dags, &view);
        }
        let still = r.render_still(&placed.camera).unwrap();
        assert!(still.counts.software + still.counts.hardware > 0);
        assert_eq!(failures.len(), 1, "{name}: {failures:?}");
        assert_eq!(failures[0].page, damaged);
        let reason = &failures[0].reason;
        assert!(reason.contains(says), "{name}: {reason}");
        assert!(reason.contains(name), "{name}: {reason}");
        // Neither it nor anything below it was installed.
        let pages = &r.data.streaming().unwrap().pages;
        let mut below = vec![damaged];
        while let Some(p) = below.pop() {
            assert!(
                pages[p as usize].resident_at.is_none(),
                "{name}: page {p} installed"
            );
            below.extend_from_slice(graph.dependents(p));
        }
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

/// The drawn cut read back from the GPU (`Renderer::drawn_clusters`) is complete on every
/// frame of a camera moving in and out under a pool far smaller than the pages: the CPU
/// checker (`stream::cut::check`) finds every path from a LOD-0 meshlet to a root
/// meeting exactly one drawn meshlet, and only meshlets of resident pages drawn.
/// Occlusion is off and the mesh stays inside the view, so what was drawn is the whole
/// cut.
#[test]
fn the_drawn_cut_read_back_from_the_gpu_is_complete_every_frame() {
    let mut placed = scenes::single(SceneData::streamed(Limits::default()), asset()).unwrap();
    placed.data.reserve_pool(all_pages() / 64).unwrap();
    let settings = FrameSettings {
        occlusion: false,
        keep_visibility: true,
        ..FrameSettings::new(480, 270)
    };
    // The copy's bounding sphere in the world (the field turns and scales it a little).
    let sphere = placed.data.meshes[0].bounding_sphere;
    let world =
        meshlight::glam::Mat4::from_cols_array_2d(&placed.data.instances[0].world_from_local);
    let centre = world.transform_point3(Vec3::new(sphere[0], sphere[1], sphere[2]));
    let radius = sphere[3]
        * world
            .x_axis
            .length()
            .max(world.y_axis.length())
            .max(world.z_axis.length());
    let mut r = Renderer::new(placed.data, settings, &GraphSource::Shipped).unwrap();
    r.start_streaming(placed.sources, Budget::default(), 2)
        .unwrap();
    let dag = MeshDag::of_asset(asset());
    let meshlets = asset().meshlets().len();
    let (mut paged, mut last) = (0, Vec::new());
    for frame in 0..48u32 {
        // From 3.5 radii (the whole mesh in view) out to 12 and back.
        let t = 0.5 - 0.5 * (frame as f32 * 0.26).cos();
        let eye = centre + Vec3::new(0.45, 0.55, 1.0).normalize() * radius * (3.5 + 8.5 * t);
        let camera = Camera::perspective(eye, centre, 40f32.to_radians(), radius * 0.05);
        r.frame(&camera).unwrap();
        let drawn = r.drawn_clusters().unwrap();
        let mut flags = vec![false; meshlets];
        for c in drawn.iter().filter(|c| c.instance == 0) {
            assert!(
                !flags[c.meshlet as usize],
                "frame {frame}: meshlet {} twice",
                c.meshlet
            );
            flags[c.meshlet as usize] = true;
        }
        let pages = &r.data.streaming().unwrap().pages;
        let resident = |g: u32| pages[g as usize].resident_at.is_some();
        if let Err(hole) = check(&dag, &flags, resident) {
            panic!("frame {frame}: {hole}");
        }
        paged += (0..meshlets)
            .filter(|&m| flags[m] && asset().meshlets()[m].parent_group != NO_GROUP)
            .count();
        last = flags;
    }
    let stats = r.streaming.as_ref().unwrap().stats();
    assert!(
        stats.evicted_total > 0,
        "the pool was never full: {stats:?}"
    );
    assert!(paged > 100, "{paged} meshlets of pages drawn");
    // The checker can fail: one drawn meshlet taken away leaves a path without one.
    let m = last.iter().position(|&d| d).unwrap();
    last[m] = false;
    let pages = &r.data.streaming().unwrap().pages;
    assert!(check(&dag, &last, |g| pages[g as usize].resident_at.is_some()).is_err());
}

/// The `residency` view in a streamed frame: before streaming has settled, clusters
/// drawn coarser than the view wants show (yellow to red, red above green); once it has
/// settled, every covered pixel is at the wanted level (green).
#[test]
fn the_residency_view_shows_missing_detail_until_streaming_settles() {
    let placed = field(Some(all_pages()));
    let settings = FrameSettings {
        view: Some(meshlight::resolve::DebugView::Residency),
        ..FrameSettings::new(W, H)
    };
    let mut r = Renderer::new(placed.data, settings, &GraphSource::Shipped).unwrap();
    r.start_streaming(placed.sources, Budget::default(), 2)
        .unwrap();
    // Pixels drawn coarser than wanted: redder than green.
    let coarser = |still: &Still| {
        still
            .rgba
            .chunks(4)
            .filter(|p| p[0] as i32 > p[1] as i32 + 8)
            .count()
    };
    let first = r.render_still(&placed.camera).unwrap();
    let early = coarser(&first);
    assert!(
        early > 50,
        "only {early} pixels drawn coarser before streaming"
    );
    r.settle_streaming(&placed.camera, 400).unwrap();
    let settled = r.render_still(&placed.camera).unwrap();
    let covered = settled.rgba.chunks(4).filter(|p| p[1] > 0).count();
    assert!(covered > 1000, "{covered} covered pixels");
    assert_eq!(coarser(&settled), 0, "drawn coarser once settled");
}

/// The shadow maps of the resident field, or of the streamed one once streaming settles.
fn shadow_maps(placed: &Placed, streamed: bool) -> Vec<u32> {
    use meshlight_virtual_geometry::setup::ShadowRequest;
    let request = ShadowRequest {
        cascades: Some(2),
        // Texels far finer than the camera's pixels: the cascades want finer levels
        // than the camera's cut holds.
        resolution: Some(1024),
        ..ShadowRequest::default()
    };
    let shadows = request.settings(&placed.data, &placed.camera, [W, H], true);
    let settings = FrameSettings {
        shadows,
        // Every cluster in software, so the maps compare bit for bit.
        hardware: Some(false),
        ..FrameSettings::new(W, H)
    };
    let mut r = Renderer::new(placed.data.clone(), settings, &GraphSource::Shipped).unwrap();
    if streamed {
        r.start_streaming(sources(placed), Budget::default(), 2)
            .unwrap();
        settle(&mut r, placed, 300);
    } else {
        r.render_still(&placed.camera).unwrap();
    }
    let maps = r
        .shadow_maps()
        .expect("the renderer keeps the maps")
        .clone();
    bytemuck::pod_collect_to_vec(&r.executor.gpu.read_buffer(&maps, 0, maps.size()).unwrap())
}

/// The shadow culls ask for the pages of their cascades' cuts after the camera's, so
/// once a streamed field settles its shadow maps are the resident field's, texel for
/// texel, though its cascades want finer levels than its low-resolution camera (with
/// the camera's requests alone, the maps stay coarser).
#[test]
fn a_streamed_fields_shadow_maps_settle_on_the_resident_maps() {
    let want = shadow_maps(&field(None), false);
    let got = shadow_maps(&field(Some(all_pages())), true);
    assert_eq!(got.len(), want.len());
    let drawn = want.iter().filter(|&&d| d != 0).count();
    assert!(drawn > want.len() / 4, "the maps cover only {drawn} texels");
    let differ = got.iter().zip(&want).filter(|(g, w)| g != w).count();
    assert_eq!(
        differ,
        0,
        "{differ} of {} texels differ from the resident maps",
        want.len()
    );
}
