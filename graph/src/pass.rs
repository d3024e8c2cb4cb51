//! The pass trait: a stage implementation declares what it needs in `setup` and encodes
//! its commands in `record`.

use crate::access::Access;
use crate::contract::StageContract;
use crate::error::Result;
use crate::exec::RecordContext;
use crate::resource::BufferDesc;
use meshlight_shaders::{ShaderDef, ShaderDefs};

/// One implementation of a stage.
///
/// A pass owns no GPU resources the graph should schedule: everything it reads or writes
/// comes through its slots or through scratch buffers declared in `setup`.
pub trait Pass: Send + Sync {
    /// The contract of the stage this pass implements.
    fn contract(&self) -> StageContract;
    /// The implementation's name within its stage, e.g. `scan_fan` or `two_step`.
    fn implementation(&self) -> &'static str;
    /// Declares features, shader defs, scratch buffers and size requirements. Runs at
    /// compile time, with the adapter's features known, so the pass can pick a variant.
    fn setup(&self, ctx: &mut SetupContext) -> Result<()>;
    /// Encodes the pass's commands.
    fn record(&self, ctx: &mut RecordContext<'_>) -> Result<()>;
}

/// A scratch buffer private to one pass.
#[derive(Clone, Debug)]
pub struct ScratchDecl {
    pub name: String,
    pub desc: BufferDesc,
    pub accesses: Vec<Access>,
}

/// What `setup` collects from a pass.
#[derive(Debug)]
pub struct SetupContext {
    adapter_features: wgpu::Features,
    bound: Vec<&'static str>,
    pub(crate) required: wgpu::Features,
    pub(crate) optional: wgpu::Features,
    pub(crate) shader_defs: Vec<(String, ShaderDef)>,
    pub(crate) scratch: Vec<ScratchDecl>,
    pub(crate) side_effect: bool,
    pub(crate) min_bytes: Vec<(String, u64)>,
}

impl SetupContext {
    pub(crate) fn new(adapter_features: wgpu::Features, bound: Vec<&'static str>) -> Self {
        Self {
            adapter_features,
            bound,
            required: wgpu::Features::empty(),
            optional: wgpu::Features::empty(),
            shader_defs: Vec::new(),
            scratch: Vec::new(),
            side_effect: false,
            min_bytes: Vec::new(),
        }
    }
    /// The adapter's features, to choose between variants.
    pub fn adapter_features(&self) -> wgpu::Features {
        self.adapter_features
    }
    /// True when `slot` is bound (always, unless the slot is optional), so setup can pick
    /// the variant that uses it.
    pub fn is_bound(&self, slot: &str) -> bool {
        self.bound.contains(&slot)
    }
    /// True when the feature will be enabled if the pass asks for it as optional.
    pub fn has(&self, feature: wgpu::Features) -> bool {
        self.adapter_features.contains(feature)
    }
    pub fn require_features(&mut self, features: wgpu::Features) {
        self.required |= features;
    }
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
            desc,
            accesses: accesses.to_vec(),
        });
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
