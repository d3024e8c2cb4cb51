//! The counters a frame leaves on the GPU, read back asynchronously: how many clusters
//! were considered, survived culling, went to each rasteriser, and whether a list was
//! too small.

use serde::Serialize;

/// The readback of `fill_clusters`' `cluster_count` (words: written, requested).
pub const CLUSTER_COUNT_READBACK: &str = "cluster_count";
/// The readback of `cull_lod`'s `raster_counts` (eight words, see that crate).
pub const RASTER_COUNTS_READBACK: &str = "raster_counts";

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
    pub hardware: u32,
    /// Triangles of those clusters.
    pub software_triangles: u32,
    pub hardware_triangles: u32,
}

impl FrameCounts {
    /// From the two readbacks' bytes; `None` when either is shorter than its words.
    pub fn from_words(frame: u64, cluster_count: &[u8], raster_counts: &[u8]) -> Option<Self> {
        let words = |bytes: &[u8], n: usize| -> Option<Vec<u32>> {
            (bytes.len() >= n * 4).then(|| bytemuck::pod_collect_to_vec(&bytes[..n * 4]))
        };
        let c = words(cluster_count, 2)?;
        let r = words(raster_counts, 8)?;
        Some(Self {
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
        })
    }

    /// Candidates the cluster list had no room for.
    pub fn clusters_dropped(&self) -> u32 {
        self.clusters_requested
            .saturating_sub(self.clusters_considered)
    }

    /// Visible clusters the raster slots had no room for.
    pub fn slots_dropped(&self) -> u32 {
        self.visible.saturating_sub(self.slots)
    }

    /// Whether anything was dropped: the frame's image may miss geometry.
    pub fn overflowed(&self) -> bool {
        self.clusters_dropped() > 0 || self.slots_dropped() > 0
    }

    pub fn triangles(&self) -> u64 {
        self.software_triangles as u64 + self.hardware_triangles as u64
    }

    /// Rows of `(label, value)` for reports.
    pub fn rows(&self) -> Vec<(&'static str, u64)> {
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

    /// The counters as an HTML table, for the graph report.
    pub fn html_table(&self) -> String {
        let mut h = format!(
            "<h2>Frame {} counters</h2>\n<table>\n<tr><th>counter</th><th>value</th></tr>\n",
            self.frame
        );
        for (label, value) in self.rows() {
            h += &format!("<tr><td>{label}</td><td style=\"text-align:right\">{value}</td></tr>\n");
        }
        h + "</table>\n"
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn words_map_to_counters_and_overflow_is_the_excess() {
        let cluster_count: Vec<u8> = bytemuck::cast_slice(&[90u32, 100]).to_vec();
        let raster: Vec<u8> = bytemuck::cast_slice(&[3u32, 4, 9, 7, 20, 300, 400, 0]).to_vec();
        let c = FrameCounts::from_words(5, &cluster_count, &raster).unwrap();
        assert_eq!((c.clusters_considered, c.clusters_requested), (90, 100));
        assert_eq!((c.software, c.hardware, c.visible, c.slots), (3, 4, 9, 7));
        assert_eq!(c.in_frustum, 20);
        assert_eq!(c.triangles(), 700);
        assert_eq!((c.clusters_dropped(), c.slots_dropped()), (10, 2));
        assert!(c.overflowed());
        assert!(FrameCounts::from_words(5, &cluster_count[..4], &raster).is_none());
        let fits = FrameCounts {
            clusters_requested: 5,
            clusters_considered: 5,
            visible: 3,
            slots: 3,
            ..c
        };
        assert!(!fits.overflowed());
        assert!(
            c.html_table()
                .contains("<td>clusters dropped (slots full)</td>")
        );
    }
}
