//! A streamed scene: pages installed and evicted rewrite the records the passes read so
//! that the renderer's own LOD test draws the cut over resident pages, and with every
//! page in, the scene reads as the fully resident one.

use glam::Mat4;
use meshlight_gpu_scene::data::Limits;
use meshlight_gpu_scene::{GpuScene, Material, SceneData};
use meshlight_scene::MeshletAsset;
use meshlight_scene::asset::format::{NO_GROUP, PayloadLayout};
use meshlight_shaders::cpu::layout::View;
use meshlight_shaders::cpu::lod::lod_cut;
use meshlight_stream::{MeshDag, PageGraph, PageId};

/// Two meshes in one scene, so the second's pages and meshlets are rebased.
fn scenes() -> (Vec<&'static MeshletAsset>, SceneData, SceneData) {
    let assets = vec![
        meshlight_testing::meshes::spot(),
        meshlight_testing::meshes::bunny(),
    ];
    let mut resident = SceneData::new(Limits::default());
    let mut streamed = SceneData::streamed(Limits::default());
    for data in [&mut resident, &mut streamed] {
        for (i, asset) in assets.iter().enumerate() {
            data.add_mesh(&format!("mesh{i}"), asset).unwrap();
        }
    }
    let total: u64 = assets
        .iter()
        .map(|a| {
            a.pages()
                .iter()
                .map(|p| u64::from(p.words) * 4)
                .sum::<u64>()
        })
        .sum();
    streamed.reserve_pool(total).unwrap();
    (assets, resident, streamed)
}

/// The scene's page graph: each mesh's appended.
fn graph(assets: &[&MeshletAsset]) -> PageGraph {
    let mut graph = PageGraph::default();
    for asset in assets {
        graph.append(&MeshDag::of_asset(asset).pages());
    }
    graph
}

/// A page's words as the asset file holds them.
fn page_words(assets: &[&MeshletAsset], page: PageId) -> (usize, Vec<u32>) {
    let mut page = page as usize;
    for (mesh, asset) in assets.iter().enumerate() {
        if let Some(record) = asset.pages().get(page) {
            return (mesh, asset.payload()[record.range()].to_vec());
        }
        page -= asset.pages().len();
    }
    panic!("no page {page}");
}

/// Pages in an order that installs parents first.
fn parents_first(graph: &PageGraph) -> Vec<PageId> {
    let mut order: Vec<PageId> = (0..graph.len() as PageId).collect();
    order.sort_by_key(|&p| graph.depth(p));
    order
}

/// Whether each of the scene's meshlets is in its LOD cut, with the renderer's LOD test
/// on the scene's (possibly rewritten) groups, for an instance at the identity.
fn cut(data: &SceneData, view: &View, threshold: f32) -> Vec<bool> {
    data.meshlets
        .iter()
        .map(|m| {
            let (own_sphere, own_error) = data.own_lod(m);
            let (parent_sphere, parent_error) = data.parent_lod(m);
            let identity = Mat4::IDENTITY.to_cols_array_2d();
            lod_cut(
                view,
                &identity,
                1.0,
                own_sphere,
                own_error,
                parent_sphere,
                parent_error,
                threshold,
            )
            .0
        })
        .collect()
}

fn view_from(distance: f32) -> View {
    View {
        camera_position: [0.3, 0.2, distance],
        near: 0.01,
        lod_scale: 540.0,
        ..View::default()
    }
}

#[test]
fn with_every_page_installed_the_scene_reads_as_the_resident_one() {
    let (assets, resident, mut streamed) = scenes();
    let graph = graph(&assets);
    assert_eq!(graph.len(), streamed.groups.len());
    // Nothing installed: only the roots' payload is held, and the cut is the roots.
    let held = streamed.streaming().unwrap().pool_base as usize;
    let roots: usize = assets
        .iter()
        .map(|a| a.header().resident_words as usize)
        .sum();
    assert_eq!(held, roots);
    let view = view_from(0.5);
    let drawn = cut(&streamed, &view, 1.0);
    for (m, record) in streamed.meshlets.iter().enumerate() {
        assert_eq!(drawn[m], record.parent_group == NO_GROUP, "meshlet {m}");
    }
    // Every page, parents first, packed at the pool's start in that order.
    let mut at = 0;
    for page in parents_first(&graph) {
        let (_, words) = page_words(&assets, page);
        streamed.install_page(page, at, &words).unwrap();
        at += words.len() as u32;
    }
    // Each meshlet's payload is where its record points; groups and nodes are the
    // asset's again.
    for (m, (s, r)) in streamed.meshlets.iter().zip(&resident.meshlets).enumerate() {
        let flags = if m < assets[0].meshlets().len() {
            assets[0].header().flags
        } else {
            assets[1].header().flags
        };
        let end = PayloadLayout::of(r, flags).end as usize;
        let (a, b) = (s.data_offset as usize, r.data_offset as usize);
        assert_eq!(
            streamed.payload[a..a + end],
            resident.payload[b..b + end],
            "meshlet {m}"
        );
        assert_eq!(
            MeshletRecordKey::of(s),
            MeshletRecordKey::of(r),
            "meshlet {m}"
        );
    }
    assert_eq!(streamed.groups, resident.groups);
    assert_eq!(streamed.hierarchy_nodes, resident.hierarchy_nodes);
    for distance in [0.2, 0.5, 1.0, 3.0, 10.0] {
        let view = view_from(distance);
        assert_eq!(
            cut(&streamed, &view, 1.0),
            cut(&resident, &view, 1.0),
            "at {distance}"
        );
    }
    assert!(
        streamed
            .streaming()
            .unwrap()
            .stream_errors
            .iter()
            .all(|&e| e == 0.0)
    );
}

