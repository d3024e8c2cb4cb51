//! `cull_lod` with the streaming slots, on a streamed scene (spot placed six times,
//! pages installed parents first at random): the pages the GPU lists are the
//! reference's (`cpu::wanted_pages`), each once a frame; a frame that already listed a
//! page does not list it again; and with every page installed the cut is the resident
//! scene's.

use glam::{Mat4, Quat, Vec3};
use meshlight_gpu_scene::data::Limits;
use meshlight_gpu_scene::gpu::elements;
use meshlight_gpu_scene::{Camera, GpuScene, Material, SceneData};
use meshlight_graph::*;
use meshlight_pass_cull_lod::cpu::wanted_pages;
use meshlight_pass_cull_lod::{CullLod, PAGE_REQUEST, Thresholds, cpu_cull};
use meshlight_shaders::cpu::layout::{Cluster, View};
use meshlight_stream::{MeshDag, PageId};
use std::collections::BTreeMap;

mod common;
use common::*;

fn placements() -> Vec<Mat4> {
    (0..6)
        .map(|i| {
            let (x, z) = ((i % 3) as f32 * 3.0 - 3.0, (i / 3) as f32 * 3.0 - 1.5);
            Mat4::from_scale_rotation_translation(
                Vec3::splat(0.8 + 0.15 * i as f32),
                Quat::from_rotation_y(i as f32 * 1.1),
                Vec3::new(x, 0.0, z),
            )
        })
        .collect()
}

fn streamed_scene() -> SceneData {
    let mut data = SceneData::streamed(Limits::default());
    let material = data.add_material(Material::default()).unwrap();
    let mesh = data.add_mesh("spot", spot()).unwrap();
    for transform in placements() {
        data.add_instance(mesh, transform, material)
            .unwrap()
            .unwrap();
    }
    let bytes: u64 = spot().pages().iter().map(|p| u64::from(p.words) * 4).sum();
    data.reserve_pool(bytes).unwrap();
    data
}

/// Installs each page whose parents are in with probability `share`, parents first, at
/// its own range of the pool.
fn install_some(data: &mut SceneData, rng: &mut Rng, share: f32) -> usize {
    let graph = MeshDag::of_asset(spot()).pages();
    let mut order: Vec<PageId> = (0..graph.len() as PageId).collect();
    order.sort_by_key(|&p| graph.depth(p));
    let at: Vec<u32> = (spot().pages().iter())
        .scan(0u32, |next, page| {
            let at = *next;
            *next += page.words;
            Some(at)
        })
        .collect();
    let mut installed = 0;
    for page in order {
        let parents_in = graph.parents(page).iter().all(|&q| {
            data.streaming().unwrap().pages[q as usize]
                .resident_at
                .is_some()
        });
        if parents_in && rng.unit() < share {
            let words = spot().payload()[spot().pages()[page as usize].range()].to_vec();
            data.install_page(page, at[page as usize], &words).unwrap();
            installed += 1;
        }
    }
    installed
}

/// The pages listed by one or more frames of the pass (frame indices `frames`), with the
/// cut of the last.
struct Listed {
    frames: Vec<BTreeMap<u32, f32>>,
    software: usize,
    hardware: usize,
}

