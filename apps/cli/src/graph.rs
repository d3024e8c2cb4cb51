//! `meshlight graph`: a pipeline file compiled without a GPU (as for an adapter with
//! every feature, of a class given or a graphics GPU) or for this machine's adapter, and
//! dumped. It compiles the file as `meshlight render --pipeline` does, through the same
//! registry, so both pick the same implementation for every stage on the same adapter.

use meshlight::graph::file::Pipeline;
use meshlight::graph::{AdapterClass, CompileOptions, GpuAdapter, GraphError, Plan};
use std::path::Path;

/// The options `graph` plans with: this machine's adapter, or one with every feature of
/// `class` (a graphics GPU when none is given).
pub fn options(
    for_adapter: bool,
    class: Option<AdapterClass>,
) -> Result<CompileOptions, GraphError> {
    if for_adapter {
        let mut options = CompileOptions::for_adapter(&GpuAdapter::select()?);
        if let Some(class) = class {
            options.class = class;
        }
        return Ok(options);
    }
    Ok(CompileOptions::new(wgpu::Features::all()).with_class(class.unwrap_or_default()))
}

/// The plan of the pipeline file at `path`, compiled with `options`.
pub fn plan(path: &Path, options: &CompileOptions) -> Result<Plan, GraphError> {
    Ok(Pipeline::load(path)?
        .build(&meshlight::registry())?
        .compile(options)?
        .plan)
}

/// A class given on the command line by its key.
pub fn parse_class(key: &str) -> Result<AdapterClass, String> {
    AdapterClass::parse(key).ok_or_else(|| {
        format!(
            "unknown adapter class `{key}`; use {}",
            AdapterClass::ALL.map(AdapterClass::key).join(", ")
        )
    })
}
