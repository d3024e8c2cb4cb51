//! The meshlight frame graph.
//!
//! Declare resources and passes with [`GraphBuilder`] (or load a pipeline file), compile
//! to a [`Plan`] with no device, inspect or dump it, and run it frame after frame with an
//! [`Executor`].

pub mod access;
pub mod builder;
pub mod choice;
pub mod compile;
pub mod contract;
pub mod dump;
pub mod error;
pub mod exec;
pub mod file;
pub mod pass;
pub mod plan;
pub mod program;
pub mod readback;
pub mod resource;
pub mod synthetic;

pub use access::Access;
pub use builder::{Bindings, GraphBuilder, History, PassNode, PassOutputs};
pub use choice::{CandidatePlan, Choice, ChoicePlan, Selection};
pub use compile::{CompileOptions, CompiledGraph};
pub use contract::{Slot, SlotKind, StageContract};
pub use error::{GraphError, Result};
pub use exec::{
    BatchStats, BindingLayout, ColorAttachment, ComputePassGuard, ComputeProgram, DepthAttachment,
    Executor, FrameData, FrameStats, GpuAdapter, GpuContext, GpuTimings, Imports, Program,
    Readback, RecordContext, RenderProgram, SamplerKind, TimingMode,
};
pub use meshlight_shaders::{PassShader, ShaderDef, ShaderDefs};
pub use pass::{Pass, SetupContext, Visibility64};
pub use plan::{Batch, Plan, Recording};
pub use program::{ColorTarget, DepthTarget, Geometry, Primitive, ProgramDesc};
pub use resource::{
    AnyHandle, Buffer, BufferDesc, Element, Handle, ResourceDesc, ResourceKind, Texture,
    TextureDesc, TextureRange,
};
