//! The compiled plan as plain data: what dumps print and what the executor follows.

use crate::access::Access;
use crate::names::{ser_buffer_usages, ser_features, ser_texture_usages};
use crate::program::ProgramPlan;
use crate::resource::{ResourceDesc, ResourceInfo, TextureRange};
use serde::Serialize;

/// How a render target is loaded and stored by one pass.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum LoadOp {
    /// Earlier contents matter: load them.
    Load,
    /// Nothing wrote it yet this frame: clear.
    Clear,
}

/// What a render pass does with an attachment at its end.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum StoreOp {
    /// A later pass reads the result: keep it.
    Store,
    /// Nothing reads the result: let the GPU drop it.
    Discard,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
pub struct AttachmentOps {
    pub load: LoadOp,
    pub store: StoreOp,
}

#[derive(Clone, Debug, Serialize)]
pub struct SlotUse {
    pub slot: &'static str,
    pub resource: usize,
    pub access: Access,
    /// Further uses in the same pass (indirect arguments, copies).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub also: Vec<Access>,
    /// The version read (or written from).
    pub version: u32,
    /// The version produced, for writes.
    pub writes_version: Option<u32>,
    /// For render and depth targets.
    pub ops: Option<AttachmentOps>,
    /// The mips and layers bound, for textures bound in part.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub range: Option<TextureRange>,
}

impl SlotUse {
    pub fn accesses(&self) -> impl Iterator<Item = Access> + Clone + '_ {
        std::iter::once(self.access).chain(self.also.iter().copied())
    }
    pub fn reads(&self) -> bool {
        crate::access::reads_earlier(self.accesses())
    }
    /// `storage-read-write+indirect`, with the range when the slot binds part of a texture.
    pub fn access_name(&self) -> String {
        let mut s = self
            .accesses()
            .map(Access::name)
            .collect::<Vec<_>>()
            .join("+");
        if let Some(r) = &self.range {
            s.push_str(&format!(" [{}]", r.label()));
        }
        s
    }
}

#[derive(Clone, Debug, Serialize)]
pub struct PassPlan {
    pub name: String,
    pub stage: &'static str,
    pub implementation: &'static str,
    /// How the implementation was picked, when the pass had several (`auto`, or a named
    /// one with alternatives).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub choice: Option<ChoicePlan>,
    pub slots: Vec<SlotUse>,
    /// Scratch resources this pass declared.
    pub scratch: Vec<usize>,
    pub shader_defs: Vec<(String, String)>,
    /// The programs declared in setup, with the exact defs each runs with.
    pub programs: Vec<ProgramPlan>,
    /// Per-frame inputs the pass reads.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub frame_inputs: Vec<String>,
    #[serde(serialize_with = "ser_features")]
    pub required_features: wgpu::Features,
    #[serde(serialize_with = "ser_features")]
    pub optional_features: wgpu::Features,
    pub side_effect: bool,
    /// How the executor records the pass: inside a batch's shared compute pass, or on the
    /// frame's command encoder.
    pub recording: Recording,
    /// Why the pass records nothing on this adapter (`SetupContext::skip`), when it does
    /// not.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub skipped: Option<String>,
    /// What the pass settled in setup that it was left to decide, and why
    /// (`SetupContext::note`).
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub notes: Vec<String>,
}

/// How a pass is recorded.
///
/// A pass is `Compute` (batched) unless compile sees it needs the command encoder: it
/// declared a render or mesh program, a slot or scratch resource is used as a copy
/// source or destination, render or depth target, vertex or index buffer, it clears a
/// texture (`ClearedReadWrite` on a texture slot, which `RecordContext::clear` turns into
/// a texture clear), or its setup called `SetupContext::needs_encoder`. A `Compute` pass
/// records its dispatches into the batch's shared compute pass, and its buffer clears
/// become dispatches of the graph's fill program there.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Recording {
    /// Recorded into its batch's shared compute pass.
    Compute,
    /// Why the pass needs the encoder.
    Encoder(String),
}

