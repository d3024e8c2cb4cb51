//! Stage `hw_raster` (being built).