fn run(data: &mut SceneData, clusters: &[Cluster], views: &[View], t: Thresholds) -> Listed {
    let gpu = gpu();
    let scene = GpuScene::new(&gpu, data);
    let mut g = GraphBuilder::new();
    let h = scene.import(&mut g);
    let stream_errors = scene.import_stream_errors(&mut g);
    let groups = data.groups.len() as u64;
    let n = clusters.len() as u64;
    let list = g.import_buffer("clusters", BufferDesc::array(elements::CLUSTER, n), USAGE);
    let count = g.import_buffer("cluster_count", BufferDesc::array(Element::U32, 2), USAGE);
    let raster = g.import_buffer(
        "raster_clusters",
        BufferDesc::array(elements::CLUSTER, n),
        USAGE,
    );
    let marks = g.import_buffer("page_marks", BufferDesc::array(Element::U32, groups), USAGE);
    let counts = g.create_buffer("raster_counts", BufferDesc::array(Element::U32, 8));
    let hw_args = g.create_buffer("hw_args", BufferDesc::array(Element::DRAW_ARGS, 1));
    let requests = g.create_buffer("page_requests", BufferDesc::array(PAGE_REQUEST, groups));
    let request_count = g.create_buffer("page_request_count", BufferDesc::array(Element::U32, 2));
    let pass = CullLod {
        thresholds: t,
        ..CullLod::default()
    };
    let out = g
        .add_pass(
            "cull",
            pass,
            base_bindings([list, count, h.groups, raster, counts, hw_args])
                .bind("page_errors", stream_errors)
                .bind("page_marks", marks)
                .bind("page_requests", requests)
                .bind("page_request_count", request_count),
        )
        .unwrap();
    for slot in ["raster_counts", "page_requests", "page_request_count"] {
        g.export(out.buffer(slot).unwrap());
    }
    let compiled = g.compile(&CompileOptions::for_gpu(&gpu)).unwrap();
    let [list_buffer, count_buffer, raster_buffer] = cull_buffers(&gpu, clusters, n as u32);
    let marks_buffer = gpu.buffer_with_data("page_marks", &vec![0u8; groups as usize * 4], USAGE);
    let imports = scene
        .imports()
        .buffer("clusters", &list_buffer)
        .buffer("cluster_count", &count_buffer)
        .buffer("raster_clusters", &raster_buffer)
        .buffer("page_marks", &marks_buffer);
    let mut exec = Executor::new(gpu);
    let mut frames = Vec::new();
    let mut last_counts: Vec<u32> = vec![];
    for view in views {
        let frame = FrameData::new().with("view", bytemuck::bytes_of(view));
        exec.execute_frame(&compiled, &imports, &frame).unwrap();
        let count: Vec<u32> =
            bytemuck::pod_collect_to_vec(&exec.read_buffer("page_request_count").unwrap());
        assert_eq!(count[0], count[1], "the list held every request");
        let list: Vec<[u32; 2]> =
            bytemuck::pod_collect_to_vec(&exec.read_buffer("page_requests").unwrap());
        let mut listed = BTreeMap::new();
        for &[group, bits] in &list[..count[0] as usize] {
            assert!(
                listed.insert(group, f32::from_bits(bits)).is_none(),
                "group {group} listed twice in a frame"
            );
        }
        frames.push(listed);
        last_counts = bytemuck::pod_collect_to_vec(&exec.read_buffer("raster_counts").unwrap());
    }
    Listed {
        frames,
        software: last_counts[0] as usize,
        hardware: last_counts[1] as usize,
    }
}

/// The slots every cull binds: the candidates and their count, the groups, the raster
/// slots, their counts and the draw arguments, in that order.
fn base_bindings(buffers: [Handle<Buffer>; 6]) -> Bindings {
    let slots = [
        "clusters",
        "cluster_count",
        "meshlet_groups",
        "raster_clusters",
        "raster_counts",
        "hw_args",
    ];
    slots
        .into_iter()
        .zip(buffers)
        .fold(Bindings::new(), |b, (slot, h)| b.bind(slot, h))
}

fn camera_view(rng: &mut Rng, frame: u32) -> View {
    let (target, direction) = random_aim(rng, Vec3::new(4.0, 0.5, 3.0), [-0.3, 1.0]);
    let distance = 1.5 * (8.0f32 / 1.5).powf(rng.unit());
    Camera::perspective(target + direction * distance, target, 1.0, 0.05).view(
        [640, 360],
        frame,
        None,
    )
}