/// The scene meshlets below hierarchy node `i` (a leaf's, or its descendants').
fn node_meshlets(data: &SceneData, i: usize) -> Vec<u32> {
    let node = data.hierarchy_nodes[i];
    if node.is_leaf() {
        return data.hierarchy_clusters[node.clusters()].to_vec();
    }
    node.children()
        .flat_map(|c| node_meshlets(data, c))
        .collect()
}

/// Everything of a meshlet record but its payload offset.
#[derive(Debug, PartialEq)]
struct MeshletRecordKey([f32; 4], u32, u32, u32, [u32; 3], u32, u32);

impl MeshletRecordKey {
    fn of(m: &meshlight_scene::asset::format::MeshletRecord) -> Self {
        Self(
            m.bounds,
            m.source_group,
            m.parent_group,
            m.counts,
            m.grid_min,
            m.bits,
            m.normals,
        )
    }
}

/// Under random residency closed under parents, the renderer's LOD test on the rewritten
/// records draws exactly the cut over resident pages, and that cut is complete.
#[test]
fn the_rewritten_records_draw_the_cut_over_resident_pages() {
    let (assets, _, mut streamed) = scenes();
    let graph = graph(&assets);
    let dags: Vec<MeshDag> = assets.iter().map(|a| MeshDag::of_asset(a)).collect();
    let mut rng = meshlight_testing::Rng(5);
    let mut resident = vec![false; graph.len()];
    // Each page at its own range of the pool (it holds them all).
    let slots: Vec<u32> = (0..graph.len() as PageId)
        .scan(0u32, |at, p| {
            let slot = *at;
            *at += (graph.bytes(p) / 4) as u32;
            Some(slot)
        })
        .collect();
    let (mut paged, mut fallbacks) = (0, 0);
    for round in 0..40 {
        // Install a few pages whose parents are in, evict a few that nothing needs.
        for page in parents_first(&graph) {
            let p = page as usize;
            let parents_in = graph.parents(page).iter().all(|&q| resident[q as usize]);
            if !resident[p] && parents_in && rng.below(3) == 0 {
                let (_, words) = page_words(&assets, page);
                streamed.install_page(page, slots[p], &words).unwrap();
                resident[p] = true;
            } else if resident[p]
                && graph
                    .dependents(page)
                    .iter()
                    .all(|&d| !resident[d as usize])
                && rng.below(4) == 0
            {
                streamed.evict_page(page).unwrap();
                resident[p] = false;
            }
        }
        // Every node's smallest own error bounds the meshlets below as the GPU sees them.
        for (i, node) in streamed.hierarchy_nodes.iter().enumerate() {
            let min = node_meshlets(&streamed, i)
                .iter()
                .map(|&m| streamed.own_lod(&streamed.meshlets[m as usize]).1)
                .fold(f32::INFINITY, f32::min);
            assert_eq!(node.min_error, min, "round {round}, node {i}");
        }
        let view = view_from(0.2 + round as f32 * 0.1);
        let drawn = cut(&streamed, &view, 1.0);
        let mut first_meshlet = 0;
        let mut first_group = 0;
        for (asset, dag) in assets.iter().zip(&dags) {
            let n = asset.meshlets().len();
            let groups = asset.groups().len();
            let shows: Vec<bool> = asset
                .groups()
                .iter()
                .map(|g| {
                    let s = g.lod_sphere;
                    let px = meshlight_shaders::cpu::lod::project_error_to_pixels(
                        &view,
                        [s[0], s[1], s[2]],
                        s[3],
                        g.error,
                    );
                    meshlight_shaders::cpu::lod::error_perceptible(px, 1.0)
                })
                .collect();
            let is_resident = |g: u32| resident[first_group + g as usize];
            let want = meshlight_stream::cut::select(dag, &shows, is_resident);
            assert_eq!(
                &drawn[first_meshlet..first_meshlet + n],
                &want[..],
                "round {round}"
            );
            // How often the cut drew a page's meshlets, and how often it fell back to a
            // coarser one because the finer page was missing.
            for (m, &d) in want.iter().enumerate() {
                let (source, parent) = (dag.source[m], dag.parent[m]);
                paged += usize::from(d && parent != NO_GROUP);
                fallbacks += usize::from(
                    d && source != NO_GROUP && shows[source as usize] && !is_resident(source),
                );
            }
            meshlight_stream::cut::check(dag, &want, is_resident).unwrap();
            first_meshlet += n;
            first_group += groups;
        }
    }
    assert!(
        paged > 1000 && fallbacks > 100,
        "{paged} paged, {fallbacks} fallbacks"
    );
}

