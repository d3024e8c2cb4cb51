//! The counters a frame leaves on the GPU, read back asynchronously: how many clusters
//! were considered, survived culling, went to each rasteriser, and whether a list was
//! too small.

use serde::Serialize;

/// The readback of `fill_clusters`' `cluster_count` (words: written, requested).
pub const CLUSTER_COUNT_READBACK: &str = "cluster_count";
/// The readback of `cull_lod`'s `raster_counts` (eight words, twelve with occlusion;
/// see that crate).
pub const RASTER_COUNTS_READBACK: &str = "raster_counts";
/// The readback of the second culling pass's `raster_counts` (twelve words).
pub const SECOND_COUNTS_READBACK: &str = "raster_counts_second";
/// The readback of the hierarchy walk's `hierarchy_counts` (four words, five with
/// occlusion; see `fill_clusters`' `hierarchy`).
pub const HIERARCHY_COUNTS_READBACK: &str = "hierarchy_counts";
/// The readback of the second walk's counters (five words).
pub const SECOND_HIERARCHY_COUNTS_READBACK: &str = "hierarchy_counts_second";
/// The readback of the second walk's list count (written, requested).
pub const SECOND_WALK_COUNT_READBACK: &str = "second_walk_count";

/// One frame's counters.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
pub struct FrameCounts {
    /// The frame they belong to.
    pub frame: u64,
    /// Candidates `fill_clusters` asked for (every level of every instance in view).
    pub clusters_requested: u32,
    /// Candidates the list held, so the clusters `cull_lod` considered.
    pub clusters_considered: u32,
    /// Clusters whose bounding sphere touched the frustum.
    pub in_frustum: u32,
    /// Clusters in the LOD cut (each asks for a raster slot).
    pub visible: u32,
    /// The raster slots there were.
    pub slots: u32,
    /// Clusters drawn by each rasteriser.
    pub software: u32,
    /// See `software`.
    pub hardware: u32,
    /// Triangles of those clusters.
    pub software_triangles: u32,
    /// See `software_triangles`.
    pub hardware_triangles: u32,
    /// Clusters the raster slots had no room for (both culling passes).
    pub slots_dropped: u32,
    /// The two culling passes' occlusion counters; `None` for a one-pass frame.
    pub occlusion: Option<OcclusionCounts>,
    /// The hierarchy walk's counters; `None` when `fill` visits every cluster.
    pub hierarchy: Option<HierarchyCounts>,
}

/// What the walk of the culling hierarchy did in one frame (`fill_clusters`'
/// `hierarchy`): the work that replaces testing every cluster of every instance.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
pub struct HierarchyCounts {
    /// Nodes whose bounds were tested (a culled instance costs one).
    pub nodes_tested: u32,
    /// Leaves (groups) accepted, whose clusters became candidates.
    pub leaves_accepted: u32,
    /// Subtrees emitted whole because the walk's queue was full (costs pruning only).
    pub subtrees_whole: u32,
    /// Walks that did not finish (0 unless a list overflowed).
    pub unfinished: u32,
    /// Nodes last frame's pyramid hid, handed to the second walk (0 without
    /// occlusion).
    pub hidden_nodes: u32,
    /// Instances whose root was tested, and those whose root passed the frustum (and,
    /// with occlusion, last frame's pyramid): `None` when the counters' buffer has no
    /// room for them.
    pub instances: Option<InstanceCounts>,
    /// The second walk, from those nodes against this frame's pyramid (two-pass
    /// frames).
    pub second: Option<SecondWalkCounts>,
}

/// Instances the hierarchy walk tested at their root, and those it went on into.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
pub struct InstanceCounts {
    /// Instances whose root the walk tested.
    pub tested: u32,
    /// Instances it went on into (in the frustum, not hidden).
    pub visible: u32,
}

/// What the second walk of the hierarchy did: the nodes the first found hidden,
/// re-tested against this frame's pyramid.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
pub struct SecondWalkCounts {
    /// Nodes the second walk tested.
    pub nodes_tested: u32,
    /// Leaves whose clusters it listed.
    pub leaves_accepted: u32,
    /// Nodes still hidden: culled for good, with everything below them.
    pub still_hidden: u32,
    /// Clusters the walk listed for the second culling pass, and asked for.
    pub clusters_listed: u32,
    /// See `clusters_listed`.
    pub clusters_requested: u32,
}

