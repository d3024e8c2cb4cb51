//! The meshlight frame graph.
//!
//! Declare resources and passes with [`GraphBuilder`] (or load a pipeline file), compile
//! to a [`Plan`] with no device, inspect or dump it, and run it frame after frame with an
//! [`Executor`].

#![warn(missing_docs)]

// The modules in layers, lowest first. A module imports only from layers before its
// own, which keeps the crate free of import cycles:
//   1 access, adapter, names, problem   2 error, layout, resource   3 contract, program
//   4 plan   5 record (what a pass records against)   6 pass (the trait and its setup)
//   7 choice   8 node, readback   9 builder   10 compile, file, synthetic   11 exec
//   12 dump

mod access;
mod adapter;
mod builder;
mod choice;
mod compile;
mod contract;
#[cfg(feature = "dumps")]
pub mod dump;
mod error;
mod exec;
pub mod file;
mod layout;
mod names;
mod node;
mod pass;
mod plan;
mod problem;
mod program;
mod readback;
mod record;
mod resource;
pub mod synthetic;

pub use access::Access;
pub use adapter::AdapterClass;
pub use builder::{Bindings, GraphBuilder, History, PassOutputs};
pub use choice::{Choice, ClassOrder};
pub use compile::{CompileOptions, CompiledGraph};
pub use contract::{Slot, SlotKind, StageContract};
pub use error::{GraphError, Result};
pub use exec::{
    ADAPTER_ENV, AdapterOptions, BATCHING_ENV, BatchStats, CHECKED_ENV, Executor, FrameStats,
    GpuAdapter, GpuContext, GpuTimings, INDIRECT_VALIDATION_ENV, Imports, PassTiming, TIMING_ENV,
    TimingMode, experimental_features,
};
pub use layout::{BindingLayout, BindingSource, LayoutEntry, SamplerKind};
pub use meshlight_shaders::{PassShader, ShaderDef, ShaderDefs};
pub use names::feature_names;
pub use pass::{Implementation, Pass, SetupContext, Visibility64};
pub use plan::{Batch, CandidatePlan, ChoicePlan, LoadOp, Plan, Recording, Selection, StoreOp};
pub use program::{ColorTarget, DepthTarget, Geometry, Primitive, ProgramDesc};
pub use readback::STAGE as READBACK_STAGE;
pub use record::{
    ColorAttachment, ComputePassGuard, ComputeProgram, DepthAttachment, FrameData, Immediates,
    Program, Readback, RecordContext, RenderProgram, Workgroups,
};
pub use resource::{
    AnyHandle, Buffer, BufferDesc, Element, Handle, ResourceDesc, ResourceKind, Texture,
    TextureDesc, TextureRange,
};

/// What a pass author uses, in one import: `use meshlight_graph::prelude::*;`. The
/// contract (slots), setup (programs, scratch, defs), record (bind groups, dispatches,
/// render passes) and registration (params, registry) of a stage implementation need
/// nothing else from this crate, and its shader declarations nothing else from
/// `meshlight_shaders`.
pub mod prelude {
    pub use crate::file::{Params, Registry};
    pub use crate::{
        Access, BindingLayout, BufferDesc, ColorAttachment, ColorTarget, ComputeProgram,
        DepthAttachment, DepthTarget, Element, GraphError, Implementation, Pass, PassShader,
        Primitive, ProgramDesc, RecordContext, ResourceDesc, Result, SamplerKind, SetupContext,
        ShaderDef, ShaderDefs, Slot, StageContract, StoreOp, TextureDesc, Visibility64, Workgroups,
    };
    pub use meshlight_shaders::{pass_shader, shader_defs, uniform_block};
}