/// The streamed scene with one instance of its first mesh, uploaded.
fn uploaded(
    gpu: &meshlight_graph::GpuContext,
) -> (Vec<&'static MeshletAsset>, SceneData, GpuScene) {
    let (assets, _, mut streamed) = scenes();
    let material = streamed.add_material(Material::default()).unwrap();
    streamed
        .add_instance(meshlight_gpu_scene::MeshId(0), Mat4::IDENTITY, material)
        .unwrap();
    let scene = GpuScene::new(gpu, &mut streamed);
    (assets, streamed, scene)
}

/// Installs and evictions reach the GPU as small writes, and the GPU's copies then
/// equal the scene's.
#[test]
fn installs_and_evictions_upload_only_what_they_change() {
    let gpu = meshlight_testing::gpu();
    let (assets, mut streamed, mut scene) = uploaded(&gpu);
    assert_eq!(scene.upload(&gpu, &mut streamed).bytes, 0);
    let graph = graph(&assets);
    let page = parents_first(&graph)[0];
    let (_, words) = page_words(&assets, page);
    let nodes_before = streamed.hierarchy_nodes.clone();
    streamed.install_page(page, 64, &words).unwrap();
    let stats = scene.upload(&gpu, &mut streamed);
    let info = streamed.streaming().unwrap().pages[page as usize].clone();
    // The nodes written: the page's leaf and those whose smallest own error changed.
    let changed = |before: &[meshlight_scene::asset::format::NodeRecord], data: &SceneData| {
        (data.hierarchy_nodes.iter().zip(before))
            .enumerate()
            .filter(|&(i, (a, b))| a != b || i == info.leaf as usize)
            .count() as u64
    };
    let node_bytes = size_of::<meshlight_scene::asset::format::NodeRecord>() as u64;
    let records = u64::from(info.meshlet_count)
        * size_of::<meshlight_scene::asset::format::MeshletRecord>() as u64
        + size_of::<meshlight_scene::asset::format::GroupRecord>() as u64
        + 4;
    let nodes = changed(&nodes_before, &streamed);
    assert!(nodes >= 2, "the install changed {nodes} nodes");
    let expected = words.len() as u64 * 4 + records + nodes * node_bytes;
    assert_eq!((stats.bytes, stats.created), (expected, 0));
    assert_streamed_buffers_match(&gpu, &scene, &streamed, "after the install");
    let nodes_before = streamed.hierarchy_nodes.clone();
    streamed.evict_page(page).unwrap();
    let stats = scene.upload(&gpu, &mut streamed);
    let nodes = changed(&nodes_before, &streamed);
    assert_eq!(stats.bytes, records + nodes * node_bytes);
    let groups = gpu
        .read_buffer(
            scene.buffer("meshlet_groups").unwrap(),
            0,
            32 * streamed.groups.len() as u64,
        )
        .unwrap();
    assert_eq!(&groups[..], bytemuck::cast_slice::<_, u8>(&streamed.groups));
}

/// Each streamed buffer of the GPU's copy equals the scene's (the CPU reference of
/// the dispatch that writes streaming's changes).
fn assert_streamed_buffers_match(
    gpu: &meshlight_graph::GpuContext,
    scene: &GpuScene,
    data: &SceneData,
    when: &str,
) {
    for name in [
        "payload",
        "meshlets",
        "meshlet_groups",
        "hierarchy_nodes",
        "stream_errors",
    ] {
        let buffer = scene.buffer(name).unwrap();
        let got = gpu.read_buffer(buffer, 0, buffer.size()).unwrap();
        let want: Vec<u8> = match name {
            "payload" => bytemuck::cast_slice(&data.payload).to_vec(),
            "meshlets" => bytemuck::cast_slice(&data.meshlets).to_vec(),
            "meshlet_groups" => bytemuck::cast_slice(&data.groups).to_vec(),
            "hierarchy_nodes" => bytemuck::cast_slice(&data.hierarchy_nodes).to_vec(),
            _ => bytemuck::cast_slice(&data.streaming().unwrap().stream_errors).to_vec(),
        };
        assert!(got[..want.len()] == want[..], "{name} differs {when}");
    }
}

