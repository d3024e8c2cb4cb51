//! Partitioning clusters into groups of about eight that share many edges, so that the
//! locked border of each group is short and simplification has room to work.

use glam::Vec3;
use rayon::prelude::*;

use crate::error::SceneError;
use crate::mesh::{edge_key, triangle_edges};

/// Target clusters per group.
pub const GROUP_SIZE: usize = 8;
static METIS_LOCK: std::sync::Mutex<()> = std::sync::Mutex::new(());

/// METIS seed: fixed, so the same input gives the same groups.
const METIS_SEED: i32 = 0x6d6c;

/// How clusters are grouped; swappable so the two can be compared on the same input.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Grouping {
    /// meshoptimizer's `partition_clusters` (shared vertices and spatial proximity), the
    /// default. Both groupings meet every DAG target on every test mesh, and this one
    /// takes a quarter of METIS's time (21 against 82 ms on the 8,192 LOD-0 clusters of
    /// the procedural mesh); METIS also runs one call at a time (see `metis_parts`), so
    /// it was the largest serial step of a two-core build.
    #[default]
    Partition,
    /// METIS recursive bisection of the cluster graph, edge weight = shared edges.
    Metis,
}

impl Grouping {
    /// Every grouping, in the order `meshlight bake --help` lists them.
    pub const ALL: [Grouping; 2] = [Grouping::Partition, Grouping::Metis];

    /// The name the command line takes.
    pub fn name(self) -> &'static str {
        match self {
            Grouping::Partition => "partition",
            Grouping::Metis => "metis",
        }
    }

    /// The grouping named `name`, if there is one.
    pub fn parse(name: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|g| g.name() == name)
    }
}

/// Groups `clusters` (triangle lists over position-welded vertex ids, so that copies of
/// one position on a UV seam count as one vertex). Returns the groups as lists of
/// indices into `clusters`, each in ascending order, groups ordered deterministically.
pub fn group_clusters(
    method: Grouping,
    clusters: &[Vec<u32>],
    positions: &[Vec3],
    source: &str,
) -> Result<Vec<Vec<u32>>, SceneError> {
    let n = clusters.len();
    if n <= GROUP_SIZE {
        return Ok(vec![(0..n as u32).collect()]);
    }
    let parts = match method {
        Grouping::Metis => metis_parts(clusters, source)?,
        Grouping::Partition => partition_parts(clusters, positions),
    };
    let count = parts.iter().copied().max().map_or(0, |m| m as usize + 1);
    let mut groups = vec![Vec::new(); count];
    for (cluster, &part) in parts.iter().enumerate() {
        groups[part as usize].push(cluster as u32);
    }
    groups.retain(|g| !g.is_empty());
    Ok(groups)
}

/// The edges of a cluster that no other triangle of the cluster shares: only these can
/// connect it to other clusters, and there are far fewer of them than edges.
fn border_edges(cluster: &[u32], out: &mut Vec<u64>) {
    let mut edges: Vec<u64> = triangle_edges(cluster)
        .map(|(a, b)| edge_key(a, b))
        .collect();
    edges.sort_unstable();
    let mut i = 0;
    while i < edges.len() {
        let mut j = i + 1;
        while j < edges.len() && edges[j] == edges[i] {
            j += 1;
        }
        if j - i == 1 {
            out.push(edges[i]);
        }
        i = j;
    }
}

/// Weighted cluster adjacency in compressed-row form (xadj, adjncy, adjwgt).
pub(crate) fn cluster_graph(clusters: &[Vec<u32>]) -> (Vec<i32>, Vec<i32>, Vec<i32>) {
    let mut tagged: Vec<(u64, u32)> = clusters
        .par_iter()
        .enumerate()
        .flat_map_iter(|(c, cluster)| {
            let mut edges = Vec::new();
            border_edges(cluster, &mut edges);
            edges.into_iter().map(move |e| (e, c as u32))
        })
        .collect();
    tagged.par_sort_unstable();
    let mut pairs: Vec<(u32, u32)> = Vec::new();
    let mut i = 0;
    while i < tagged.len() {
        let mut j = i + 1;
        while j < tagged.len() && tagged[j].0 == tagged[i].0 {
            j += 1;
        }
        // Non-manifold edges can join more than two clusters: connect every pair.
        for a in i..j {
            for b in a + 1..j {
                let (ca, cb) = (tagged[a].1, tagged[b].1);
                if ca != cb {
                    pairs.push((ca, cb));
                    pairs.push((cb, ca));
                }
            }
        }
        i = j;
    }
    pairs.par_sort_unstable();
    let mut xadj = vec![0i32; clusters.len() + 1];
    let mut adjncy = Vec::new();
    let mut adjwgt = Vec::new();
    let mut k = 0;
    while k < pairs.len() {
        let mut m = k + 1;
        while m < pairs.len() && pairs[m] == pairs[k] {
            m += 1;
        }
        xadj[pairs[k].0 as usize + 1] += 1;
        adjncy.push(pairs[k].1 as i32);
        adjwgt.push((m - k) as i32);
        k = m;
    }
    for c in 0..clusters.len() {
        xadj[c + 1] += xadj[c];
    }
    (xadj, adjncy, adjwgt)
}

fn metis_parts(clusters: &[Vec<u32>], source: &str) -> Result<Vec<i32>, SceneError> {
    let (xadj, adjncy, adjwgt) = cluster_graph(clusters);
    let nparts = clusters.len().div_ceil(GROUP_SIZE) as i32;
    let mut part = vec![0i32; clusters.len()];
    let fail = |e: String| SceneError::Build {
        source_name: source.to_owned(),
        reason: format!("METIS could not partition {} clusters: {e}", clusters.len()),
    };
    // Recursive bisection rather than k-way: with a thousand parts k-way gains nothing
    // from coarsening and spends its time in an initial recursive bisection plus
    // refinement. On the 8,192 LOD-0 clusters of the default mesh it took 190 ms against
    // 53 ms, for 3% fewer cut edges (shared edges between groups).
    // METIS keeps its random generator in process-wide statics and re-seeds it at the
    // start of each call; two concurrent calls (two builds in one process) would
    // interleave draws and lose determinism. One call at a time keeps same input → same
    // groups.
    let _serial = METIS_LOCK
        .lock()
        .unwrap_or_else(|poisoned| poisoned.into_inner());
    metis::Graph::new(1, nparts, &xadj, &adjncy)
        .map_err(|e| fail(e.to_string()))?
        .set_adjwgt(&adjwgt)
        .set_option(metis::option::Seed(METIS_SEED))
        .part_recursive(&mut part)
        .map_err(|e| fail(e.to_string()))?;
    Ok(part)
}

fn partition_parts(clusters: &[Vec<u32>], positions: &[Vec3]) -> Vec<i32> {
    let indices: Vec<u32> = clusters.iter().flatten().copied().collect();
    let counts: Vec<u32> = clusters.iter().map(|c| c.len() as u32).collect();
    let adapter = meshopt::VertexDataAdapter::new(bytemuck::cast_slice(positions), 12, 0)
        .expect("Vec3 is 12 bytes");
    let mut dest = vec![0u32; clusters.len()];
    meshopt::partition_clusters_with_positions(&mut dest, &indices, &counts, &adapter, GROUP_SIZE);
    dest.into_iter().map(|p| p as i32).collect()
}
