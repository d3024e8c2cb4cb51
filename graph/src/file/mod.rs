//! Pipelines as data: TOML files naming pass instances, built through a registry.

mod params;
mod pipeline;
mod registry;

pub use crate::choice::AUTO;
pub use crate::problem::{MAX_PIPELINE_FILE_BYTES, ResourceProblem, SourceProblem};
pub use params::Params;
pub use pipeline::{
    PipelineFile, load_pipeline, load_pipeline_with, parse_format, parse_pipeline,
    parse_pipeline_with, read_pipeline_text,
};
pub use registry::{IntoPass, Registry};