impl Recording {
    /// True when the pass is batched with other compute passes.
    pub fn is_compute(&self) -> bool {
        matches!(self, Recording::Compute)
    }
}

/// A run of consecutive passes in execution order that the executor records together:
/// compute-only passes share one wgpu compute pass (wgpu puts the barrier each dependent
/// dispatch needs inside it); a pass that needs the encoder is a batch of its own.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
pub struct Batch {
    /// Indices into `Plan::passes`, in execution order.
    pub passes: Vec<usize>,
    /// True for a shared compute pass, false for one pass recorded on the encoder.
    pub compute: bool,
}

impl Batch {
    /// `batch 3` for an encoder pass, `batch 3 (compute ×5)` for a shared compute pass.
    pub fn label(&self, index: usize) -> String {
        if self.compute {
            format!("batch {index} (compute ×{})", self.passes.len())
        } else {
            format!("batch {index} (encoder)")
        }
    }
}

/// Groups `order` into batches by each pass's recording.
pub fn batches_of(passes: &[PassPlan], order: &[usize]) -> Vec<Batch> {
    let mut batches: Vec<Batch> = Vec::new();
    for &p in order {
        let compute = passes[p].recording.is_compute();
        match batches.last_mut() {
            Some(b) if compute && b.compute => b.passes.push(p),
            _ => batches.push(Batch {
                passes: vec![p],
                compute,
            }),
        }
    }
    batches
}

impl PassPlan {
    /// `implementation`, marked `(auto)` when compile picked it by the adapter and
    /// `(skipped)` when it records nothing there.
    pub fn implementation_label(&self) -> String {
        let label = match &self.choice {
            Some(c) if c.selection == Selection::Auto => {
                format!("{} (auto)", self.implementation)
            }
            _ => self.implementation.to_string(),
        };
        if self.skipped.is_some() {
            format!("{label} (skipped)")
        } else {
            label
        }
    }
    /// Why compile picked this implementation, for passes with several.
    pub fn choice_reason(&self) -> Option<&str> {
        self.choice.as_ref().map(|c| c.reason.as_str())
    }
    /// What the plan says about how this pass was decided: why it is skipped, why its
    /// implementation was picked, or both.
    pub fn decision(&self) -> Option<String> {
        let parts: Vec<String> = self
            .skipped
            .iter()
            .map(|skip| format!("skipped: {skip}"))
            .chain(self.choice_reason().map(str::to_string))
            .chain(self.notes.iter().cloned())
            .collect();
        (!parts.is_empty()).then(|| parts.join("; "))
    }
}

#[derive(Clone, Debug, Serialize)]
pub struct ResourcePlan {
    #[serde(flatten)]
    pub info: ResourceInfo,
    /// Number of versions written this frame.
    pub versions: u32,
    pub lifetime: Option<Lifetime>,
    pub pool_slot: Option<usize>,
    #[serde(serialize_with = "ser_buffer_usages")]
    pub buffer_usage: wgpu::BufferUsages,
    #[serde(serialize_with = "ser_texture_usages")]
    pub texture_usage: wgpu::TextureUsages,
}

/// A compiled graph's schedule: passes in order, resources with lifetimes and pool slots,
/// edges, batches and parameters. Dumps read it.
#[derive(Clone, Debug, Serialize)]
pub struct Plan {
    /// Every pass, culled ones included, in the order they were added.
    pub passes: Vec<PassPlan>,
    /// Indices into `passes`, in execution order (culled passes left out).
    pub order: Vec<usize>,
    /// `order` grouped into what the executor records together (see [`Batch`]).
    pub batches: Vec<Batch>,
    /// Indices into `passes` of the passes culled: nothing visible outside the frame
    /// depends on them.
    pub culled: Vec<usize>,
    /// Every resource, in declaration order, with its lifetime, pool slot and usages.
    pub resources: Vec<ResourcePlan>,
    /// Dependencies between passes, labelled with the resource version and access.
    pub edges: Vec<Edge>,
    /// The pool's slots: transients whose lifetimes do not overlap share one.
    pub pool_slots: Vec<PoolSlot>,
    /// Transient bytes with a resource each.
    pub bytes_without_reuse: u64,
    /// Transient bytes with pool slots shared: what the executor allocates.
    pub bytes_with_reuse: u64,
    /// The features the device must have: every pass's required ones and the optional
    /// ones the adapter has; open the device with these.
    #[serde(serialize_with = "ser_features")]
    pub enabled_features: wgpu::Features,
    /// The adapter class the plan was made for: what `auto` choices and parameters
    /// followed where they depend on it.
    pub class: crate::adapter::AdapterClass,
    /// Size parameters and their current values.
    pub params: Vec<(String, u64)>,
    /// Bumped by every re-plan (a size parameter changed), so the executor knows to
    /// replace resources.
    pub generation: u64,
}

