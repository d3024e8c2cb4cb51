//! Recording a pass: the [`RecordContext`] `Pass::record` gets, and the GPU tables it
//! reads: physical resources and their views, the program and bind-group caches, the
//! batch's shared compute pass, the fill program, readback rings and the frame's inputs.
//!
//! The executor owns these tables and lends them to one pass at a time. They sit below
//! the pass trait, which names the context, and so below the executor too; nothing here
//! knows passes, the builder or compile.

pub mod context;
pub mod fill;
pub mod frame;
pub mod physical;
pub mod programs;
pub mod readback;
pub(crate) mod reflect;
pub mod ring;
pub mod shared;
pub mod views;

pub use context::{ColorAttachment, DepthAttachment, Immediates, RecordContext, Workgroups};
pub use frame::FrameData;
pub use programs::{ComputeProgram, Program, RenderProgram};
pub use readback::Readback;
pub use shared::ComputePassGuard;
