//! Pipelines as data: TOML files naming pass instances, built through a registry.

mod params;
mod pipeline;
mod registry;

pub use params::Params;
pub use pipeline::{
    PipelineFile, load_pipeline, load_pipeline_with, parse_format, parse_pipeline,
    parse_pipeline_with,
};
pub use registry::{AUTO, Factory, Registry};
