//! The instance table as passes bind it: slot `instances`, and slot `instances_high`
//! when the table is larger than one storage binding may be.
//!
//! A device binds at most `max_storage_buffer_binding_size` bytes of a buffer to one
//! slot (128 MiB by default: 599,186 instances of 224 bytes). Rather than refuse a
//! larger scene, [`crate::GpuScene`] fills `instances` to that limit and puts the rest
//! in `instances_high`; every pass that reads instances imports the WGSL module
//! `meshlight::instance_table` and reads them through `instance_at(i)`, which picks the
//! binding. A pass declares the optional slot with [`high_slot`] and in setup composes its
//! programs with the defs of [`InstanceTable::of`]; a layout read from the shader then
//! binds `instances` (and `instances_high`) by name. A scene that fits one binding binds
//! only `instances` and compiles without the branch.

use crate::gpu::elements;
use crate::names;
use meshlight_graph::{RecordContext, Result, SetupContext, ShaderDef, ShaderDefs, Slot};

/// The optional second binding's slot (and the GPU scene's buffer of that name).
pub const HIGH_SLOT: &str = names::INSTANCES_HIGH;
/// The def that turns on the second binding in `meshlight::instance_table`.
pub const HIGH_DEF: &str = "INSTANCES_HIGH";

/// The optional `instances_high` slot, for a stage contract beside `instances`.
pub fn high_slot() -> Slot {
    Slot::read(
        HIGH_SLOT,
        elements::INSTANCE,
        "the scene's instances past what one binding holds (bound only when the scene needs it)",
    )
    .optional()
}

/// Which variant of the instance table a pass compiles: one binding or two.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct InstanceTable {
    /// The instances take two bindings: `instances_high` is bound and `INSTANCES_HIGH` defined.
    pub split: bool,
}

impl InstanceTable {
    /// The variant the pass's bindings ask for: split when `instances_high` is bound.
    pub fn of(ctx: &SetupContext) -> Self {
        Self {
            split: ctx.is_bound(HIGH_SLOT),
        }
    }
}

impl ShaderDefs for InstanceTable {
    fn shader_defs(&self) -> Vec<(&'static str, ShaderDef)> {
        if self.split {
            vec![(HIGH_DEF, ShaderDef::Bool(true))]
        } else {
            Vec::new()
        }
    }
}

/// How many instances the bound table holds, both bindings together (what
/// `instance_total()` returns in WGSL).
pub fn bound_instances(ctx: &RecordContext<'_>) -> Result<u32> {
    let size = size_of::<meshlight_shaders::cpu::layout::Instance>() as u64;
    let (_, low) = ctx.buffer(names::INSTANCES)?;
    let high = if ctx.is_bound(HIGH_SLOT) {
        ctx.buffer(HIGH_SLOT)?.1
    } else {
        0
    };
    Ok(((low + high) / size).min(u32::MAX as u64) as u32)
}
