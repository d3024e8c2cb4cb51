//! One hierarchy walk for several views (`views` > 1) against a walk per view: each
//! view's list holds exactly the clusters its own walk lists (as a set, each once), with
//! the same count words, and `cull_lod` reading that view's list (`list`, `lists`) finds
//! the same cut. Views are seeded perspective and orthographic ones and a sun's shadow
//! cascades; a view given no viewport lists nothing; lists may start past the first of
//! the buffers; and with a queue too short to hold the frontier (whole subtrees emitted)
//! the lists may differ but every cut still holds. A first walk over a camera and a sun's
//! cascades, occlusion tested for the camera alone against last frame's pyramid, lists
//! for each view and hands on as hidden exactly what the walk of each view alone does.

mod support;

use glam::Vec3;
use meshlight_gpu_scene::cascades::{Cascade, CascadeSettings, cascades};
use meshlight_gpu_scene::gpu::elements;
use meshlight_gpu_scene::{Camera, GpuScene, ListPart, SceneData};
use meshlight_graph::*;
use meshlight_pass_cull_lod::{CullLod, Thresholds};
use meshlight_pass_fill_clusters::{CAMERA_CUT_INPUT, HIDDEN_NODE, HierarchyFill};
use meshlight_shaders::cpu::layout::{Cluster, View};
use meshlight_shaders::cpu::occlusion::DepthPyramid;
use meshlight_testing::copy_pyramid::{pyramid_texture_desc, uploaded_history};
use meshlight_testing::{texture, write_pyramid};
use std::collections::BTreeSet;
use support::run::{Cull, run_fill};
use support::scenes::{Views, walls};
use support::*;

/// The bunny and spot on a 4 × 3 field, turned and scaled differently.
fn scene() -> SceneData {
    support::scenes::bunny_and_spot()
}

/// Random views of the field (every fourth orthographic), near and far, at 1 px.
const VIEWS: Views = Views {
    thresholds: &[1.0],
    ..support::scenes::BUNNY_AND_SPOT_VIEWS
};

/// Clusters each list may hold.
const LIST: u32 = 1 << 15;

/// The sun's cascades over the field: `count` of 512² to 30 bunny radii, for `camera`.
fn suns(data: &SceneData, camera: &Camera, viewport: [u32; 2], count: u32) -> Vec<Cascade> {
    let radius = data.meshes[0].bounding_sphere[3];
    let settings = CascadeSettings {
        count,
        resolution: 512,
        distance: 30.0 * radius,
        caster_reach: 30.0 * radius,
        ..CascadeSettings::default()
    };
    cascades(camera, viewport, Vec3::new(0.4, 1.0, 0.3), &settings, 0).unwrap()
}

/// A camera over the field from one corner, in bunny radii.
fn corner_camera(data: &SceneData) -> Camera {
    let radius = data.meshes[0].bounding_sphere[3];
    Camera::perspective(
        Vec3::new(-2.0, 1.5, -2.0) * radius,
        Vec3::new(5.0, 0.0, 4.0) * radius,
        1.0,
        radius * 0.02,
    )
}

/// What one view's list and cut came to.
struct ViewResult {
    list: BTreeSet<(u32, u32)>,
    /// Entries written, before being made a set (to see none was written twice).
    written: usize,
    words: [u32; 2],
    cut: BTreeSet<(u32, u32)>,
}

