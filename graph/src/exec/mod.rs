//! Execution on wgpu.

pub mod context;
pub mod executor;
mod fill;
pub mod frame;
pub mod physical;
pub mod programs;
pub mod readback;
pub mod record;
pub(crate) mod reflect;
mod ring;
pub mod shared;
pub mod timing;
mod views;

pub use context::{ADAPTER_ENV, GpuAdapter, GpuContext, INDIRECT_VALIDATION_ENV};
pub use executor::{
    BATCHING_ENV, BatchStats, CHECKED_ENV, Executor, FrameStats, Imports, PassTiming,
};
pub use frame::FrameData;
pub use programs::{ComputeProgram, Program, RenderProgram};
pub use readback::Readback;
pub use record::{ColorAttachment, DepthAttachment, Immediates, RecordContext};
pub use shared::ComputePassGuard;
pub use timing::{GpuTimings, TIMING_ENV, TimingMode};
