//! Geometry streaming: which pages of the meshes' DAGs a fixed-size GPU pool holds, and
//! a LOD cut that draws only what is held and never shows a hole.
//!
//! - [`pages`]: a mesh's pages (the meshlets simplified in one DAG group, the finer
//!   replacement for what that group produced) and the pages each needs first.
//! - [`cut`]: the LOD cut restricted to resident pages, and the checker that a drawn cut
//!   is complete.
//! - [`pool`]: where pages go in the pool's bytes.
//! - [`pressure`]: the LOD threshold's scale, coupled to how full the pool is wanted.
//! - [`streamer`]: the policy: requests in; loads, installs and evictions out, within
//!   per-frame budgets, parents first, least recently used evicted first.
//! - [`loader`]: threads reading pages with positional reads, checked as they arrive.
//!
//! Nothing here touches the GPU: the renderer reads back the GPU's requests, gives them
//! to the [`streamer::Streamer`], has the [`loader::Loader`] read the pages it asks for,
//! and uploads what it installs. So every rule is tested on the CPU, on real meshes'
//! DAGs and on random ones.

#![warn(missing_docs)]

pub mod cut;
pub mod loader;
pub mod pages;
pub mod pool;
pub mod pressure;
pub mod streamer;

pub use pages::{MeshDag, PageGraph, PageId};
pub use streamer::{Budget, FramePlan, Install, Load, Request, Streamer};