/// One walk over `views` writing lists `first .. first + views.len()` of `lists`, then a
/// cull per view reading its list; each view's list and cut. `queue`: the walk's
/// frontier capacity (`None`: the default).
fn one_walk(
    data: &mut SceneData,
    views: &[View],
    first: u32,
    lists: u32,
    threshold: f32,
    queue: Option<u32>,
) -> Vec<ViewResult> {
    let gpu = gpu();
    let scene = GpuScene::new(&gpu, data);
    let mut g = GraphBuilder::new();
    scene.import(&mut g);
    scene.import_hierarchy(&mut g);
    g.import_buffer(
        "clusters",
        BufferDesc::array(elements::CLUSTER, u64::from(LIST * lists)),
        USAGE,
    );
    g.create_buffer(
        "cluster_count",
        BufferDesc::array(Element::U32, 2 * u64::from(lists)),
    );
    let walk = HierarchyFill {
        lod_threshold_px: threshold,
        capacity: Some(LIST),
        queue_capacity: queue,
        views: views.len() as u32,
        part: ListPart { list: first, lists },
        ..HierarchyFill::default()
    };
    let out = g
        .add_pass("walk", walk, Bindings::new().input("view", "views"))
        .unwrap();
    g.export(out.buffer("cluster_count").unwrap());
    for k in 0..views.len() as u32 {
        let cull = CullLod {
            thresholds: Thresholds {
                lod_threshold_px: threshold,
                ..Thresholds::default()
            },
            part: ListPart {
                list: first + k,
                lists,
            },
            ..CullLod::default()
        };
        let name = |n: &str| format!("{n}_{k}");
        g.create_buffer(
            &name("raster_clusters"),
            BufferDesc::array(elements::CLUSTER, u64::from(LIST)),
        );
        g.create_buffer(&name("raster_counts"), BufferDesc::array(Element::U32, 8));
        g.create_buffer(&name("hw_args"), BufferDesc::array(Element::DRAW_ARGS, 1));
        let bindings = Bindings::new()
            .input("view", &name("view"))
            .bind_named("raster_clusters", &name("raster_clusters"))
            .bind_named("raster_counts", &name("raster_counts"))
            .bind_named("hw_args", &name("hw_args"));
        let culled = g.add_pass(&name("cull"), cull, bindings).unwrap();
        g.export(culled.buffer("raster_clusters").unwrap());
        g.export(culled.buffer("raster_counts").unwrap());
    }
    let compiled = g.compile(&CompileOptions::for_gpu(&gpu)).unwrap();
    let list_buffer = gpu.buffer_with_data(
        "clusters",
        bytemuck::cast_slice(&vec![SENTINEL; (LIST * lists) as usize]),
        USAGE,
    );
    let mut frame = FrameData::new().with("views", bytemuck::cast_slice(views));
    for (k, v) in views.iter().enumerate() {
        frame = frame.with(&format!("view_{k}"), bytemuck::bytes_of(v));
    }
    let mut exec = Executor::new(gpu);
    exec.execute_frame(
        &compiled,
        &scene.imports().buffer("clusters", &list_buffer),
        &frame,
    )
    .unwrap();
    let words: Vec<u32> = bytemuck::pod_collect_to_vec(&exec.read_buffer("cluster_count").unwrap());
    let all: Vec<Cluster> = bytemuck::pod_collect_to_vec(
        &exec
            .gpu
            .read_buffer(&list_buffer, 0, list_buffer.size())
            .unwrap(),
    );
    // Lists the walk does not write keep the sentinel and zero words.
    for k in (0..lists).filter(|k| !(first..first + views.len() as u32).contains(k)) {
        let part = &all[(k * LIST) as usize..((k + 1) * LIST) as usize];
        assert!(
            part.iter().all(|c| *c == SENTINEL),
            "list {k}, which no view of the walk owns, was written"
        );
        assert_eq!(
            words[2 * k as usize..2 * k as usize + 2],
            [0, 0],
            "list {k}'s words"
        );
    }
    (0..views.len() as u32)
        .map(|k| {
            let list = first + k;
            let w = [words[2 * list as usize], words[2 * list as usize + 1]];
            let part = &all[(list * LIST) as usize..((list + 1) * LIST) as usize];
            assert!(
                part[w[0] as usize..].iter().all(|c| *c == SENTINEL),
                "view {k}: a slot past its list was written"
            );
            let listed = &part[..w[0] as usize];
            let raster: Vec<Cluster> = bytemuck::pod_collect_to_vec(
                &exec.read_buffer(&format!("raster_clusters_{k}")).unwrap(),
            );
            let c: Vec<u32> = bytemuck::pod_collect_to_vec(
                &exec.read_buffer(&format!("raster_counts_{k}")).unwrap(),
            );
            let (sw, hw) = (c[0] as usize, c[1] as usize);
            let cut = raster[..sw]
                .iter()
                .chain(&raster[LIST as usize - hw..])
                .map(|c| (c.instance, c.meshlet))
                .collect();
            ViewResult {
                list: set(listed),
                written: listed.len(),
                words: w,
                cut,
            }
        })
        .collect()
}

