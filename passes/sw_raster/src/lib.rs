//! Stage `sw_raster` (being built).
