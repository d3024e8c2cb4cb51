//! Mesh loading, the meshlet LOD DAG builder and the meshlet asset format.
//!
//! The path from a file to the GPU: [`load::load_mesh`] → [`Mesh::clean`] →
//! [`dag::build_dag`] → [`asset::MeshletAsset::from_dag`] (quantise and pack) →
//! [`asset::MeshletAsset::save`] / [`asset::MeshletAsset::load`]. [`build_asset`] runs
//! the whole chain; [`procedural_mesh`] is the built-in default mesh.

pub mod asset;
pub mod bake;
pub mod bounds;
pub mod cache;
pub mod chain_fingerprint;
pub mod compress;
pub mod dag;
#[cfg(any(test, feature = "test-utils"))]
pub mod damaged;
pub mod deviation;
pub mod error;
pub mod greedy_meshlets;
pub mod grouping;
pub mod hierarchy;
pub mod inspect;
pub mod load;
pub mod mesh;
pub mod meshlets;
pub mod pipeline;
pub mod procedural;
pub mod simplify;
pub mod terrain;
pub mod verify;
pub mod watertight;
pub mod weld;

pub use asset::MeshletAsset;
pub use dag::{Dag, DagOptions, build_dag};
pub use error::SceneError;
pub use grouping::Grouping;
pub use mesh::{CleanReport, Mesh};
pub use pipeline::{BuildOptions, Built, build_asset};
pub use procedural::{DEFAULT_SEGMENTS, procedural_mesh};
pub use terrain::Terrain;
