//! Execution on wgpu: the device, the executor that runs a compiled graph frame after
//! frame, and GPU timing. What a pass records against lives in `record`, below the pass
//! trait.

pub mod context;
pub mod executor;
mod prepare;
mod quiet;
pub mod timing;

pub use context::{
    ADAPTER_ENV, AdapterOptions, GpuAdapter, GpuContext, INDIRECT_VALIDATION_ENV,
    experimental_features,
};
pub use executor::{
    BATCHING_ENV, BatchStats, CHECKED_ENV, Executor, FrameStats, Imports, PassTiming,
};
pub use timing::{GpuTimings, TIMING_ENV, TimingMode};
