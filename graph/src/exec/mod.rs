//! Execution on wgpu.

pub mod context;
pub mod executor;
pub mod layout;
pub mod physical;
pub mod programs;
pub mod record;
mod timing;

pub use context::{ADAPTER_ENV, GpuAdapter, GpuContext};
pub use executor::{Executor, FrameStats, Imports, PassTiming};
pub use layout::{BindingLayout, BindingSource, LayoutEntry};
pub use programs::ComputeProgram;
pub use record::{ComputeDesc, RecordContext};