/// The walk of `view` alone, with cull after it: its list and cut.
fn single_walk(
    data: &mut SceneData,
    view: &View,
    threshold: f32,
    queue: Option<u32>,
) -> ViewResult {
    let walk = HierarchyFill {
        lod_threshold_px: threshold,
        capacity: Some(LIST),
        queue_capacity: queue,
        ..HierarchyFill::default()
    };
    let cull = Cull {
        threshold,
        slots: LIST,
    };
    let f = run_fill(data, view, Box::new(walk), LIST + GUARD, Some(cull));
    ViewResult {
        list: set(f.listed()),
        written: f.listed().len(),
        words: f.cluster_count,
        cut: f.cut.expect("cull ran"),
    }
}

/// Every view of `views` walked at once and alone: the same lists (`exact`) and cuts.
fn compare(
    data: &mut SceneData,
    views: &[View],
    first: u32,
    lists: u32,
    queue: Option<u32>,
    exact: bool,
) -> usize {
    let threshold = 1.0;
    let together = one_walk(data, views, first, lists, threshold, queue);
    let mut clusters = 0;
    for (k, (view, got)) in views.iter().zip(&together).enumerate() {
        assert_eq!(
            got.written,
            got.list.len(),
            "view {k}: a cluster written twice"
        );
        if view.viewport_size == [0.0, 0.0] {
            assert_eq!(
                got.words,
                [0, 0],
                "view {k} has no viewport, yet listed clusters"
            );
            continue;
        }
        let alone = single_walk(data, view, threshold, queue);
        if exact {
            assert_eq!(got.words, alone.words, "view {k}: count words");
            assert!(
                got.list == alone.list,
                "view {k}: {} clusters listed alone, {} in one walk, {} differ",
                alone.list.len(),
                got.list.len(),
                got.list.symmetric_difference(&alone.list).count()
            );
        }
        assert!(
            got.cut == alone.cut,
            "view {k}: the cut differs ({} alone, {} in one walk)",
            alone.cut.len(),
            got.cut.len()
        );
        clusters += got.list.len();
    }
    clusters
}

#[test]
fn one_walk_for_four_views_lists_what_four_walks_list() {
    let mut data = scene();
    let mut listed = 0;
    for seed in [0x5eed_0001u64, 0x5eed_0002, 0x5eed_0003] {
        let views: Vec<View> = VIEWS.seeded(&data, seed, 4).map(|(_, v, _)| v).collect();
        listed += compare(&mut data, &views, 0, 4, None, true);
    }
    assert!(
        listed > 1000,
        "only {listed} clusters listed: the views see too little"
    );
}

#[test]
fn one_walk_for_a_suns_cascades_lists_what_a_walk_per_cascade_lists() {
    let mut data = scene();
    let list = suns(&data, &corner_camera(&data), [640, 360], 4);
    let views: Vec<View> = list.iter().map(|c| c.view).collect();
    let listed = compare(&mut data, &views, 0, 4, None, true);
    assert!(listed > 100, "only {listed} clusters listed");
}

#[test]
fn a_view_without_a_viewport_lists_nothing_and_lists_may_start_past_the_first() {
    let mut data = scene();
    let mut views: Vec<View> = VIEWS
        .seeded(&data, 0x5eed_0004, 3)
        .map(|(_, v, _)| v)
        .collect();
    views[1] = View::default();
    views[1].viewport_size = [0.0, 0.0];
    compare(&mut data, &views, 1, 5, None, true);
}

