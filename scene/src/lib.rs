//! Mesh loading, the meshlet LOD DAG builder and the meshlet asset format.
//!
//! The path from a file to the GPU: [`load::load_mesh`] → [`Mesh::clean`] →
//! [`dag::build_dag`] → [`asset::MeshletAsset::from_dag`] (quantise and pack) →
//! [`asset::MeshletAsset::save`] / [`asset::MeshletAsset::load`]. [`build_asset`] runs
//! the whole chain; [`procedural_mesh`] is the built-in default mesh.
//!
//! # Features
//!
//! - `build` (default): everything that makes assets: the loaders, the texture decoders,
//!   the procedural and
//!   terrain meshes, the DAG builder, packing, `bake` and the asset cache, with the
//!   C and C++ libraries they need (METIS, meshoptimizer). A renderer that only draws
//!   assets baked elsewhere turns it off (`default-features = false`) and keeps
//!   [`asset::MeshletAsset::load`], validation, the DAG checks of [`verify`] and
//!   [`inspect`].
//! - `test-utils`: `damaged`, assets broken on purpose for other crates' tests (with
//!   `build`).

#![warn(missing_docs)]

// Reading, validating, verifying and inspecting assets: always built.
pub mod asset;
pub mod bounds;
pub mod chain_fingerprint;
pub mod compress;
pub mod error;
pub mod hierarchy;
pub mod input;
pub mod inspect;
pub mod open_edges;
pub mod verify;
pub mod watertight;

pub use asset::MeshletAsset;
pub use error::SceneError;

// Making assets: the `build` feature.
#[cfg(feature = "build")]
pub mod bake;
#[cfg(feature = "build")]
pub mod cache;
#[cfg(feature = "build")]
pub mod dag;
#[cfg(all(feature = "build", any(test, feature = "test-utils")))]
pub mod damaged;
#[cfg(feature = "build")]
pub mod deviation;
#[cfg(feature = "build")]
pub mod glb;
#[cfg(feature = "build")]
pub mod greedy_meshlets;
#[cfg(feature = "build")]
pub mod grouping;
#[cfg(feature = "build")]
pub mod load;
#[cfg(feature = "build")]
pub mod mesh;
#[cfg(feature = "build")]
pub mod meshlets;
#[cfg(feature = "build")]
pub mod pipeline;
#[cfg(feature = "build")]
pub mod procedural;
#[cfg(feature = "build")]
pub mod simplify;
#[cfg(feature = "build")]
pub mod terrain;
pub mod texture;
#[cfg(feature = "build")]
pub mod uv_slide;
#[cfg(feature = "build")]
pub mod weld;
#[cfg(feature = "build")]
pub mod world;

#[cfg(feature = "build")]
pub use dag::{Dag, DagOptions, build_dag};
#[cfg(feature = "build")]
pub use grouping::Grouping;
#[cfg(feature = "build")]
pub use mesh::{CleanReport, Mesh};
#[cfg(feature = "build")]
pub use pipeline::{BuildOptions, Built, build_asset};
#[cfg(feature = "build")]
pub use procedural::{DEFAULT_SEGMENTS, Knot, knot_mesh, procedural_mesh};
#[cfg(feature = "build")]
pub use terrain::Terrain;
#[cfg(feature = "build")]
pub use world::World;
