//! Pipelines as data: TOML files naming pass instances, built through a registry.

mod params;
mod pipeline;
mod registry;

pub use params::Params;
pub use pipeline::{load_pipeline, parse_format, parse_pipeline, PipelineFile};
pub use registry::{Factory, Registry};
