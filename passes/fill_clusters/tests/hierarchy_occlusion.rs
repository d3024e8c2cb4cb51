//! The `hierarchy` walk with occlusion on the GPU against `cpu_walk_with`: the second
//! walk (`mode = "second"`, this frame's pyramid) started from every instance's root,
//! on seeded random views with random walls of depth in front of the instances. The
//! list (as a set), the node counters and the count of hidden nodes must equal the
//! reference's, apart from nodes whose test lies within rounding of a threshold. The
//! first walk runs the same node test through the previous transforms; the frame-level
//! test `apps/virtual_geometry/tests/occlusion.rs` covers it end to end (no false culling).

mod support;

use glam::Vec3;
use meshlight_gpu_scene::gpu::elements;
use meshlight_gpu_scene::{Camera, GpuScene, Phase, SceneData};
use meshlight_graph::*;
use meshlight_pass_fill_clusters::hierarchy::{OCCLUSION_COUNT_WORDS, OCCLUSION_MIN_CLUSTERS};
use meshlight_pass_fill_clusters::{
    HIDDEN_NODE, HierarchyFill, WalkOcclusion, WalkParams, cpu_walk_with,
};
use meshlight_shaders::cpu::layout::{Cluster, View};
use meshlight_shaders::cpu::occlusion::DepthPyramid;
use meshlight_testing::{texture, write_pyramid};
use support::run::words;
use support::scenes::{field, walls};
use support::*;

const VIEWPORT: [u32; 2] = [320, 200];
const NEAR_THRESHOLD: f32 = 1e-5;

/// A 5 × 4 field of bunnies.
fn scene() -> SceneData {
    field(&[("bunny", bunny())], 20, |i| {
        let (x, z) = ((i % 5) as f32, (i / 5) as f32);
        let scale = Vec3::splat(0.6 + 0.1 * (i % 4) as f32);
        (scale, i as f32 * 0.7, Vec3::new(x * 2.5, 0.0, z * 2.5))
    })
}

fn random_view(data: &SceneData, rng: &mut Rng, v: u32) -> View {
    let radius = data.meshes[0].bounding_sphere[3];
    let target = Vec3::new(rng.range(3.0, 7.0), 0.0, rng.range(2.0, 5.0)) * radius;
    let direction = Vec3::new(
        rng.range(-1.0, 1.0),
        rng.range(0.2, 1.0),
        rng.range(-1.0, 1.0),
    )
    .normalize_or(Vec3::Y);
    let camera = Camera::perspective(
        target + direction * radius * rng.range(8.0, 20.0),
        target,
        1.0,
        radius * 0.05,
    );
    camera.view(VIEWPORT, v, None)
}

/// What the second walk left on the GPU.
struct Walked {
    clusters: Vec<Cluster>,
    counts: Vec<u32>,
}