impl HierarchyCounts {
    /// From the readback's bytes; `None` when shorter than four words. A fifth word is
    /// the hidden-node count; the sixth and seventh, the walk's entries tested and
    /// passed (`fill_clusters::hierarchy::ENTRY_COUNT_WORDS`).
    pub fn from_words(bytes: &[u8]) -> Option<Self> {
        let w: Vec<u32> =
            (bytes.len() >= 16).then(|| bytemuck::pod_collect_to_vec(&bytes[..16]))?;
        let hidden_nodes = match bytes.get(16..20) {
            Some(word) => bytemuck::pod_read_unaligned::<u32>(word),
            None => 0,
        };
        Some(Self {
            nodes_tested: w[0],
            leaves_accepted: w[1],
            subtrees_whole: w[2],
            unfinished: w[3],
            hidden_nodes,
            instances: bytes.get(20..28).map(|w| {
                let [tested, visible]: [u32; 2] = bytemuck::pod_read_unaligned(w);
                InstanceCounts { tested, visible }
            }),
            second: None,
        })
    }

    /// The second walk's counters from its two readbacks; `None` when one is short.
    pub fn with_second(mut self, counts: &[u8], list: &[u8]) -> Option<Self> {
        let c = Self::from_words(counts)?;
        let l: Vec<u32> = (list.len() >= 8).then(|| bytemuck::pod_collect_to_vec(&list[..8]))?;
        self.second = Some(SecondWalkCounts {
            nodes_tested: c.nodes_tested,
            leaves_accepted: c.leaves_accepted,
            still_hidden: c.hidden_nodes,
            clusters_listed: l[0],
            clusters_requested: l[1],
        });
        Some(self)
    }
}

/// What two-pass occlusion culling did in one frame. The totals of [`FrameCounts`]
/// (`visible`, `software`, `hardware`, triangles) include the second pass.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
pub struct OcclusionCounts {
    /// First pass: clusters in the LOD cut and those whose sphere could be tested
    /// against last frame's pyramid (both 0 without valid history or on a camera cut,
    /// when nothing is tested), and those it hid (the second pass's candidates).
    pub first_cut: u32,
    /// See `first_cut`.
    pub first_tested: u32,
    /// See `first_cut`.
    pub first_occluded: u32,
    /// Second pass: candidates considered, tested against this frame's pyramid, still
    /// hidden (culled for good), and drawn.
    pub second_considered: u32,
    /// See `second_considered`.
    pub second_tested: u32,
    /// See `second_considered`.
    pub second_occluded: u32,
    /// See `second_considered`.
    pub second_drawn: u32,
    /// Triangles of the clusters the second pass drew.
    pub second_triangles: u32,
}

impl FrameCounts {
    /// From the readbacks' bytes (`second`: the second culling pass's, in a two-pass
    /// frame); `None` when one is shorter than its words.
    pub fn from_words(
        frame: u64,
        cluster_count: &[u8],
        raster_counts: &[u8],
        second: Option<&[u8]>,
    ) -> Option<Self> {
        let words = |bytes: &[u8], n: usize| -> Option<Vec<u32>> {
            (bytes.len() >= n * 4).then(|| bytemuck::pod_collect_to_vec(&bytes[..n * 4]))
        };
        let c = words(cluster_count, 2)?;
        let r = words(raster_counts, 8)?;
        let mut counts = Self {
            frame,
            clusters_considered: c[0],
            clusters_requested: c[1],
            software: r[0],
            hardware: r[1],
            visible: r[2],
            slots: r[3],
            in_frustum: r[4],
            software_triangles: r[5],
            hardware_triangles: r[6],
            slots_dropped: r[2].saturating_sub(r[3]),
            occlusion: None,
            hierarchy: None,
        };
        if let Some(second) = second {
            let r = words(raster_counts, 12)?;
            let s = words(second, 12)?;
            counts.slots = r[10];
            counts.slots_dropped = r[2].saturating_sub(r[10]) + s[2].saturating_sub(s[10]);
            counts.visible += s[2];
            counts.software += s[0];
            counts.hardware += s[1];
            counts.software_triangles += s[5];
            counts.hardware_triangles += s[6];
            counts.occlusion = Some(OcclusionCounts {
                first_cut: r[8],
                first_tested: r[11],
                first_occluded: r[9],
                second_considered: s[4],
                second_tested: s[11],
                second_occluded: s[9],
                second_drawn: s[0] + s[1],
                second_triangles: s[5] + s[6],
            });
        }
        Some(counts)
    }

    /// Candidates the cluster list had no room for.
    pub fn clusters_dropped(&self) -> u32 {
        self.clusters_requested
            .saturating_sub(self.clusters_considered)
    }

