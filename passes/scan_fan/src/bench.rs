//! Benchmark (placeholder, filled below).