#[test]
fn the_listed_pages_are_the_references_once_a_frame() {
    let (mut listed_missing, mut listed_used) = (0, 0);
    for seed in 1..=4u64 {
        let mut data = streamed_scene();
        let (mut rng, _, clusters) = seeded(seed, scene_with(&placements()));
        let installed = install_some(&mut data, &mut rng, [0.3, 0.6, 0.9, 1.0][seed as usize - 1]);
        let t = Thresholds {
            lod_threshold_px: 1.0,
            ..Thresholds::default()
        };
        let view = camera_view(&mut rng, 7);
        let mut next = view;
        next.frame_index = 8;
        // The same frame twice lists nothing the second time; the next frame lists again.
        let got = run(&mut data, &clusters, &[view, view, next], t);
        let want = wanted_pages(&data, &view, &clusters, &t);
        let label = format!("seed {seed} ({installed} pages in)");
        assert!(
            got.frames[1].is_empty(),
            "{label}: listed again in the same frame"
        );
        // The same pages; each at the priority of whichever of its clusters listed it
        // first, which may differ from frame to frame (checked against the range below).
        assert!(
            got.frames[0].keys().eq(got.frames[2].keys()),
            "{label}: the next frame lists the same pages"
        );
        let gpu_groups: Vec<u32> = got.frames[0].keys().copied().collect();
        let cpu_groups: Vec<u32> = want.keys().copied().collect();
        assert_eq!(gpu_groups, cpu_groups, "{label}");
        for (group, &px) in got.frames[0].iter().chain(&got.frames[2]) {
            let (lo, hi) = want[group];
            let slack = 1e-5 * hi.max(1.0);
            assert!(
                px >= lo - slack && px <= hi + slack,
                "{label}: group {group} at {px}, want {lo}..={hi}"
            );
            match px > 0.0 {
                true => listed_missing += 1,
                false => listed_used += 1,
            }
        }
        assert!(got.software + got.hardware > 0, "{label}: nothing drawn");
    }
    assert!(
        listed_missing >= 4 && listed_used >= 10,
        "missing {listed_missing}, used {listed_used}"
    );
}

/// Every page installed: the cull draws the resident scene's cut and asks for nothing
/// missing.
#[test]
fn with_every_page_in_the_cut_is_the_resident_scenes() {
    let mut data = streamed_scene();
    let (mut rng, resident, clusters) = seeded(9, scene_with(&placements()));
    install_some(&mut data, &mut rng, 2.0);
    assert!(
        data.streaming()
            .unwrap()
            .stream_errors
            .iter()
            .all(|&e| e == 0.0)
    );
    let t = Thresholds::default();
    for frame in 0..4 {
        let view = camera_view(&mut rng, frame);
        let streamed = cpu_cull(&data, &view, &clusters, &t, clusters.len() as u32);
        let reference = cpu_cull(&resident, &view, &clusters, &t, clusters.len() as u32);
        assert_eq!(streamed.cut, reference.cut, "frame {frame}");
        let got = run(&mut data, &clusters, &[view], t);
        assert_eq!(
            got.software + got.hardware,
            reference.cut.len(),
            "frame {frame}"
        );
        assert!(
            got.frames[0].values().all(|&px| px == 0.0),
            "a page asked for with all in"
        );
    }
}

/// The streaming slots must come as four, and only to a first pass.
#[test]
fn streaming_slots_bound_by_halves_are_refused() {
    let mut g = GraphBuilder::new();
    let buffer = |g: &mut GraphBuilder, name: &str, e: Element| {
        g.import_buffer(name, BufferDesc::array(e, 64), USAGE)
    };
    let data = streamed_scene();
    let h = meshlight_gpu_scene::gpu::import_for(&data, &mut g);
    let list = buffer(&mut g, "clusters", elements::CLUSTER);
    let count = buffer(&mut g, "cluster_count", Element::U32);
    let raster = buffer(&mut g, "raster_clusters", elements::CLUSTER);
    let marks = buffer(&mut g, "page_marks", Element::U32);
    let counts = g.create_buffer("raster_counts", BufferDesc::array(Element::U32, 8));
    let hw_args = g.create_buffer("hw_args", BufferDesc::array(Element::DRAW_ARGS, 1));
    let out = g
        .add_pass(
            "cull",
            CullLod::default(),
            base_bindings([list, count, h.groups, raster, counts, hw_args])
                .bind("page_marks", marks),
        )
        .unwrap();
    g.export(out.buffer("raster_counts").unwrap());
    let Err(err) = g.compile(&CompileOptions::for_gpu(&gpu())) else {
        panic!("three of the four streaming slots unbound compiled");
    };
    let err = err.to_string();
    assert!(err.contains("bind all four streaming slots"), "{err}");
    assert!(err.contains("1 of them are bound"), "{err}");
}
