//! The one error type of the graph: every variant names the passes and resources involved
//! and says what to change.

use thiserror::Error;

/// Every error of the graph: building, compiling, loading a pipeline file and executing.
/// Each says what is wrong and what to change.
#[derive(Debug, Error)]
pub enum GraphError {
    /// Passes depend on each other in a circle (compile).
    #[error("dependency cycle: {} -> {}; break it by reading an earlier version of one of these resources", path.join(" -> "), path.first().map(String::as_str).unwrap_or(""))]
    Cycle { path: Vec<String> },

    /// A pass reads a transient resource no earlier pass writes (compile).
    #[error(
        "pass `{pass}` reads `{resource}` (version {version}) in slot `{slot}`, but no pass writes that version; add a pass that writes it before, or import the resource"
    )]
    ReadWithoutWriter {
        pass: String,
        slot: String,
        resource: String,
        version: u32,
    },

    /// A pass binds an older version of a resource than the newest (compile).
    #[error(
        "pass `{pass}` uses a stale handle of `{resource}` in slot `{slot}`: version {given}, but `{writer}` has already written version {current}; use the handle `{writer}` returned"
    )]
    StaleVersion {
        pass: String,
        slot: String,
        resource: String,
        given: u32,
        current: u32,
        writer: String,
    },

    /// A bound resource is not what the slot expects: element, format, size or range (build
    /// or compile).
    #[error(
        "pass `{pass}` slot `{slot}` expects {expected}, but `{resource}` is {found}; bind a resource of the expected kind or change the resource's descriptor"
    )]
    DescriptorMismatch {
        pass: String,
        slot: String,
        resource: String,
        expected: String,
        found: String,
    },

    /// An imported resource lacks a usage a slot needs (compile).
    #[error(
        "pass `{pass}` uses `{resource}` as {access} in slot `{slot}`, which needs {needed}, but {reason}"
    )]
    UsageNotAllowed {
        pass: String,
        slot: String,
        resource: String,
        access: String,
        needed: String,
        reason: String,
    },

    /// Two resources or passes share a name (build).
    #[error("duplicate {what} name `{name}`; every {what} in a graph needs a unique name")]
    DuplicateName { what: &'static str, name: String },

    /// A pass needs device features the adapter lacks (compile).
    #[error(
        "pass `{pass}` (stage `{stage}`) requires the adapter feature(s) {features}, which this adapter lacks; {instead}"
    )]
    MissingFeature {
        pass: String,
        stage: String,
        features: String,
        /// What would run instead, or what to change.
        instead: String,
    },

    /// A binding names a slot the stage does not have (build).
    #[error("pass `{pass}` (stage `{stage}`) has no slot `{slot}`; its slots are: {available}")]
    UnknownSlot {
        pass: String,
        stage: String,
        slot: String,
        available: String,
    },

    /// A required slot is left unbound (build).
    #[error("pass `{pass}` leaves slot `{slot}` unbound; bind it to a resource")]
    UnboundSlot { pass: String, slot: String },

    /// A binding or pipeline file names a resource that does not exist (build).
    #[error(
        "pass `{pass}` binds `{resource}` to slot `{slot}` but no resource of that name exists; declare it first"
    )]
    UnknownResource {
        pass: String,
        slot: String,
        resource: String,
    },

    /// A pass writes an imported read-only or history resource (build).
    #[error("`{resource}` is read-only ({why}); pass `{pass}` cannot write it in slot `{slot}`")]
    ReadOnlyResource {
        pass: String,
        slot: String,
        resource: String,
        why: &'static str,
    },

    /// A pipeline names an implementation the registry does not have (load).
    #[error(
        "no implementation `{implementation}` of stage `{stage}` is registered; known: {known}"
    )]
    UnknownImplementation {
        stage: String,
        implementation: String,
        known: String,
    },

    /// A pipeline names a stage the registry does not have (load).
    #[error(
        "{file}: pass `{pass}` names stage `{stage}`, which no registered pass crate provides; stages: {known}"
    )]
    UnknownStage {
        file: String,
        pass: String,
        stage: String,
        known: String,
    },

    /// A size passes one of the adapter's limits (compile).
    #[error("{what} is {value} {unit}, over the adapter's {limit} of {max}; {hint}")]
    LimitExceeded {
        /// The resource or pass, named.
        what: String,
        limit: &'static str,
        value: u64,
        max: u64,
        unit: &'static str,
        hint: String,
    },

    /// A size computed from parameters overflows 64 bits (compile).
    #[error(
        "resource `{resource}`: its size overflows 64 bits (element count × element size); use a smaller count"
    )]
    SizeOverflow { resource: String },

    /// A buffer is sized by an undeclared parameter (compile).
    #[error(
        "resource `{resource}` is sized by parameter `{param}`, which is not declared; declare it with size_param (known: {known})"
    )]
    UnknownParam {
        resource: String,
        param: String,
        known: String,
    },

    /// wgpu rejected the frame and no pass was named (execute; checked mode names it).
    #[error(
        "wgpu validation error {when}: {message}; run the executor with `checked = true` to name the pass"
    )]
    FrameValidation { when: &'static str, message: String },

    /// The device was opened without features the compiled graph uses (execute).
    #[error("the device lacks {features}, which the compiled graph uses; {instead}")]
    DeviceLacksFeatures { features: String, instead: String },

    /// A resource declaration is impossible in itself, e.g. more mips than its size has
    /// (compile).
    #[error("resource `{resource}`: {problem}")]
    BadDeclaration { resource: String, problem: String },

    /// `set_param` names a parameter the graph does not have.
    #[error("the graph has no size parameter `{param}` to set; its parameters: {known}")]
    NoSuchParam { param: String, known: String },

    /// An output was asked of a pass that does not write that slot (build).
    #[error(
        "pass `{pass}` writes no slot `{slot}`, so it has no output of that name; it writes: {written}"
    )]
    NotWritten {
        pass: String,
        slot: String,
        written: String,
    },

    /// A pass reads a frame input the frame does not supply (execute).
    #[error(
        "pass `{pass}` reads frame input `{input}`, which this frame does not supply; add it to the FrameData given to execute"
    )]
    MissingFrameInput { pass: String, input: String },

    /// A physical resource could not be created (execute).
    #[error("could not allocate `{resource}`: {message}")]
    Allocation { resource: String, message: String },

    /// A pass rejects its parameters (setup or load).
    #[error("pass `{pass}` parameter error: {message}")]
    Parameter { pass: String, message: String },

    /// A pipeline file cannot be read or used as a whole (load).
    #[error("pipeline file {file}: {message}")]
    PipelineFile { file: String, message: String },

    /// A pipeline file has a problem at a place in its text (load).
    #[error("pipeline file {file}: {problem}")]
    PipelineSource {
        file: String,
        problem: crate::file::SourceProblem,
    },

    /// A pipeline file's resource declaration is wrong (load).
    #[error("pipeline file {file}: resource `{resource}`: {problem}")]
    PipelineResource {
        file: String,
        resource: String,
        problem: crate::file::ResourceProblem,
    },

    /// An imported resource was not given to the frame (execute).
    #[error("imported resource `{resource}` was not supplied to the frame; pass it in the imports")]
    MissingImport { resource: String },

    /// A supplied import differs from its declaration (execute).
    #[error("imported resource `{resource}` does not match its declaration: {message}")]
    ImportMismatch { resource: String, message: String },

    /// No Vulkan adapter was found; the message says how to install one.
    #[error(
        "no Vulkan adapter found{detail}. Install Mesa's software driver: `sudo apt-get install mesa-vulkan-drivers` (lavapipe), or set MESHLIGHT_ADAPTER to a name from `vulkaninfo --summary`"
    )]
    NoAdapter { detail: String },

    /// The device could not be created.
    #[error("could not create the device: {0}")]
    Device(String),

    /// A pass's shader does not compose or validate (execute).
    #[error("shader error in pass `{pass}`: {source}")]
    Shader {
        pass: String,
        #[source]
        source: meshlight_shaders::ShaderError,
    },

    /// wgpu rejected what a named pass recorded (execute).
    #[error("wgpu validation error in pass `{pass}`: {message}")]
    Validation { pass: String, message: String },

    /// A pass failed while recording, e.g. a shader's bindings do not match its slots
    /// (execute).
    #[error("pass `{pass}` failed while recording: {message}")]
    Record { pass: String, message: String },

    /// Reading a buffer back from the GPU failed.
    #[error("GPU readback failed: {0}")]
    Readback(String),
}

impl GraphError {
    /// A pass's parameter error, before the pass has a name: the pipeline-file loader
    /// and the compiler fill in the pass it belongs to.
    pub fn parameter(message: impl Into<String>) -> Self {
        GraphError::Parameter {
            pass: String::new(),
            message: message.into(),
        }
    }
}

/// The graph's result type.
pub type Result<T, E = GraphError> = std::result::Result<T, E>;