    /// Visible clusters the raster slots had no room for.
    pub fn slots_dropped(&self) -> u32 {
        self.slots_dropped
    }

    /// Whether anything was dropped: the frame's image may miss geometry.
    pub fn overflowed(&self) -> bool {
        self.clusters_dropped() > 0 || self.slots_dropped() > 0
    }

    /// Triangles both rasterisers drew.
    pub fn triangles(&self) -> u64 {
        self.software_triangles as u64 + self.hardware_triangles as u64
    }

    /// Rows of `(label, value)` for reports.
    pub fn rows(&self) -> Vec<(&'static str, u64)> {
        let mut rows = self.totals();
        if let Some(h) = self.hierarchy {
            let second = h.second.unwrap_or_default();
            if let Some(i) = h.instances {
                rows.extend([
                    ("instances tested", i.tested as u64),
                    ("instances visible", i.visible as u64),
                ]);
            }
            rows.extend([
                ("hierarchy: nodes tested", h.nodes_tested as u64),
                ("hierarchy: leaves accepted", h.leaves_accepted as u64),
                (
                    "hierarchy: nodes + candidate clusters tested",
                    (h.nodes_tested + second.nodes_tested) as u64
                        + (self.clusters_considered + second.clusters_listed) as u64,
                ),
            ]);
            if h.second.is_some() {
                rows.extend([
                    ("first walk: nodes hidden", h.hidden_nodes as u64),
                    ("second walk: nodes tested", second.nodes_tested as u64),
                    (
                        "second walk: nodes still hidden",
                        second.still_hidden as u64,
                    ),
                    (
                        "second walk: clusters listed",
                        second.clusters_listed as u64,
                    ),
                ]);
            }
        }
        if let Some(o) = self.occlusion {
            rows.extend([
                ("first pass: clusters in the LOD cut", o.first_cut as u64),
                ("first pass: tested for occlusion", o.first_tested as u64),
                ("first pass: occluded (candidates)", o.first_occluded as u64),
                (
                    "second pass: candidates considered",
                    o.second_considered as u64,
                ),
                ("second pass: tested for occlusion", o.second_tested as u64),
                ("second pass: occluded (culled)", o.second_occluded as u64),
                ("second pass: clusters drawn", o.second_drawn as u64),
                ("second pass: triangles drawn", o.second_triangles as u64),
            ]);
        }
        rows
    }

    fn totals(&self) -> Vec<(&'static str, u64)> {
        vec![
            ("clusters requested", self.clusters_requested as u64),
            ("clusters considered", self.clusters_considered as u64),
            ("clusters in the frustum", self.in_frustum as u64),
            ("clusters visible (LOD cut)", self.visible as u64),
            ("software clusters", self.software as u64),
            ("hardware clusters", self.hardware as u64),
            ("triangles rasterised", self.triangles()),
            ("software triangles", self.software_triangles as u64),
            ("hardware triangles", self.hardware_triangles as u64),
            (
                "clusters dropped (list full)",
                self.clusters_dropped() as u64,
            ),
            ("clusters dropped (slots full)", self.slots_dropped() as u64),
        ]
    }

    /// Triangles rasterised per pixel of a `width` × `height` viewport: how close the
    /// LOD cut and the culling come to drawing one triangle per pixel.
    pub fn triangles_per_pixel(&self, width: u32, height: u32) -> f64 {
        self.triangles() as f64 / (f64::from(width) * f64::from(height)).max(1.0)
    }

    /// The counters as an HTML table, for the graph report; with the viewport, the
    /// triangles rasterised per pixel too.
    pub fn html_table(&self, viewport: Option<(u32, u32)>) -> String {
        let mut h = format!(
            "<h2>Frame {} counters</h2>\n<table>\n<tr><th>counter</th><th>value</th></tr>\n",
            self.frame
        );
        for (label, value) in self.rows() {
            h += &format!("<tr><td>{label}</td><td style=\"text-align:right\">{value}</td></tr>\n");
        }
        if let Some((w, h_px)) = viewport {
            h += &format!(
                "<tr><td>{PER_PIXEL}</td><td style=\"text-align:right\">{:.2}</td></tr>\n",
                self.triangles_per_pixel(w, h_px)
            );
        }
        h + "</table>\n"
    }
}