fn run_second_walk(
    data: &mut SceneData,
    view: &View,
    pyramid: &DepthPyramid,
    nodes: &[(u32, u32)],
    occlusion_min_clusters: u32,
) -> Walked {
    let gpu = gpu();
    let scene = GpuScene::new(&gpu, data);
    let slots = 1 << 16;
    let mut g = GraphBuilder::new();
    scene.import(&mut g);
    scene.import_hierarchy(&mut g);
    g.create_buffer("clusters", BufferDesc::array(elements::CLUSTER, slots));
    g.create_buffer("cluster_count", BufferDesc::array(Element::U32, 2));
    g.create_buffer(
        "hierarchy_counts",
        BufferDesc::array(Element::U32, OCCLUSION_COUNT_WORDS),
    );
    let node_words: Vec<u32> = nodes.iter().flat_map(|&(i, n)| [i, n, 1]).collect();
    let node_list = g.import_buffer(
        "node_list",
        BufferDesc::array(HIDDEN_NODE, nodes.len().max(1) as u64),
        USAGE,
    );
    let node_count = g.import_buffer("node_count", BufferDesc::array(Element::U32, 2), USAGE);
    let (w, h0, _) = pyramid.levels[0];
    let levels = pyramid.levels.len() as u32;
    let desc = TextureDesc::d2(
        wgpu::TextureFormat::R32Float,
        w.next_power_of_two(),
        h0.next_power_of_two(),
    )
    .with_mips(levels);
    let usage = wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST;
    let pyramid_handle = g.import_texture("pyramid_now", desc.clone(), usage);
    let walk = HierarchyFill {
        phase: Phase::Second,
        occlusion_min_clusters,
        ..HierarchyFill::default()
    };
    let out = g
        .add_pass(
            "fill_second",
            walk,
            Bindings::new()
                .bind("pyramid", pyramid_handle)
                .bind("candidate_nodes", node_list)
                .bind("candidate_node_count", node_count),
        )
        .unwrap();
    for name in ["clusters", "cluster_count", "hierarchy_counts"] {
        g.export(out.buffer(name).unwrap());
    }
    let compiled = g.compile(&CompileOptions::for_gpu(&gpu)).unwrap();
    let nodes_buffer = gpu.buffer_with_data("node_list", bytemuck::cast_slice(&node_words), USAGE);
    let n = nodes.len() as u32;
    let count_buffer = gpu.buffer_with_data("node_count", bytemuck::cast_slice(&[n, n]), USAGE);
    let texture = texture(&gpu, "pyramid_now", &desc, usage);
    write_pyramid(&gpu.queue, &texture, pyramid);
    let mut exec = Executor::new(gpu);
    let imports = scene
        .imports()
        .buffer("node_list", &nodes_buffer)
        .buffer("node_count", &count_buffer)
        .texture("pyramid_now", &texture);
    let frame = FrameData::new().with("view", bytemuck::bytes_of(view));
    exec.execute_frame(&compiled, &imports, &frame).unwrap();
    let cluster_count = words(&mut exec, "cluster_count");
    assert_eq!(cluster_count[0], cluster_count[1], "the list overflowed");
    let all: Vec<Cluster> = bytemuck::pod_collect_to_vec(&exec.read_buffer("clusters").unwrap());
    Walked {
        clusters: all[..cluster_count[0] as usize].to_vec(),
        counts: words(&mut exec, "hierarchy_counts"),
    }
}

#[test]
fn the_second_walk_matches_the_reference_on_random_views_and_walls() {
    let mut data = scene();
    let mut rng = Rng(0x0cc1_0de5);
    let roots: Vec<(u32, u32)> = data
        .instances
        .iter()
        .enumerate()
        .map(|(i, inst)| (i as u32, data.hierarchy_roots[inst.mesh as usize]))
        .collect();
    let (mut hidden, mut compared) = (0, 0);
    for v in 0..8 {
        let view = random_view(&data, &mut rng, v);
        let count = 1 + rng.below(4);
        let pyramid = walls(&mut rng, &data, &view, VIEWPORT, count);
        // Every node tested, nodes of 64 meshlets and more, or the default's (the
        // walk's entries alone), in turn.
        let min = [0, 64, OCCLUSION_MIN_CLUSTERS][v as usize % 3];
        let params = WalkParams {
            occlusion_min_clusters: min,
            ..WalkParams::default()
        };
        let want = cpu_walk_with(
            &data,
            &view,
            &params,
            NEAR_THRESHOLD,
            WalkOcclusion::Second {
                pyramid: &pyramid,
                nodes: &roots,
            },
        );
        let got = run_second_walk(&mut data, &view, &pyramid, &roots, min);
        // Instances with a decision within rounding are left out of the comparison.
        let near: std::collections::BTreeSet<u32> =
            want.near_threshold.iter().map(|&(i, _)| i).collect();
        let kept = |clusters: &[Cluster]| {
            let mut kept = set(clusters);
            kept.retain(|(instance, _)| !near.contains(instance));
            kept
        };
        assert_eq!(
            kept(&got.clusters),
            kept(&want.clusters),
            "view {v}: the listed clusters differ"
        );
        assert_eq!(
            got.clusters.len(),
            set(&got.clusters).len(),
            "view {v}: a cluster twice"
        );
        if near.is_empty() {
            assert_eq!(
                (got.counts[0], got.counts[1], got.counts[4]),
                (
                    want.counts[0],
                    want.counts[1],
                    want.hidden_nodes.len() as u32
                ),
                "view {v}: nodes tested, leaves accepted, nodes hidden"
            );
            compared += 1;
        }
        hidden += want.hidden_nodes.len();
    }
    // The walls hid something, and the counters were compared on most views.
    assert!(hidden > 0, "no node was hidden on any view");
    assert!(
        compared >= 3,
        "only {compared} views without near decisions"
    );
}
