//! Pipelines as data: TOML files naming resources and pass instances, read into a
//! [`Pipeline`] a caller may change through its methods, then built into a
//! `GraphBuilder` through a registry.

mod build;
mod params;
mod pipeline;
mod read;
mod registry;

pub use crate::choice::AUTO;
pub use crate::problem::{MAX_PIPELINE_FILE_BYTES, ResourceProblem, SourceProblem};
pub use build::{format_text, parse_format};
pub use params::Params;
pub use pipeline::{
    BufferEntry, EntryKind, MipLevels, PassEntry, Pipeline, Removed, ResourceEntry, TextureEntry,
    VisibilityEntry, load_pipeline, parse_pipeline,
};
pub use read::read_pipeline_text;
pub use registry::{IntoPass, Registry};
