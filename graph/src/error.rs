//! The one error type of the graph: every variant names the passes and resources involved
//! and says what to change.

use thiserror::Error;

/// Every error of the graph: building, compiling, loading a pipeline file and executing. Each says what is wrong and what to change.
#[derive(Debug, Error)]
pub enum GraphError {
    #[error("dependency cycle: {} -> {}; break it by reading an earlier version of one of these resources", path.join(" -> "), path.first().map(String::as_str).unwrap_or(""))]
    Cycle { path: Vec<String> },

    #[error(
        "pass `{pass}` reads `{resource}` (version {version}) in slot `{slot}`, but no pass writes that version; add a pass that writes it before, or import the resource"
    )]
    ReadWithoutWriter {
        pass: String,
        slot: String,
        resource: String,
        version: u32,
    },

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

    #[error("duplicate {what} name `{name}`; every {what} in a graph needs a unique name")]
    DuplicateName { what: &'static str, name: String },

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

    #[error("pass `{pass}` (stage `{stage}`) has no slot `{slot}`; its slots are: {available}")]
    UnknownSlot {
        pass: String,
        stage: String,
        slot: String,
        available: String,
    },

    #[error("pass `{pass}` leaves slot `{slot}` unbound; bind it to a resource")]
    UnboundSlot { pass: String, slot: String },

    #[error(
        "pass `{pass}` binds `{resource}` to slot `{slot}` but no resource of that name exists; declare it first"
    )]
    UnknownResource {
        pass: String,
        slot: String,
        resource: String,
    },

    #[error("`{resource}` is read-only ({why}); pass `{pass}` cannot write it in slot `{slot}`")]
    ReadOnlyResource {
        pass: String,
        slot: String,
        resource: String,
        why: &'static str,
    },

    #[error(
        "no implementation `{implementation}` of stage `{stage}` is registered; known: {known}"
    )]
    UnknownImplementation {
        stage: String,
        implementation: String,
        known: String,
    },

    #[error(
        "{file}: pass `{pass}` names stage `{stage}`, which no registered pass crate provides; stages: {known}"
    )]
    UnknownStage {
        file: String,
        pass: String,
        stage: String,
        known: String,
    },

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

    #[error(
        "resource `{resource}`: its size overflows 64 bits (element count × element size); use a smaller count"
    )]
    SizeOverflow { resource: String },

    #[error(
        "resource `{resource}` is sized by parameter `{param}`, which is not declared; declare it with size_param (known: {known})"
    )]
    UnknownParam {
        resource: String,
        param: String,
        known: String,
    },

    #[error(
        "wgpu validation error {when}: {message}; run the executor with `checked = true` to name the pass"
    )]
    FrameValidation { when: &'static str, message: String },

    #[error("the device lacks {features}, which the compiled graph uses; {instead}")]
    DeviceLacksFeatures { features: String, instead: String },

    #[error("resource `{resource}`: {problem}")]
    BadDeclaration { resource: String, problem: String },

    #[error("the graph has no size parameter `{param}` to set; its parameters: {known}")]
    NoSuchParam { param: String, known: String },

    #[error(
        "pass `{pass}` writes no slot `{slot}`, so it has no output of that name; it writes: {written}"
    )]
    NotWritten {
        pass: String,
        slot: String,
        written: String,
    },

    #[error(
        "pass `{pass}` reads frame input `{input}`, which this frame does not supply; add it to the FrameData given to execute"
    )]
    MissingFrameInput { pass: String, input: String },

    #[error("could not allocate `{resource}`: {message}")]
    Allocation { resource: String, message: String },

    #[error("pass `{pass}` parameter error: {message}")]
    Parameter { pass: String, message: String },

    #[error("pipeline file {file}: {message}")]
    PipelineFile { file: String, message: String },

    #[error("pipeline file {file}: {problem}")]
    PipelineSource {
        file: String,
        problem: crate::file::SourceProblem,
    },

    #[error("pipeline file {file}: resource `{resource}`: {problem}")]
    PipelineResource {
        file: String,
        resource: String,
        problem: crate::file::ResourceProblem,
    },

    #[error("imported resource `{resource}` was not supplied to the frame; pass it in the imports")]
    MissingImport { resource: String },

    #[error("imported resource `{resource}` does not match its declaration: {message}")]
    ImportMismatch { resource: String, message: String },

    #[error(
        "no Vulkan adapter found{detail}. Install Mesa's software driver: `sudo apt-get install mesa-vulkan-drivers` (lavapipe), or set MESHLIGHT_ADAPTER to a name from `vulkaninfo --summary`"
    )]
    NoAdapter { detail: String },

    #[error("could not create the device: {0}")]
    Device(String),

    #[error("shader error in pass `{pass}`: {source}")]
    Shader {
        pass: String,
        #[source]
        source: meshlight_shaders::ShaderError,
    },

    #[error("wgpu validation error in pass `{pass}`: {message}")]
    Validation { pass: String, message: String },

    #[error("pass `{pass}` failed while recording: {message}")]
    Record { pass: String, message: String },

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