impl Plan {
    /// The index in `passes` of the pass named `name`.
    pub fn pass_index(&self, name: &str) -> Option<usize> {
        self.passes.iter().position(|p| p.name == name)
    }
    /// The index in `resources` of the resource named `name`.
    pub fn resource_index(&self, name: &str) -> Option<usize> {
        self.resources.iter().position(|r| r.info.name == name)
    }
    /// True when compile culled the pass at index `pass`.
    pub fn is_culled(&self, pass: usize) -> bool {
        self.culled.contains(&pass)
    }
    /// The current value of the size parameter `name`.
    pub(crate) fn param(&self, name: &str) -> Option<u64> {
        self.params.iter().find(|(n, _)| n == name).map(|(_, v)| *v)
    }
    /// The batch a pass runs in, `None` for culled passes.
    pub fn batch_of(&self, pass: usize) -> Option<usize> {
        self.batches.iter().position(|b| b.passes.contains(&pass))
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum EdgeKind {
    /// The later pass reads what the earlier one wrote.
    ReadAfterWrite,
    /// The later pass overwrites what the earlier one read.
    WriteAfterRead,
    /// The later pass overwrites what the earlier one wrote.
    WriteAfterWrite,
}

#[derive(Clone, Debug, PartialEq, Eq, PartialOrd, Ord, Serialize)]
pub struct Edge {
    pub from: usize,
    pub to: usize,
    pub resource: usize,
    pub version: u32,
    pub kind: EdgeKind,
}

/// First and last position (in the executed order) at which a resource is used.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
pub struct Lifetime {
    pub first: usize,
    pub last: usize,
}

impl Lifetime {
    pub fn overlaps(&self, other: &Lifetime) -> bool {
        self.first <= other.last && other.first <= self.last
    }
}

#[derive(Clone, Debug, Serialize)]
pub struct PoolSlot {
    pub index: usize,
    /// Descriptor of the physical resource: the largest member for buffers.
    pub desc: ResourceDesc,
    pub bytes: u64,
    /// Resource indices, in the order they use the slot.
    pub members: Vec<usize>,
    #[serde(skip)]
    pub(crate) last_use: usize,
}

/// How a pass instance's implementation was decided.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Selection {
    /// The one implementation the graph was given.
    Fixed,
    /// `auto`: the best candidate the adapter runs.
    Auto,
    /// The pipeline named the first candidate; the rest are alternatives for messages.
    Named,
}

/// One candidate as compile judged it.
#[derive(Clone, Debug, Serialize)]
pub struct CandidatePlan {
    /// The candidate's implementation name.
    pub implementation: &'static str,
    /// Features its setup asked for that the adapter lacks (empty: it runs here).
    pub missing: Vec<String>,
    /// Why its setup refused the pass's parameters, where it did (it does not run).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub refused: Option<String>,
}

/// What compile decided for a pass with several candidates, for dumps and `info`.
#[derive(Clone, Debug, Serialize)]
pub struct ChoicePlan {
    /// How the choice was made: auto, or named by the pipeline.
    pub selection: Selection,
    /// The implementation compile kept.
    pub chosen: &'static str,
    /// One sentence: why this one.
    pub reason: String,
    /// Every candidate, in preference order, with what it lacks here.
    pub candidates: Vec<CandidatePlan>,
}
