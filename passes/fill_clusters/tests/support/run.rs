//! One frame of a fill on the GPU over a sentinel-filled list, with `cull_lod` after it
//! when asked, and what it left.

use super::graph::{add_cull, add_fill};
use super::{SENTINEL, USAGE, gpu};
use meshlight_gpu_scene::gpu::elements;
use meshlight_gpu_scene::{GpuScene, SceneData};
use meshlight_graph::{BufferDesc, CompileOptions, Executor, FrameData, GraphBuilder, Pass};
use meshlight_pass_cull_lod::{CullLod, Thresholds};
use meshlight_shaders::cpu::layout::{Cluster, View};
use std::collections::BTreeSet;

/// What one frame left: the fill's list and words, and the cut when cull ran after it.
pub struct Frame {
    /// The whole list buffer: the slots the fill may write, then any guard.
    pub list: Vec<Cluster>,
    pub cluster_count: [u32; 2],
    /// `hierarchy_counts` (zeros for the flat fill).
    pub counts: [u32; 4],
    /// Software and hardware sides of cull's raster list.
    pub cut: Option<BTreeSet<(u32, u32)>>,
}

impl Frame {
    /// The clusters written.
    pub fn listed(&self) -> &[Cluster] {
        &self.list[..self.cluster_count[0] as usize]
    }

    /// The first `capacity` slots, after checking that the fill wrote every one of them
    /// and none past them.
    pub fn filled_to(&self, capacity: u32) -> &[Cluster] {
        let (written, past) = self.list.split_at(capacity as usize);
        assert!(
            written.iter().all(|c| *c != SENTINEL),
            "a slot below the capacity was left unwritten"
        );
        assert!(
            past.iter().all(|c| *c == SENTINEL),
            "a slot past the capacity was written"
        );
        written
    }
}

/// `cull_lod` after the fill: its threshold, and the clusters its raster list holds.
#[derive(Clone, Copy)]
pub struct Cull {
    pub threshold: f32,
    pub slots: u32,
}

/// Runs `fill` (and `cull` after it) for one view over a list of `list_len` slots, each
/// holding the sentinel before the frame.
pub fn run_fill(
    data: &mut SceneData,
    view: &View,
    fill: Box<dyn Pass>,
    list_len: u32,
    cull: Option<Cull>,
) -> Frame {
    let gpu = gpu();
    let scene = GpuScene::new(&gpu, data);
    let mut g = GraphBuilder::new();
    g.import_buffer(
        "clusters",
        BufferDesc::array(elements::CLUSTER, list_len as u64),
        USAGE,
    );
    let walks = add_fill(&mut g, &scene, fill).unwrap();
    if let Some(Cull { threshold, slots }) = cull {
        let pass = CullLod {
            thresholds: Thresholds {
                lod_threshold_px: threshold,
                ..Thresholds::default()
            },
            ..CullLod::default()
        };
        let culled = add_cull(&mut g, pass, slots as u64).unwrap();
        g.export(culled.buffer("raster_clusters").unwrap());
    }
    let compiled = g.compile(&CompileOptions::for_gpu(&gpu)).unwrap();
    let list_buffer = gpu.buffer_with_data(
        "clusters",
        bytemuck::cast_slice(&vec![SENTINEL; list_len as usize]),
        USAGE,
    );
    let mut exec = Executor::new(gpu);
    let frame = FrameData::new().with("view", bytemuck::bytes_of(view));
    exec.execute_frame(
        &compiled,
        &scene.imports().buffer("clusters", &list_buffer),
        &frame,
    )
    .unwrap();
    let cluster_count = words(&mut exec, "cluster_count");
    let counts = if walks {
        words(&mut exec, "hierarchy_counts")
    } else {
        vec![0; 4]
    };
    let cut = cull.map(|Cull { slots, .. }| {
        let raster: Vec<Cluster> =
            bytemuck::pod_collect_to_vec(&exec.read_buffer("raster_clusters").unwrap());
        let c = words(&mut exec, "raster_counts");
        let (sw, hw, total) = (c[0] as usize, c[1] as usize, c[2] as usize);
        assert!(total <= slots as usize, "the raster list overflowed");
        raster[..sw]
            .iter()
            .chain(&raster[slots as usize - hw..])
            .map(|c| (c.instance, c.meshlet))
            .collect()
    });
    // The list is imported: read the caller's buffer (after the words, so the frame ran).
    let list = bytemuck::pod_collect_to_vec(
        &exec
            .gpu
            .read_buffer(&list_buffer, 0, list_buffer.size())
            .unwrap(),
    );
    Frame {
        list,
        cluster_count: [cluster_count[0], cluster_count[1]],
        counts: counts[..4].try_into().unwrap(),
        cut,
    }
}

/// The u32 words of the exported buffer `name`.
pub fn words(exec: &mut Executor, name: &str) -> Vec<u32> {
    bytemuck::pod_collect_to_vec(&exec.read_buffer(name).unwrap())
}
