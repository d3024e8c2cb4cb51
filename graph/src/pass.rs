//! The pass trait: a stage implementation declares what it needs in `setup` and encodes
//! its commands in `record`.

use crate::access::Access;
use crate::adapter::AdapterClass;
use crate::contract::StageContract;
use crate::error::Result;
use crate::program::ProgramDesc;
use crate::record::RecordContext;
use crate::resource::{BufferDesc, ResourceDesc, TextureDesc};
use meshlight_shaders::{ShaderDef, ShaderDefs};

/// One implementation of a stage.
///
/// A pass owns no GPU resources the graph should schedule: everything it reads or writes
/// comes through its slots or through scratch buffers declared in `setup`.
pub trait Pass: Send + Sync {
    /// Which implementation of which stage this pass is: pipeline files, the registry,
    /// `auto` and every report name a pass by this pair.
    fn implementation(&self) -> Implementation;
    /// Declares features, shader defs, scratch buffers and size requirements. Runs at
    /// compile time, with the adapter's features known, so the pass can pick a variant.
    fn setup(&self, ctx: &mut SetupContext) -> Result<()>;
    /// Encodes the pass's commands.
    fn record(&self, ctx: &mut RecordContext<'_>) -> Result<()>;
    /// The form in which this pass writes a 64-bit visibility target it clears. A
    /// target declared with `GraphBuilder::create_visibility64` takes it, so every other
    /// pass bound there (which reads [`SetupContext::is_texture`]) follows. `None`: the
    /// pass adapts to whatever is bound.
    fn visibility64(&self) -> Option<Visibility64> {
        None
    }
}

/// A pass's identity: its name within its stage and the stage's contract. One value, so
/// a pass says what it is in one place.
#[derive(Clone, Debug)]
pub struct Implementation {
    /// The implementation's name within its stage, e.g. `scan_fan` or `two_step`.
    pub name: &'static str,
    /// The contract of the stage this pass implements.
    pub contract: StageContract,
}

impl Implementation {
    /// The implementation `name` of the stage `contract` describes.
    pub fn new(name: &'static str, contract: StageContract) -> Self {
        Self { name, contract }
    }
}

/// How a 64-bit visibility target is held.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Visibility64 {
    /// A buffer of `u64`, written with 64-bit buffer atomics.
    Buffer,
    /// An `R64Uint` storage texture, written with 64-bit texture atomics.
    Texture,
}

impl Visibility64 {
    /// What `atomicMax` onto a target of this form asks of the adapter: 64-bit integers
    /// and the 64-bit atomics of a buffer or of a storage texture. Every rasteriser that
    /// writes the target asks the same, whichever stage it implements.
    pub fn atomic_max_features(self) -> wgpu::Features {
        wgpu::Features::SHADER_INT64
            | match self {
                Visibility64::Buffer => wgpu::Features::SHADER_INT64_ATOMIC_MIN_MAX,
                Visibility64::Texture => {
                    wgpu::Features::TEXTURE_ATOMIC | wgpu::Features::TEXTURE_INT64_ATOMIC
                }
            }
    }
}

/// A scratch buffer or texture private to one pass.
#[derive(Clone, Debug)]
pub struct ScratchDecl {
    pub name: String,
    pub desc: ResourceDesc,
    pub accesses: Vec<Access>,
}

/// What `setup` collects from a pass.
#[derive(Debug)]
pub struct SetupContext<'a> {
    adapter_features: wgpu::Features,
    limits: &'a wgpu::Limits,
    class: AdapterClass,
    params: &'a [(String, u64)],
    bound: Vec<&'static str>,
    textures: Vec<(&'static str, wgpu::TextureFormat)>,
    pub(crate) required: wgpu::Features,
    pub(crate) optional: wgpu::Features,
    pub(crate) shader_defs: Vec<(String, ShaderDef)>,
    pub(crate) scratch: Vec<ScratchDecl>,
    pub(crate) side_effect: bool,
    pub(crate) min_bytes: Vec<(String, u64)>,
    pub(crate) programs: Vec<(String, ProgramDesc)>,
    pub(crate) frame_inputs: Vec<String>,
    pub(crate) dispatches: Vec<(String, [u32; 3])>,
    pub(crate) needs_encoder: Option<String>,
    pub(crate) clears_itself: Vec<String>,
    pub(crate) skipped: Option<String>,
    pub(crate) notes: Vec<String>,
}

