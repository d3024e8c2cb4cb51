//! Stage `fill_clusters` (being built).