#[test]
fn a_full_queue_emits_whole_subtrees_for_its_views_and_keeps_every_cut() {
    let mut data = scene();
    let views: Vec<View> = VIEWS
        .seeded(&data, 0x5eed_0005, 4)
        .map(|(_, v, _)| v)
        .collect();
    compare(&mut data, &views, 0, 4, Some(2), false);
}

/// One view's list (as a set) and its words (written, requested).
type Listed = (BTreeSet<(u32, u32)>, [u32; 2]);

/// What a first walk left: per view its list, and the nodes the pyramid hid with their
/// words (written, found).
struct FirstWalk {
    lists: Vec<Listed>,
    hidden: BTreeSet<(u32, u32)>,
    hidden_words: [u32; 2],
}

/// A first walk over `views` (lists `0 .. views.len()` of as many), occlusion tested for
/// view `o` of `occlusion` against its pyramid as last frame's (a history filled the
/// frame before, which walks `before`, or `views` when `None`); `None`: no pyramid
/// bound.
fn first_walk(
    data: &mut SceneData,
    views: &[View],
    before: Option<&[View]>,
    occlusion: Option<(u32, &DepthPyramid)>,
) -> FirstWalk {
    walk_frames(data, views, before, occlusion, false)
}

/// [`first_walk`], with `cut`: one frame more, told the camera jumped (it tests nothing).
fn walk_frames(
    data: &mut SceneData,
    views: &[View],
    before: Option<&[View]>,
    occlusion: Option<(u32, &DepthPyramid)>,
    cut: bool,
) -> FirstWalk {
    const NODES: u64 = 1 << 12;
    let gpu = gpu();
    let scene = GpuScene::new(&gpu, data);
    let lists = views.len() as u32;
    let mut g = GraphBuilder::new();
    scene.import(&mut g);
    scene.import_hierarchy(&mut g);
    g.create_buffer(
        "clusters",
        BufferDesc::array(elements::CLUSTER, u64::from(LIST * lists)),
    );
    g.create_buffer(
        "cluster_count",
        BufferDesc::array(Element::U32, 2 * u64::from(lists)),
    );
    let walk = HierarchyFill {
        capacity: Some(LIST),
        views: lists,
        occlusion_view: occlusion.map_or(0, |(o, _)| o),
        part: ListPart { list: 0, lists },
        ..HierarchyFill::default()
    };
    let mut bindings = Bindings::new().input("view", "views");
    let usage = wgpu::TextureUsages::TEXTURE_BINDING
        | wgpu::TextureUsages::COPY_SRC
        | wgpu::TextureUsages::COPY_DST;
    let mut upload = None;
    if let Some((_, pyramid)) = occlusion {
        let desc = pyramid_texture_desc(pyramid);
        let history = uploaded_history(&mut g, "pyramid", "upload", &desc, usage).unwrap();
        let nodes = g.create_buffer("hidden_nodes", BufferDesc::array(HIDDEN_NODE, NODES));
        let count = g.create_buffer("hidden_count", BufferDesc::array(Element::U32, 2));
        bindings = bindings
            .bind("pyramid", history.prev)
            .bind("occluded_nodes", nodes)
            .bind("occluded_node_count", count);
        upload = Some((texture(&gpu, "upload", &desc, usage), pyramid));
    }
    let out = g.add_pass("walk", walk, bindings).unwrap();
    g.export(out.buffer("clusters").unwrap());
    g.export(out.buffer("cluster_count").unwrap());
    if occlusion.is_some() {
        g.export(out.buffer("occluded_nodes").unwrap());
        g.export(out.buffer("occluded_node_count").unwrap());
    }
    let compiled = g.compile(&CompileOptions::for_gpu(&gpu)).unwrap();
    let mut imports = scene.imports();
    if let Some((texture, pyramid)) = &upload {
        write_pyramid(&gpu.queue, texture, pyramid);
        imports = imports.texture("upload", texture);
    }
    let frame = |views: &[View], cut: bool| {
        FrameData::new()
            .with("views", bytemuck::cast_slice(views))
            .with(CAMERA_CUT_INPUT, &u32::from(cut).to_le_bytes())
    };
    let mut exec = Executor::new(gpu);
    // The first frame fills the history; the second walks against it; with `cut`, a
    // third is told the camera jumped.
    for views in [before.unwrap_or(views), views] {
        exec.execute_frame(&compiled, &imports, &frame(views, false))
            .unwrap();
    }
    if cut {
        exec.execute_frame(&compiled, &imports, &frame(views, true))
            .unwrap();
    }
    let words = |exec: &mut Executor, name: &str| -> Vec<u32> {
        bytemuck::pod_collect_to_vec(&exec.read_buffer(name).unwrap())
    };
    let counts = words(&mut exec, "cluster_count");
    let all: Vec<Cluster> = bytemuck::pod_collect_to_vec(&exec.read_buffer("clusters").unwrap());
    let lists = (0..lists as usize)
        .map(|k| {
            let w = [counts[2 * k], counts[2 * k + 1]];
            assert_eq!(w[0], w[1], "list {k} overflowed");
            let listed = &all[k * LIST as usize..][..w[0] as usize];
            let listed_set = set(listed);
            assert_eq!(listed_set.len(), listed.len(), "list {k}: a cluster twice");
            (listed_set, w)
        })
        .collect();
    let (mut hidden, mut hidden_words) = (BTreeSet::new(), [0, 0]);
    if occlusion.is_some() {
        let w = words(&mut exec, "hidden_count");
        hidden_words = [w[0], w[1]];
        let nodes = words(&mut exec, "hidden_nodes");
        hidden = nodes
            .chunks_exact(3)
            .take(w[0] as usize)
            .map(|n| (n[0], n[1]))
            .collect();
        assert_eq!(hidden.len(), w[0] as usize, "a hidden node twice");
    }
    FirstWalk {
        lists,
        hidden,
        hidden_words,
    }
}

