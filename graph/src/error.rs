//! The one error type of the graph: every variant names the passes and resources involved
//! and says what to change.

use thiserror::Error;

/// Every error of the graph: building, compiling, loading a pipeline file and executing.
/// Each says what is wrong and what to change.
#[derive(Debug, Error)]
pub enum GraphError {
    /// Passes depend on each other in a circle (compile).
    #[error("dependency cycle: {} -> {}; break it by reading an earlier version of one of these resources", path.join(" -> "), path.first().map(String::as_str).unwrap_or(""))]
    Cycle {
        /// The passes around the circle, in dependency order.
        path: Vec<String>,
    },

    /// A pass reads a transient resource no earlier pass writes (compile).
    #[error(
        "pass `{pass}` reads `{resource}` (version {version}) in slot `{slot}`, but no pass writes that version; add a pass that writes it before, or import the resource"
    )]
    ReadWithoutWriter {
        /// The pass, by its name in the graph.
        pass: String,
        /// The slot of that pass's stage contract.
        slot: String,
        /// The resource, by its declared name.
        resource: String,
        /// The version the pass's handle names.
        version: u32,
    },

    /// A pass binds an older version of a resource than the newest (compile).
    #[error(
        "pass `{pass}` uses a stale handle of `{resource}` in slot `{slot}`: version {given}, but `{writer}` has already written version {current}; use the handle `{writer}` returned"
    )]
    StaleVersion {
        /// The pass, by its name in the graph.
        pass: String,
        /// The slot of that pass's stage contract.
        slot: String,
        /// The resource, by its declared name.
        resource: String,
        /// The version of the handle the pass bound.
        given: u32,
        /// The newest version, the one the pass should bind.
        current: u32,
        /// The pass that wrote the newest version.
        writer: String,
    },

    /// A bound resource is not what the slot expects: element, format, size or range (build
    /// or compile).
    #[error(
        "pass `{pass}` slot `{slot}` expects {expected}, but `{resource}` is {found}; bind a resource of the expected kind or change the resource's descriptor"
    )]
    DescriptorMismatch {
        /// The pass, by its name in the graph.
        pass: String,
        /// The slot of that pass's stage contract.
        slot: String,
        /// The resource, by its declared name.
        resource: String,
        /// What the slot declares, in words.
        expected: String,
        /// What the bound resource is, in words.
        found: String,
    },

    /// An imported resource lacks a usage a slot needs (compile).
    #[error(
        "pass `{pass}` uses `{resource}` as {access} in slot `{slot}`, which needs {needed}, but {reason}"
    )]
    UsageNotAllowed {
        /// The pass, by its name in the graph.
        pass: String,
        /// The slot of that pass's stage contract.
        slot: String,
        /// The resource, by its declared name.
        resource: String,
        /// How the slot uses the resource.
        access: String,
        /// The wgpu usage that access needs.
        needed: String,
        /// Why the resource cannot have that usage.
        reason: String,
    },

    /// Two resources or passes share a name (build).
    #[error("duplicate {what} name `{name}`; every {what} in a graph needs a unique name")]
    DuplicateName {
        /// What kind of thing is named twice: "resource" or "pass".
        what: &'static str,
        /// The name used twice.
        name: String,
    },

    /// A pass needs device features the adapter lacks (compile).
    #[error(
        "pass `{pass}` (stage `{stage}`) requires the adapter feature(s) {features}, which this adapter lacks; {instead}"
    )]
    MissingFeature {
        /// The pass, by its name in the graph.
        pass: String,
        /// The pass's stage kind.
        stage: String,
        /// The missing wgpu features, in wgpu's names.
        features: String,
        /// What would run instead, or what to change.
        instead: String,
    },

    /// A binding names a slot the stage does not have (build).
    #[error("pass `{pass}` (stage `{stage}`) has no slot `{slot}`; its slots are: {available}")]
    UnknownSlot {
        /// The pass, by its name in the graph.
        pass: String,
        /// The pass's stage kind.
        stage: String,
        /// The slot of that pass's stage contract.
        slot: String,
        /// The stage's slots, comma-separated.
        available: String,
    },

    /// A required slot is left unbound (build).
    #[error("pass `{pass}` leaves slot `{slot}` unbound; bind it to a resource")]
    UnboundSlot {
        /// The pass, by its name in the graph.
        pass: String,
        /// The slot of that pass's stage contract.
        slot: String,
    },

    /// A binding or pipeline file names a resource that does not exist (build).
    #[error(
        "pass `{pass}` binds `{resource}` to slot `{slot}` but no resource of that name exists; declare it first"
    )]
    UnknownResource {
        /// The pass, by its name in the graph.
        pass: String,
        /// The slot of that pass's stage contract.
        slot: String,
        /// The resource, by its declared name.
        resource: String,
    },

    /// A pass writes an imported read-only or history resource (build).
    #[error("`{resource}` is read-only ({why}); pass `{pass}` cannot write it in slot `{slot}`")]
    ReadOnlyResource {
        /// The pass, by its name in the graph.
        pass: String,
        /// The slot of that pass's stage contract.
        slot: String,
        /// The resource, by its declared name.
        resource: String,
        /// Why it cannot be written, e.g. it is last frame's history.
        why: &'static str,
    },

    /// A pipeline names an implementation the registry does not have (load).
    #[error(
        "no implementation `{implementation}` of stage `{stage}` is registered; known: {known}"
    )]
    UnknownImplementation {
        /// The stage kind whose implementation was asked for.
        stage: String,
        /// The implementation name the pipeline asked for.
        implementation: String,
        /// The implementations registered for that stage.
        known: String,
    },

    /// A pipeline names a stage the registry does not have (load).
    #[error(
        "{file}: pass `{pass}` names stage `{stage}`, which no registered pass crate provides; stages: {known}"
    )]
    UnknownStage {
        /// The pipeline file, as given to the loader.
        file: String,
        /// The pipeline's pass entry that names the stage.
        pass: String,
        /// The stage kind the pass names.
        stage: String,
        /// The stages the registry has.
        known: String,
    },

    /// A size passes one of the adapter's limits (compile).
    #[error("{what} is {value} {unit}, over the adapter's {limit} of {max}; {hint}")]
    LimitExceeded {
        /// The resource or pass, named.
        what: String,
        /// The wgpu limit's name, e.g. `max_buffer_size`.
        limit: &'static str,
        /// The size asked for, in `unit`.
        value: u64,
        /// The adapter's limit, in `unit`.
        max: u64,
        /// The unit of `value` and `max`, e.g. "bytes".
        unit: &'static str,
        /// What to change to fit.
        hint: String,
    },

    /// A size computed from parameters overflows 64 bits (compile).
    #[error(
        "resource `{resource}`: its size overflows 64 bits (element count × element size); use a smaller count"
    )]
    SizeOverflow {
        /// The resource, by its declared name.
        resource: String,
    },

    /// A buffer of no elements (compile): nothing could be bound to it.
    #[error(
        "resource `{resource}` holds no elements, and a buffer holds at least one: {}",
        match param {
            Some(p) => format!("give its size parameter `{p}` (now 0) at least 1"),
            None => "declare a count of at least 1".to_string(),
        }
    )]
    EmptyBuffer {
        /// The resource, by its declared name.
        resource: String,
        /// The size parameter that gave it no elements, if one did.
        param: Option<String>,
    },

    /// A buffer is sized by an undeclared parameter (compile).
    #[error(
        "resource `{resource}` is sized by parameter `{param}`, which is not declared; declare it with size_param (known: {known})"
    )]
    UnknownParam {
        /// The resource, by its declared name.
        resource: String,
        /// The parameter the resource names.
        param: String,
        /// The declared size parameters.
        known: String,
    },

    /// wgpu rejected the frame and no pass was named (execute; checked mode names it).
    #[error(
        "wgpu validation error {when}: {message}; run the executor with `checked = true` to name the pass"
    )]
    FrameValidation {
        /// When wgpu rejected it: while recording or at submit.
        when: &'static str,
        /// wgpu's validation message.
        message: String,
    },

    /// The device was opened without features the compiled graph uses (execute).
    #[error("the device lacks {features}, which the compiled graph uses; {instead}")]
    DeviceLacksFeatures {
        /// The wgpu features the plan uses and the device lacks.
        features: String,
        /// What to change: open the device with them, or compile for this device.
        instead: String,
    },

    /// A resource declaration is impossible in itself, e.g. more mips than its size has
    /// (compile).
    #[error("resource `{resource}`: {problem}")]
    BadDeclaration {
        /// The resource, by its declared name.
        resource: String,
        /// What is impossible about it and what to change.
        problem: String,
    },

    /// `set_param` names a parameter the graph does not have.
    #[error("the graph has no size parameter `{param}` to set; its parameters: {known}")]
    NoSuchParam {
        /// The name given to `set_param`.
        param: String,
        /// The graph's size parameters.
        known: String,
    },

    /// An output was asked of a pass that does not write that slot (build).
    #[error(
        "pass `{pass}` writes no slot `{slot}`, so it has no output of that name; it writes: {written}"
    )]
    NotWritten {
        /// The pass, by its name in the graph.
        pass: String,
        /// The slot asked for.
        slot: String,
        /// The slots the pass does write.
        written: String,
    },

    /// A pass reads a frame input the frame does not supply (execute).
    #[error(
        "pass `{pass}` reads frame input `{input}`, which this frame does not supply; add it to the FrameData given to execute"
    )]
    MissingFrameInput {
        /// The pass, by its name in the graph.
        pass: String,
        /// The frame input's name.
        input: String,
    },

    /// A physical resource could not be created (execute).
    #[error("could not allocate `{resource}`: {message}")]
    Allocation {
        /// The resource, by its declared name.
        resource: String,
        /// wgpu's reason.
        message: String,
    },

    /// A setting of a whole frame (not of one pass) is out of range: the viewport, a
    /// capacity, a grid. Raised by the renderers built on the graph.
    #[error("{setting}: {message}")]
    Setting {
        /// What is set, as its owner names it (`the viewport`, `ClusteringSettings::objects`).
        setting: String,
        /// What is wrong and what to change.
        message: String,
    },

    /// A pass rejects its parameters (setup or load).
    #[error("pass `{pass}` parameter error: {message}")]
    Parameter {
        /// The pass; empty until the loader or compiler fills it in.
        pass: String,
        /// Which parameter is wrong and what it accepts.
        message: String,
    },

    /// A pipeline file cannot be read or used as a whole (load).
    #[error("pipeline file {file}: {message}")]
    PipelineFile {
        /// The pipeline file, as given to the loader.
        file: String,
        /// What is wrong with the file as a whole.
        message: String,
    },

    /// A pipeline file has a problem at a place in its text (load).
    #[error("pipeline file {file}: {problem}")]
    PipelineSource {
        /// The pipeline file, as given to the loader.
        file: String,
        /// The problem and where in the text it is.
        problem: crate::problem::SourceProblem,
    },

    /// A pipeline file's resource declaration is wrong (load).
    #[error("pipeline file {file}: resource `{resource}`: {problem}")]
    PipelineResource {
        /// The pipeline file, as given to the loader.
        file: String,
        /// The resource's name in the file.
        resource: String,
        /// What is wrong with the declaration.
        problem: crate::problem::ResourceProblem,
    },

    /// An imported resource was not given to the frame (execute).
    #[error("imported resource `{resource}` was not supplied to the frame; pass it in the imports")]
    MissingImport {
        /// The resource, by its declared name.
        resource: String,
    },

    /// A supplied import differs from its declaration (execute).
    #[error("imported resource `{resource}` does not match its declaration: {message}")]
    ImportMismatch {
        /// The resource, by its declared name.
        resource: String,
        /// How the supplied object differs from the declaration.
        message: String,
    },

    /// No adapter was found on the backends searched; the message says how to install
    /// one.
    #[error(
        "no GPU adapter found on {backends}{detail}. On Linux without a GPU, install Mesa's software Vulkan driver: `sudo apt-get install mesa-vulkan-drivers` (lavapipe); set MESHLIGHT_ADAPTER to part of a name from `vulkaninfo --summary`, or WGPU_BACKEND to the backends to search"
    )]
    NoAdapter {
        /// The backends searched, as wgpu names them.
        backends: String,
        /// The adapter asked for and those found; empty when none was asked for.
        detail: String,
    },

    /// The device could not be created.
    #[error("could not create the device: {0}")]
    Device(String),

    /// A pass's shader does not compose or validate (execute).
    #[error("shader error in pass `{pass}`: {source}")]
    Shader {
        /// The pass, by its name in the graph.
        pass: String,
        /// The composer's or validator's error.
        #[source]
        source: meshlight_shaders::ShaderError,
    },

    /// wgpu rejected what a named pass recorded (execute).
    #[error("wgpu validation error in pass `{pass}`: {message}")]
    Validation {
        /// The pass, by its name in the graph.
        pass: String,
        /// wgpu's validation message.
        message: String,
    },

    /// A pass's programs could not be built for the device: a shader's bindings do not
    /// match its slots, or the device refuses a pipeline or layout (prepare, before any
    /// frame).
    #[error("pass `{pass}` cannot be prepared for this device: {message}")]
    Prepare {
        /// The pass, by its name in the graph.
        pass: String,
        /// What is wrong and what to change.
        message: String,
    },

    /// A pass failed while recording (execute).
    #[error("pass `{pass}` failed while recording: {message}")]
    Record {
        /// The pass, by its name in the graph.
        pass: String,
        /// What the pass reported.
        message: String,
    },

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