impl<'a> SetupContext<'a> {
    pub(crate) fn new(
        adapter_features: wgpu::Features,
        limits: &'a wgpu::Limits,
        class: AdapterClass,
        params: &'a [(String, u64)],
        bound: Vec<&'static str>,
    ) -> Self {
        Self {
            adapter_features,
            limits,
            class,
            params,
            bound,
            textures: Vec::new(),
            required: wgpu::Features::empty(),
            optional: wgpu::Features::empty(),
            shader_defs: Vec::new(),
            scratch: Vec::new(),
            side_effect: false,
            min_bytes: Vec::new(),
            programs: Vec::new(),
            frame_inputs: Vec::new(),
            dispatches: Vec::new(),
            needs_encoder: None,
            clears_itself: Vec::new(),
            skipped: None,
            notes: Vec::new(),
        }
    }
    /// The adapter's features, to choose between variants.
    pub fn adapter_features(&self) -> wgpu::Features {
        self.adapter_features
    }
    /// The adapter's limits (workgroups per dimension, binding sizes, …).
    pub fn limits(&self) -> &wgpu::Limits {
        self.limits
    }
    /// The adapter's class, for a parameter whose best value depends on how the
    /// adapter's units divide between graphics and compute (`auto`).
    pub fn adapter_class(&self) -> AdapterClass {
        self.class
    }
    /// Checks a pass's `max_per_dimension` param, the workgroup limit per dimension its
    /// dispatches are sized for: unset (the adapter's limit) or at most the adapter's
    /// passes; a larger one is a parameter error naming the limit.
    pub fn check_max_per_dimension(&self, asked: Option<u32>) -> Result<()> {
        let limit = self.limits.max_compute_workgroups_per_dimension;
        match asked {
            Some(m) if m > limit => Err(crate::error::GraphError::parameter(format!(
                "`max_per_dimension` = {m} is above the adapter's limit of {limit}; leave it out to use the limit"
            ))),
            _ => Ok(()),
        }
    }
    /// The value of a size parameter at compile time.
    pub fn param(&self, name: &str) -> Option<u64> {
        self.params.iter().find(|(n, _)| n == name).map(|(_, v)| *v)
    }
    /// True when `slot` is bound (always, unless the slot is optional), so setup can pick
    /// the variant that uses it.
    pub fn is_bound(&self, slot: &str) -> bool {
        self.bound.contains(&slot)
    }
    /// True when `slot` is bound to a texture, so a pass whose slot takes a buffer or a
    /// texture (a 64-bit visibility target) picks the matching shader variant.
    pub fn is_texture(&self, slot: &str) -> bool {
        self.format(slot).is_some()
    }
    /// The format of the texture bound to `slot`, so a pass whose slot takes any format
    /// (a host's target) compiles the variant for it (sRGB encoding, channel order).
    pub fn format(&self, slot: &str) -> Option<wgpu::TextureFormat> {
        self.textures
            .iter()
            .find(|(s, _)| *s == slot)
            .map(|(_, f)| *f)
    }
    pub(crate) fn with_textures(
        mut self,
        textures: Vec<(&'static str, wgpu::TextureFormat)>,
    ) -> Self {
        self.textures = textures;
        self
    }
    /// True when the feature will be enabled if the pass asks for it as optional.
    pub fn has(&self, feature: wgpu::Features) -> bool {
        self.adapter_features.contains(feature)
    }
    /// Features the pass cannot run without; compile fails with [`crate::GraphError::MissingFeature`]
    /// where the adapter lacks one.
    pub fn require_features(&mut self, features: wgpu::Features) {
        self.required |= features;
    }
    /// Features the pass uses where the adapter has them; check [`SetupContext::has`] to pick
    /// the variant.
    pub fn optional_features(&mut self, features: wgpu::Features) {
        self.optional |= features;
    }
    /// Records the defs a variant compiles with, so dumps show which variant runs.
    pub fn shader_defs(&mut self, defs: &impl ShaderDefs) {
        for (name, value) in defs.shader_defs() {
            self.shader_defs.retain(|(n, _)| n != name);
            self.shader_defs.push((name.to_string(), value));
        }
    }
    /// Declares a buffer only this pass uses; the graph pools it like any transient.
    pub fn scratch_buffer(&mut self, name: &str, desc: BufferDesc, accesses: &[Access]) {
        self.scratch.push(ScratchDecl {
            name: name.to_string(),
            desc: ResourceDesc::Buffer(desc),
            accesses: accesses.to_vec(),
        });
    }
    /// Declares a texture only this pass uses, e.g. the colour target a render pipeline
    /// must have when its fragment shader writes only storage (a render target here is
    /// cleared and discarded, so it costs no memory traffic).
    pub fn scratch_texture(&mut self, name: &str, desc: TextureDesc, accesses: &[Access]) {
        self.scratch.push(ScratchDecl {
            name: name.to_string(),
            desc: ResourceDesc::Texture(desc),
            accesses: accesses.to_vec(),
        });
    }
    /// Declares a program the pass records with; `record` fetches it by `name`. The plan
    /// and its dumps list it with its exact defs.
    pub fn program(&mut self, name: &str, desc: ProgramDesc) {
        self.required |= desc.required_features();
        if let crate::program::ProgramKind::Render { primitive, .. } = &desc.kind
            && primitive.unclipped_depth
        {
            self.optional |= wgpu::Features::DEPTH_CLIP_CONTROL;
        }
        if desc.immediate_size > 0 {
            self.optional |= wgpu::Features::IMMEDIATES;
        }
        self.programs.retain(|(n, _)| n != name);
        self.programs.push((name.to_string(), desc));
    }
    /// Declares a per-frame input the pass reads in `record` (`RecordContext::frame_bytes`);
    /// a frame that does not supply it fails with an error naming the pass and the input.
    pub fn frame_input(&mut self, name: &str) {
        if !self.frame_inputs.iter().any(|n| n == name) {
            self.frame_inputs.push(name.to_string());
        }
    }
    /// Declares the largest workgroup grid a dispatch of this pass uses, so a grid over
    /// the adapter's per-dimension limit is a compile error instead of a device error.
    pub fn dispatch(&mut self, label: &str, groups: [u32; 3]) {
        self.dispatches.push((label.to_string(), groups));
    }
    /// Declares that `record` takes the command encoder (`RecordContext::encoder`) for
    /// something compile cannot see from slots and programs (a query, a debug copy), so
    /// the pass is recorded on the encoder instead of inside a batch's shared compute
    /// pass. `why` is shown in the plan and its dumps.
    pub fn needs_encoder(&mut self, why: &str) {
        self.needs_encoder = Some(why.to_string());
    }
    /// Declares that the pass clears the texture bound to `slot` (a `ClearedReadWrite`
    /// slot) with its own dispatch and never calls `RecordContext::clear` on it, so the
    /// slot does not take the pass out of its batch.
    pub fn clears_itself(&mut self, slot: &str) {
        self.clears_itself.push(slot.to_string());
    }
    /// Declares that the pass has nothing to do on this adapter, and why: it stays in the
    /// plan (what it writes keeps its versions, and the dumps show it with `why`) but
    /// records nothing. For a pass that measurements say not to run on an adapter class
    /// (a hardware rasteriser where few units run graphics) while the frame stays one
    /// pipeline. A skipped pass should declare nothing else.
    pub fn skip(&mut self, why: &str) {
        self.skipped = Some(why.to_string());
    }
    /// Records how the pass settled something it was left to decide (a parameter given
    /// as `auto`, say), so the plan and its dumps say what it chose and why.
    pub fn note(&mut self, decision: String) {
        self.notes.push(decision);
    }
    /// Marks the pass as having an effect outside the graph (readback, logging), so it is
    /// never culled.
    pub fn side_effect(&mut self) {
        self.side_effect = true;
    }
    /// Requires the resource bound to `slot` to be at least `bytes` long.
    pub fn min_bytes(&mut self, slot: &str, bytes: u64) {
        self.min_bytes.push((slot.to_string(), bytes));
    }
}