#[test]
fn one_walk_for_the_camera_and_a_suns_cascades_tests_occlusion_for_the_camera_alone() {
    let mut data = scene();
    let radius = data.meshes[0].bounding_sphere[3];
    let viewport = [640, 360];
    let mut rng = Rng(0x0cc1_7a11);
    let (mut hidden, mut behind) = (0, 0);
    for round in 0..6 {
        let eye = Vec3::new(
            rng.range(-3.0, -1.0),
            rng.range(0.8, 2.5),
            rng.range(-3.0, -1.0),
        );
        let target = Vec3::new(rng.range(4.0, 7.0), 0.0, rng.range(3.0, 5.0));
        let camera = Camera::perspective(eye * radius, target * radius, 1.0, radius * 0.02);
        let suns = suns(&data, &camera, viewport, 4);
        let camera_view = camera.view(viewport, 0, None);
        let walls_count = 6 + rng.below(6);
        let pyramid = walls(&mut rng, &data, &camera_view, viewport, walls_count);
        // The camera last (as the shipped frame walks it), or first.
        let mut views: Vec<View> = suns.iter().map(|c| c.view).collect();
        let o = if round % 2 == 0 { views.len() } else { 0 };
        views.insert(o, camera_view);
        let together = first_walk(&mut data, &views, None, Some((o as u32, &pyramid)));
        let alone = first_walk(&mut data, &[camera_view], None, Some((0, &pyramid)));
        assert_eq!(
            (&together.hidden, together.hidden_words),
            (&alone.hidden, alone.hidden_words),
            "round {round}: the camera's hidden nodes"
        );
        for (k, view) in views.iter().enumerate() {
            let want = if k == o {
                alone.lists[0].clone()
            } else {
                first_walk(&mut data, &[*view], None, None).lists[0].clone()
            };
            let got = &together.lists[k];
            assert_eq!(got.1, want.1, "round {round}, view {k}: count words");
            assert!(
                got.0 == want.0,
                "round {round}, view {k}: {} clusters alone, {} in one walk, {} differ",
                want.0.len(),
                got.0.len(),
                got.0.symmetric_difference(&want.0).count()
            );
        }
        // Instances the camera's pyramid hides whole are still listed for a cascade.
        let hidden_instances: BTreeSet<u32> = together.hidden.iter().map(|h| h.0).collect();
        behind += views
            .iter()
            .enumerate()
            .filter(|&(k, _)| k != o)
            .flat_map(|(k, _)| &together.lists[k].0)
            .filter(|(instance, _)| hidden_instances.contains(instance))
            .count();
        hidden += together.hidden.len();
    }
    assert!(hidden > 0, "the walls hid no node on any view");
    assert!(
        behind > 0,
        "no cascade listed a cluster of an instance the camera's pyramid hid"
    );
}