/// Many pages installed, evicted and installed again elsewhere, frame after frame
/// (hundreds of ranges in one upload): the GPU's buffers follow the scene's exactly.
#[test]
fn many_installs_and_evictions_a_frame_reach_the_gpu_exactly() {
    let gpu = meshlight_testing::gpu();
    let (assets, mut streamed, mut scene) = uploaded(&gpu);
    let graph = graph(&assets);
    let order = parents_first(&graph);
    let pool = streamed.streaming().unwrap().pool_words;
    let mut rng = meshlight_testing::Rng(11);
    let mut resident: Vec<PageId> = Vec::new();
    let (mut installs, mut at) = (0, 0u32);
    for frame in 0..8 {
        // Evict pages nothing resident needs (the deepest first), then install pages
        // not resident in parents-first order, at offsets spread over the pool.
        resident.sort_by_key(|&p| std::cmp::Reverse(graph.depth(p)));
        let evict = resident.len().min(30 + rng.below(60) as usize);
        for page in resident.drain(..evict) {
            streamed.evict_page(page).unwrap();
        }
        let count = 40 + rng.below(120) as usize;
        let absent: Vec<PageId> = (order.iter())
            .filter(|p| !resident.contains(p))
            .take(count)
            .copied()
            .collect();
        for page in absent {
            let (_, words) = page_words(&assets, page);
            if at + words.len() as u32 > pool {
                at = 0;
            }
            streamed.install_page(page, at, &words).unwrap();
            at += words.len() as u32 + rng.below(8) * 4;
            resident.push(page);
            installs += 1;
        }
        scene.upload(&gpu, &mut streamed);
        assert_streamed_buffers_match(&gpu, &scene, &streamed, &format!("after frame {frame}"));
    }
    assert!(installs > 400, "only {installs} installs");
}

/// The scene's pages name the same parents as the stream crate's page graph.
#[test]
fn the_scenes_pages_need_what_the_page_graph_says() {
    let (assets, _, streamed) = scenes();
    let graph = graph(&assets);
    for (g, page) in streamed.streaming().unwrap().pages.iter().enumerate() {
        assert_eq!(page.parents, graph.parents(g as PageId), "page {g}");
        assert_eq!(
            u64::from(page.words) * 4,
            graph.bytes(g as PageId),
            "page {g}"
        );
    }
}

#[test]
fn bad_streaming_calls_are_refused_by_name() {
    let (assets, mut resident, mut streamed) = scenes();
    let err = resident.install_page(0, 0, &[]).unwrap_err().to_string();
    assert!(err.contains("does not stream"), "{err}");
    let err = streamed
        .install_page(1 << 30, 0, &[])
        .unwrap_err()
        .to_string();
    assert!(err.contains("page 1073741824 does not exist"), "{err}");
    let (_, words) = page_words(&assets, 0);
    let err = streamed
        .install_page(0, 0, &words[1..])
        .unwrap_err()
        .to_string();
    assert!(
        err.contains(&format!(
            "has {} words, {} were given",
            words.len(),
            words.len() - 1
        )),
        "{err}"
    );
    let pool = streamed.streaming().unwrap().pool_words;
    let err = streamed
        .install_page(0, pool - 1, &words)
        .unwrap_err()
        .to_string();
    assert!(err.contains("runs past the pool"), "{err}");
    let err = streamed.reserve_pool(1024).unwrap_err().to_string();
    assert!(err.contains("already reserved"), "{err}");
    let err = resident.reserve_pool(1024).unwrap_err().to_string();
    assert!(err.contains("does not stream"), "{err}");
    // An asset opened for streaming holds its resident part only: a resident scene
    // refuses it, a streamed one takes it.
    let dir = std::env::temp_dir().join(format!("meshlight-gpu-scene-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("spot.mlasset");
    assets[0].save(&path).unwrap();
    let opened = MeshletAsset::open_resident(&path).unwrap();
    let err = resident
        .add_mesh("opened", &opened)
        .unwrap_err()
        .to_string();
    assert!(err.contains("opened for streaming"), "{err}");
    let mut fresh = SceneData::streamed(Limits::default());
    fresh.add_mesh("opened", &opened).unwrap();
    std::fs::remove_dir_all(&dir).unwrap();
}
