//! GPU light clustering: which point lights, spot lights, probes and decals touch each
//! froxel of the view. The stages z_slice → count_raster → scan_fan → populate wired
//! into a graph ([`frame_graph`]), run frame after frame with overflow growth
//! ([`Clusterer`]), and the CPU reference of the whole assignment ([`reference`]).

#![warn(missing_docs)]

pub mod clusterer;
pub mod frame_graph;
pub mod growth;
pub mod reference;

pub use clusterer::{Clustered, Clusterer, ClusteringCounts, ClusteringSource, ClusteringWarning};
pub use frame_graph::ClusteringSettings;
pub use growth::Growth;