/// The label of [`FrameCounts::triangles_per_pixel`] in reports.
pub const PER_PIXEL: &str = "triangles rasterised per pixel";

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn words_map_to_counters_and_overflow_is_the_excess() {
        let cluster_count: Vec<u8> = bytemuck::cast_slice(&[90u32, 100]).to_vec();
        let raster: Vec<u8> = bytemuck::cast_slice(&[3u32, 4, 9, 7, 20, 300, 400, 0]).to_vec();
        let c = FrameCounts::from_words(5, &cluster_count, &raster, None).unwrap();
        assert_eq!((c.clusters_considered, c.clusters_requested), (90, 100));
        assert_eq!((c.software, c.hardware, c.visible, c.slots), (3, 4, 9, 7));
        assert_eq!(c.in_frustum, 20);
        assert_eq!(c.triangles(), 700);
        assert_eq!((c.clusters_dropped(), c.slots_dropped()), (10, 2));
        assert!(c.overflowed());
        assert!(FrameCounts::from_words(5, &cluster_count[..4], &raster, None).is_none());
        let fits = FrameCounts {
            clusters_requested: 5,
            clusters_considered: 5,
            visible: 3,
            slots: 3,
            slots_dropped: 0,
            ..c
        };
        assert!(!fits.overflowed());
        assert!(
            c.html_table(None)
                .contains("<td>clusters dropped (slots full)</td>")
        );
        let table = c.html_table(Some((10, 5)));
        let per_pixel = format!("{:.2}", c.triangles() as f64 / 50.0);
        assert!(
            table.contains(&format!(
                "<td>{PER_PIXEL}</td><td style=\"text-align:right\">{per_pixel}</td>"
            )),
            "{table}"
        );
    }

    #[test]
    fn a_second_pass_adds_its_clusters_and_its_own_overflow() {
        let cluster_count: Vec<u8> = bytemuck::cast_slice(&[100u32, 100]).to_vec();
        // First: 3 sw, 4 hw, 9 wanting slots, C 10, 20 in frustum, triangles, 0, cut 15,
        // occluded 6, 10 slots, 12 tested.
        let first: Vec<u8> =
            bytemuck::cast_slice(&[3u32, 4, 9, 10, 20, 300, 400, 0, 15, 6, 10, 12]).to_vec();
        // Second: 0 sw, 1 hw, 5 wanting slots of the 3 left, C2 6, 6 considered, …
        let second: Vec<u8> =
            bytemuck::cast_slice(&[0u32, 1, 5, 6, 6, 0, 50, 0, 6, 1, 3, 6]).to_vec();
        let c = FrameCounts::from_words(7, &cluster_count, &first, Some(&second)).unwrap();
        assert_eq!((c.hardware, c.visible, c.hardware_triangles), (5, 14, 450));
        assert_eq!(c.slots, 10);
        assert_eq!(
            c.slots_dropped(),
            2,
            "the second pass wanted 5 of its 3 slots"
        );
        let o = c.occlusion.unwrap();
        assert_eq!((o.first_cut, o.first_tested, o.first_occluded), (15, 12, 6));
        assert_eq!(
            (o.second_considered, o.second_occluded, o.second_drawn),
            (6, 1, 1)
        );
        assert!(
            c.rows()
                .iter()
                .any(|(l, v)| l.contains("second pass: occluded") && *v == 1)
        );
        // A first pass's eight words are too short for a two-pass frame.
        assert!(FrameCounts::from_words(7, &cluster_count, &first[..32], Some(&second)).is_none());
    }

    #[test]
    fn the_walks_counters_read_as_many_words_as_the_buffer_has() {
        let words =
            |n: usize| -> Vec<u8> { bytemuck::cast_slice(&[9u32, 8, 7, 6, 5, 4, 3][..n]).to_vec() };
        assert!(HierarchyCounts::from_words(&words(3)).is_none());
        let four = HierarchyCounts::from_words(&words(4)).unwrap();
        assert_eq!(
            (four.nodes_tested, four.hidden_nodes, four.instances),
            (9, 0, None)
        );
        let five = HierarchyCounts::from_words(&words(5)).unwrap();
        assert_eq!((five.hidden_nodes, five.instances), (5, None));
        let seven = HierarchyCounts::from_words(&words(7)).unwrap();
        assert_eq!(
            seven.instances,
            Some(InstanceCounts {
                tested: 4,
                visible: 3
            })
        );
        let counts = FrameCounts {
            hierarchy: Some(seven),
            ..FrameCounts::default()
        };
        let rows = counts.rows();
        assert!(rows.contains(&("instances tested", 4)), "{rows:?}");
        assert!(rows.contains(&("instances visible", 3)), "{rows:?}");
    }
}