/// A walk over several views given one viewport this frame (the camera while every
/// cascade keeps its map; one cascade drawn) runs as that view's own walk: the same list
/// and hidden nodes, and every other list's words zeroed though the frame before wrote
/// them.
#[test]
fn a_walk_given_one_view_lists_and_hides_what_that_views_own_walk_does() {
    let mut data = scene();
    let viewport = [640, 360];
    let mut rng = Rng(0x0e1e_0001);
    let camera = corner_camera(&data);
    let suns = suns(&data, &camera, viewport, 2);
    let camera_view = camera.view(viewport, 0, None);
    let pyramid = walls(&mut rng, &data, &camera_view, viewport, 8);
    let all = [suns[0].view, suns[1].view, camera_view];
    let zeroed = View {
        viewport_size: [0.0; 2],
        ..View::default()
    };
    // The camera alone, occlusion tested for it.
    let lone = [zeroed, zeroed, camera_view];
    let got = first_walk(&mut data, &lone, Some(&all), Some((2, &pyramid)));
    let want = first_walk(&mut data, &[camera_view], None, Some((0, &pyramid)));
    assert_eq!(got.lists[2], want.lists[0], "the camera's list and words");
    assert_eq!(
        (&got.hidden, got.hidden_words),
        (&want.hidden, want.hidden_words),
        "the camera's hidden nodes"
    );
    assert!(!want.hidden.is_empty(), "the walls hid nothing");
    // One cascade alone, no pyramid.
    let lone = [zeroed, suns[1].view, zeroed];
    let got = first_walk(&mut data, &lone, Some(&all), None);
    let want = first_walk(&mut data, &[suns[1].view], None, None);
    assert_eq!(got.lists[1], want.lists[0], "the cascade's list and words");
    for k in [0, 2] {
        assert_eq!(
            got.lists[k].1,
            [0, 0],
            "list {k}'s words kept the frame before's"
        );
    }
    assert!(!want.lists[0].0.is_empty(), "the cascade listed nothing");
}

/// A first walk with a pyramid that tests nothing (no history, a camera cut: the
/// renderer's frames while occlusion does not pay) runs kernels compiled without the
/// test. It lists what a walk without a pyramid lists, and hands on no hidden node,
/// though the frame before hid some.
#[test]
fn a_first_walk_that_tests_nothing_lists_what_a_walk_without_a_pyramid_does() {
    let mut data = scene();
    let viewport = [640, 360];
    let mut rng = Rng(0x0c07_0001);
    let camera_view = corner_camera(&data).view(viewport, 0, None);
    let pyramid = walls(&mut rng, &data, &camera_view, viewport, 8);
    let tested = first_walk(&mut data, &[camera_view], None, Some((0, &pyramid)));
    assert!(!tested.hidden.is_empty(), "the walls hid nothing");
    let cut = walk_frames(&mut data, &[camera_view], None, Some((0, &pyramid)), true);
    let plain = first_walk(&mut data, &[camera_view], None, None);
    assert_eq!(cut.lists[0], plain.lists[0], "the list and its words");
    assert_eq!(cut.hidden_words, [0, 0], "hidden nodes after a cut");
}
