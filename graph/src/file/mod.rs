//! Pipelines as data: TOML files naming resources and pass instances, read into a
//! [`Pipeline`] a caller may change through its methods, then built into a
//! `GraphBuilder` through a registry.

#[cfg(feature = "pipeline-files")]
mod build;
mod params;
#[cfg(feature = "pipeline-files")]
mod pipeline;
#[cfg(feature = "pipeline-files")]
mod read;
mod registry;

pub use crate::choice::AUTO;
pub use crate::problem::{MAX_PIPELINE_FILE_BYTES, ResourceProblem, SourceProblem};
#[cfg(feature = "pipeline-files")]
pub use build::{format_text, parse_format};
pub use params::Params;
#[cfg(feature = "pipeline-files")]
pub use pipeline::{
    BufferEntry, EntryKind, MipLevels, PassEntry, Pipeline, Removed, ResourceEntry, TextureEntry,
    VisibilityEntry, load_pipeline, parse_pipeline,
};
#[cfg(feature = "pipeline-files")]
pub use read::read_pipeline_text;
pub use registry::{IntoPass, Registry};
