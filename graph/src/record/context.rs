//! What a pass sees while recording: its bound resources by slot name, the programs it
//! declared in setup, bind groups, the frame's inputs, and the command encoder.

use crate::contract::StageContract;
use crate::error::{GraphError, Result};
use crate::layout::BindingSource;
use crate::plan::{AttachmentOps, LoadOp, Plan, StoreOp};
use crate::program::{ProgramDesc, ProgramKind};
use crate::record::fill::Fill;
use crate::record::frame::FrameData;
use crate::record::physical::Physical;
use crate::record::programs::{
    AnyProgram, BindGroupKey, BoundResource, CHUNK, ComputeProgram, ImmediateMode, Program,
    Programs, RenderProgram,
};
use crate::record::readback::Readbacks;
use crate::record::shared::{ComputePassGuard, SharedPass, Unplanned};
use crate::record::views::ViewCache;
use crate::resource::{ResourceDesc, ResourceKind, TextureRange};
use std::sync::Arc;

/// A colour attachment of [`RecordContext::render_pass`]: a target slot or scratch
/// texture, and the colour it is cleared to when the compiler chose to clear it.
#[derive(Clone, Copy, Debug)]
pub struct ColorAttachment {
    /// The slot or scratch texture drawn into.
    pub target: &'static str,
    /// The clear colour, used only when the compiler chose to clear (nothing written it
    /// before).
    pub clear: wgpu::Color,
}

impl ColorAttachment {
    /// The colour target `target`, cleared to transparent black.
    pub fn new(target: &'static str) -> Self {
        Self {
            target,
            clear: wgpu::Color::TRANSPARENT,
        }
    }
    /// Clears to `color` instead of transparent black.
    pub fn clear(mut self, color: wgpu::Color) -> Self {
        self.clear = color;
        self
    }
}

/// The depth attachment of [`RecordContext::render_pass`].
#[derive(Clone, Copy, Debug)]
pub struct DepthAttachment {
    /// The depth slot or scratch texture.
    pub target: &'static str,
    /// The depth it is cleared to, used only when the compiler chose to clear.
    pub clear: f32,
}

/// Immediate data ready to set on a pass: natively, or as the fallback uniform block.
pub struct Immediates {
    inner: ImmediatesInner,
}

enum ImmediatesInner {
    None,
    Native(Vec<u8>),
    Uniform {
        group: u32,
        bind_group: wgpu::BindGroup,
    },
}

impl Immediates {
    /// Sets the data on a compute pass before its dispatches.
    pub fn set_on_compute(&self, pass: &mut wgpu::ComputePass<'_>) {
        self.set_on(pass)
    }
    /// Sets the data on a render pass before its draws.
    pub fn set_on_render(&self, pass: &mut wgpu::RenderPass<'_>) {
        self.set_on(pass)
    }
    /// The one way immediates reach either kind of pass.
    fn set_on(&self, pass: &mut impl TakesImmediates) {
        match &self.inner {
            ImmediatesInner::None => {}
            ImmediatesInner::Native(bytes) => pass.native(bytes),
            ImmediatesInner::Uniform { group, bind_group } => pass.uniform(*group, bind_group),
        }
    }
}

/// A pass immediates are set on: compute and render passes spell the two calls alike
/// but share no wgpu trait, so this one lets [`Immediates`] match its form once.
trait TakesImmediates {
    /// The bytes as native immediate data, from offset 0.
    fn native(&mut self, bytes: &[u8]);
    /// The fallback uniform block's bind group, at `group`.
    fn uniform(&mut self, group: u32, bind_group: &wgpu::BindGroup);
}

macro_rules! takes_immediates {
    ($($pass:ty),*) => {$(
        impl TakesImmediates for $pass {
            fn native(&mut self, bytes: &[u8]) {
                self.set_immediates(0, bytes)
            }
            fn uniform(&mut self, group: u32, bind_group: &wgpu::BindGroup) {
                self.set_bind_group(group, bind_group, &[])
            }
        }
    )*};
}
takes_immediates!(wgpu::ComputePass<'_>, wgpu::RenderPass<'_>);

/// What `Pass::record` gets: the pass's bound resources, its programs, bind groups, the
/// frame's inputs and the command encoder.
pub struct RecordContext<'a> {
    pub(crate) device: &'a wgpu::Device,
    pub(crate) queue: &'a wgpu::Queue,
    pub(crate) features: wgpu::Features,
    pub(crate) encoder: &'a mut wgpu::CommandEncoder,
    /// The pass instance's name, for labels and errors.
    pub(crate) name: &'a str,
    /// (frame input the pass reads, the frame input supplied for it).
    pub(crate) inputs: &'a [(String, String)],
    /// The pass's stage contract with its unbound optional slots removed.
    pub(crate) contract: &'a StageContract,
    /// The programs the pass declared in setup, in declaration order.
    pub(crate) declared: &'a [(String, Arc<ProgramDesc>)],
    pub(crate) pass_index: usize,
    pub(crate) plan: &'a Plan,
    pub(crate) physical: &'a [Option<Physical>],
    pub(crate) programs: &'a mut Programs,
    pub(crate) views: &'a mut ViewCache,
    pub(crate) readbacks: &'a mut Readbacks,
    pub(crate) frame_data: &'a FrameData,
    pub(crate) frame_index: u64,
    /// Per resource: for a history pair, whether `prev` holds last frame's contents.
    pub(crate) history_valid: &'a [bool],
    /// The batch's shared compute pass; used only when `batched`.
    pub(crate) shared: &'a mut SharedPass,
    /// True when this pass records into the batch's shared compute pass.
    pub(crate) batched: bool,
    pub(crate) fill: &'a Fill,
    /// `CompiledGraph::id`, under which the programs this pass resolved are kept.
    pub(crate) graph_id: u64,
}

/// How many workgroups [`RecordContext::dispatch_compute`] runs: a grid known when
/// recording, or the `[x, y, z]` arguments a kernel of the frame wrote at `offset` of a
/// buffer (an `Indirect` slot).
#[derive(Clone, Copy, Debug)]
pub enum Workgroups<'b> {
    /// `[x, y, z]` workgroups.
    Direct([u32; 3]),
    /// The arguments at this byte offset of this buffer.
    Indirect(&'b wgpu::Buffer, u64),
}

impl<'a> RecordContext<'a> {
    /// The device, to create what the pass makes per frame (buffers for uploads).
    pub fn device(&self) -> &wgpu::Device {
        self.device
    }
    /// The workgroup limit per dimension to size dispatches for: a pass's
    /// `max_per_dimension` when set (checked at setup by
    /// [`SetupContext::check_max_per_dimension`](crate::SetupContext::check_max_per_dimension)),
    /// else the adapter's; never above the adapter's.
    pub fn max_per_dimension(&self, asked: Option<u32>) -> u32 {
        let limit = self.device.limits().max_compute_workgroups_per_dimension;
        asked.unwrap_or(limit).min(limit)
    }
    /// The queue, to upload per-frame data before the frame is submitted.
    pub fn queue(&self) -> &wgpu::Queue {
        self.queue
    }
    /// Features enabled on the device (the pass's optional features among them).
    pub fn features(&self) -> wgpu::Features {
        self.features
    }
    /// The frame's command encoder. A batched pass (the plan says `Compute`) that takes it
    /// ends its batch's compute pass here, so the commands stay in order; that costs a
    /// pass boundary the plan does not show, and checked mode reports it as an error:
    /// declare such a pass with `SetupContext::needs_encoder`.
    pub fn encoder(&mut self) -> &mut wgpu::CommandEncoder {
        self.leave_batch("encoder()");
        self.encoder
    }

    /// True when the pass records into its batch's shared compute pass.
    pub fn is_batched(&self) -> bool {
        self.batched
    }

    /// Ends the shared compute pass before an encoder command, noting the split.
    fn leave_batch(&mut self, what: &'static str) {
        if self.batched && self.shared.split() {
            self.shared.unplanned.push(Unplanned {
                pass: self.name.to_string(),
                what,
            });
        }
    }
    /// The pass instance's name in the graph, for labels and messages.
    pub fn pass_name(&self) -> &str {
        self.name
    }
    /// The adapter class the graph was compiled for, so a parameter left `auto` in
    /// setup resolves the same way when the pass records.
    pub fn adapter_class(&self) -> crate::adapter::AdapterClass {
        self.plan.class
    }
    /// The executor's frame counter, from 0.
    pub fn frame_index(&self) -> u64 {
        self.frame_index
    }
    /// A per-frame input the pass declared with `SetupContext::frame_input`.
    pub fn frame_bytes(&self, name: &str) -> Result<&'a [u8]> {
        let supplied = (self.inputs.iter())
            .find(|(read, _)| read == name)
            .map_or(name, |(_, s)| s.as_str());
        self.frame_data
            .get(supplied)
            .ok_or_else(|| GraphError::MissingFrameInput {
                pass: self.name.to_string(),
                input: supplied.to_string(),
            })
    }
    /// A per-frame u32 input (`FrameData::u32`).
    pub fn frame_u32(&self, name: &str) -> Result<u32> {
        let bytes = self.frame_bytes(name)?;
        bytes
            .get(..4)
            .map(|b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
            .ok_or_else(|| self.err(format!("frame input `{name}` holds fewer than 4 bytes")))
    }
    /// True when the history resource bound to `slot` (either half) holds last frame's
    /// contents: false on the first frame and after it was resized.
    pub fn history_valid(&self, slot: &str) -> Result<bool> {
        let r = self.slot_resource(slot)?;
        Ok(match self.plan.resources[r].info.kind {
            ResourceKind::History { .. } | ResourceKind::HistoryPrev { .. } => {
                self.history_valid[r]
            }
            _ => false,
        })
    }
    /// The current value of a size parameter.
    pub fn param(&self, name: &str) -> Option<u64> {
        self.plan.param(name)
    }

    fn err(&self, message: String) -> GraphError {
        GraphError::Record {
            pass: self.name.to_string(),
            message,
        }
    }

    fn slot_use(&self, slot: &str) -> Result<&'a crate::plan::SlotUse> {
        let pass = &self.plan.passes[self.pass_index];
        pass.slots
            .iter()
            .find(|s| s.slot == slot)
            .ok_or_else(|| GraphError::UnknownSlot {
                pass: self.name.to_string(),
                stage: pass.stage.to_string(),
                slot: slot.to_string(),
                available: pass
                    .slots
                    .iter()
                    .map(|s| s.slot)
                    .collect::<Vec<_>>()
                    .join(", "),
            })
    }
    fn slot_resource(&self, slot: &str) -> Result<usize> {
        self.slot_use(slot).map(|s| s.resource)
    }
    fn scratch_resource(&self, name: &str) -> Result<usize> {
        let full = format!("{}/{}", self.name, name);
        self.plan.passes[self.pass_index]
            .scratch
            .iter()
            .copied()
            .find(|&r| self.plan.resources[r].info.name == full)
            .ok_or_else(|| {
                self.err(format!(
                    "no scratch resource `{name}`; declare it in setup with scratch_buffer or scratch_texture"
                ))
            })
    }
    fn physical(&self, r: usize) -> Result<&'a Physical> {
        self.physical[r].as_ref().ok_or_else(|| {
            self.err(format!(
                "resource `{}` has no GPU allocation",
                self.plan.resources[r].info.name
            ))
        })
    }
    fn buffer_of(&self, r: usize) -> Result<(&'a wgpu::Buffer, u64)> {
        match self.physical(r)? {
            Physical::Buffer { buffer, size } => Ok((buffer, *size)),
            Physical::Texture { .. } => Err(self.err(format!(
                "`{}` is a texture, not a buffer",
                self.plan.resources[r].info.name
            ))),
        }
    }
    /// The resource a name refers to, with the texture range a slot binds: a slot of the
    /// pass, else a scratch resource it declared (render targets may be either).
    fn named(&self, name: &str) -> Result<(usize, Option<TextureRange>)> {
        match self.slot_use(name) {
            Ok(s) => Ok((s.resource, s.range)),
            Err(e) => self
                .scratch_resource(name)
                .map(|r| (r, None))
                .map_err(|_| e),
        }
    }

    /// What a binding of the named slot or scratch resource binds: the buffer, or the view
    /// of the part of the texture it binds.
    fn bound(&mut self, name: &str) -> Result<BoundResource> {
        let (r, range) = self.named(name)?;
        Ok(match self.physical(r)? {
            Physical::Buffer { buffer, size } => BoundResource::Buffer {
                buffer: buffer.clone(),
                offset: 0,
                size: (*size).max(4),
            },
            Physical::Texture { texture, view } => BoundResource::View(match range {
                Some(range) => self.views.range(texture, range, self.frame_index),
                None => view.clone(),
            }),
        })
    }

    /// A slot's (or scratch) texture and the view of the part it binds.
    fn target_view(&mut self, name: &str) -> Result<(wgpu::Texture, wgpu::TextureView)> {
        let (r, _) = self.named(name)?;
        let texture = match self.physical(r)? {
            Physical::Texture { texture, .. } => texture.clone(),
            Physical::Buffer { .. } => {
                return Err(self.err(format!("`{name}` is a buffer, not a texture")));
            }
        };
        match self.bound(name)? {
            BoundResource::View(view) => Ok((texture, view)),
            _ => unreachable!("a texture binds a view"),
        }
    }

    /// True when `slot` is bound (always, unless the slot is optional).
    pub fn is_bound(&self, slot: &str) -> bool {
        self.contract.slot(slot).is_some()
    }
    /// The buffer bound to `slot`, and its size in bytes (the pooled buffer may be larger).
    pub fn buffer(&self, slot: &str) -> Result<(&'a wgpu::Buffer, u64)> {
        self.buffer_of(self.slot_resource(slot)?)
    }
    /// A scratch buffer declared in setup.
    pub fn scratch(&self, name: &str) -> Result<(&'a wgpu::Buffer, u64)> {
        self.buffer_of(self.scratch_resource(name)?)
    }
    /// The texture bound to `slot` and the view of the mips and layers it binds.
    pub fn texture(&mut self, slot: &str) -> Result<(wgpu::Texture, wgpu::TextureView)> {
        self.slot_use(slot)?;
        self.target_view(slot)
    }
    /// The descriptor of the resource bound to `slot`.
    pub fn desc(&self, slot: &str) -> Result<&'a ResourceDesc> {
        Ok(&self.plan.resources[self.slot_resource(slot)?].info.desc)
    }
    /// The mips and layers `slot` binds (the whole texture unless bound in part).
    pub fn range(&self, slot: &str) -> Result<Option<TextureRange>> {
        let s = self.slot_use(slot)?;
        Ok(
            match (&self.plan.resources[s.resource].info.desc, s.range) {
                (_, Some(r)) => Some(r),
                (ResourceDesc::Texture(t), None) => Some(t.full_range()),
                _ => None,
            },
        )
    }
    /// Load and store ops the compiler derived for a render or depth target slot.
    pub fn attachment_ops(&self, slot: &str) -> Option<AttachmentOps> {
        self.plan.passes[self.pass_index]
            .slots
            .iter()
            .find(|s| s.slot == slot)
            .and_then(|s| s.ops)
    }

    /// Clears what `slot` binds to zero (a fill command): the first step of a
    /// `ClearedReadWrite` slot. A pass that clears with its own dispatch need not call it.
    /// Inside a batch a buffer is zeroed by the graph's fill dispatch in the shared compute
    /// pass (a `clear_buffer` would end it); a texture clear needs the encoder, which is
    /// why a `ClearedReadWrite` texture slot makes compile record the pass on the encoder.
    pub fn clear(&mut self, slot: &str) -> Result<()> {
        let r = self.slot_resource(slot)?;
        self.clear_resource(r, slot)
    }

    /// Zeroes `bytes` bytes of the buffer bound to `slot` from byte `offset`: one part of
    /// a buffer several passes share (one layer each of a stack of maps). Both must be
    /// multiples of 4, and `offset` of the device's storage offset alignment (256 bytes
    /// at most) so the fill dispatch can bind the part; otherwise, or past the buffer's
    /// end, it is a record error naming the numbers.
    pub fn clear_part(&mut self, slot: &str, offset: u64, bytes: u64) -> Result<()> {
        let r = self.slot_resource(slot)?;
        let Physical::Buffer { buffer, .. } = self.physical(r)? else {
            return Err(self.err(format!(
                "`clear_part` clears part of a buffer, but slot `{slot}` binds a texture"
            )));
        };
        let align = u64::from(self.device.limits().min_storage_buffer_offset_alignment);
        let end = offset.saturating_add(bytes);
        if !offset.is_multiple_of(align) || !bytes.is_multiple_of(4) || end > buffer.size() {
            return Err(self.err(format!(
                "cannot clear bytes {offset}..{end} of slot `{slot}` ({} bytes): the start must be a multiple of {align} and the length of 4, within the buffer",
                buffer.size()
            )));
        }
        self.fill_dispatch_at(buffer, offset, bytes);
        Ok(())
    }

    /// Zeroes a scratch buffer declared in setup, as [`Self::clear`] does a slot.
    pub fn clear_scratch(&mut self, name: &str) -> Result<()> {
        let r = self.scratch_resource(name)?;
        self.clear_resource(r, name)
    }

    fn clear_resource(&mut self, r: usize, slot: &str) -> Result<()> {
        match self.physical(r)? {
            Physical::Buffer { buffer, size } => {
                let bytes = size.next_multiple_of(4).min(buffer.size());
                let usage = buffer.usage();
                let fill = usage.contains(wgpu::BufferUsages::STORAGE)
                    && (self.batched || !usage.contains(wgpu::BufferUsages::COPY_DST));
                if fill {
                    self.fill_dispatch(buffer, bytes);
                } else {
                    self.leave_batch("clear_buffer");
                    self.encoder.clear_buffer(buffer, 0, Some(bytes));
                }
            }
            Physical::Texture { texture, .. } => {
                self.leave_batch("clear_texture");
                let range = self
                    .range(slot)?
                    .unwrap_or_else(|| TextureRange::mips(0, 1));
                self.encoder.clear_texture(
                    texture,
                    &wgpu::ImageSubresourceRange {
                        aspect: wgpu::TextureAspect::All,
                        base_mip_level: range.base_mip,
                        mip_level_count: Some(range.mip_count),
                        base_array_layer: range.base_layer,
                        array_layer_count: Some(range.layer_count),
                    },
                );
            }
        }
        Ok(())
    }

    /// Zeroes `bytes` of `buffer` with the fill program: in the shared compute pass inside
    /// a
    /// batch, else in a compute pass of its own.
    fn fill_dispatch(&mut self, buffer: &wgpu::Buffer, bytes: u64) {
        self.fill_dispatch_at(buffer, 0, bytes);
    }

    /// [`Self::fill_dispatch`] of `bytes` from `start` (aligned for a binding).
    fn fill_dispatch_at(&mut self, buffer: &wgpu::Buffer, start: u64, bytes: u64) {
        if bytes == 0 {
            return;
        }
        let limits = self.device.limits();
        let chunks = Fill::chunks(
            bytes,
            limits.max_storage_buffer_binding_size,
            limits.min_storage_buffer_offset_alignment as u64,
        );
        let mut groups = Vec::with_capacity(chunks.len());
        for (offset, size) in chunks {
            let bound = BoundResource::Buffer {
                buffer: buffer.clone(),
                offset: start + offset,
                size,
            };
            let group = self.cached_bind_group(
                "meshlight fill",
                self.fill.layout.clone(),
                vec![(0, bound)],
            );
            groups.push((group, Fill::grid(size)));
        }
        let pipeline = &self.fill.pipeline;
        // Outside a batch (a buffer without COPY_DST) the fill gets a compute pass of its own.
        let mut pass = self.compute_pass();
        pass.set_pipeline(pipeline);
        for (group, [x, y]) in &groups {
            pass.set_bind_group(0, group, &[]);
            pass.dispatch_workgroups(*x, *y, 1);
        }
    }

    fn declared(&self, name: &str) -> Result<(usize, &'a Arc<ProgramDesc>)> {
        self.declared
            .iter()
            .enumerate()
            .find(|(_, (n, _))| n == name)
            .map(|(i, (_, d))| (i, d))
            .ok_or_else(|| {
                self.err(format!(
                    "no program `{name}`; declare it in setup with SetupContext::program (declared: {})",
                    self.declared
                        .iter()
                        .map(|(n, _)| n.as_str())
                        .collect::<Vec<_>>()
                        .join(", ")
                ))
            })
    }

    /// The compute program declared in setup as `name`, built when the graph was
    /// prepared for the device ([`crate::Executor::prepare`]).
    pub fn compute(&mut self, name: &str) -> Result<Arc<ComputeProgram>> {
        let (index, desc) = self.declared(name)?;
        if !matches!(desc.kind, ProgramKind::Compute { .. }) {
            return Err(self.err(format!("program `{name}` is not a compute program")));
        }
        match self
            .programs
            .resolved(self.graph_id, self.pass_index, index)
        {
            Some(AnyProgram::Compute(p)) => Ok(p.clone()),
            _ => Err(self.unprepared(name)),
        }
    }

    /// The render (vertex or mesh) program declared in setup as `name`, built when the
    /// graph was prepared for the device.
    pub fn render(&mut self, name: &str) -> Result<Arc<RenderProgram>> {
        let (index, desc) = self.declared(name)?;
        if !matches!(desc.kind, ProgramKind::Render { .. }) {
            return Err(self.err(format!("program `{name}` is not a render program")));
        }
        match self
            .programs
            .resolved(self.graph_id, self.pass_index, index)
        {
            Some(AnyProgram::Render(p)) => Ok(p.clone()),
            _ => Err(self.unprepared(name)),
        }
    }

    /// A program asked for that preparing the graph did not build: the pass declared it
    /// under another kind, or recorded against a graph the executor never prepared.
    fn unprepared(&self, name: &str) -> GraphError {
        self.err(format!(
            "program `{name}` was not built for this device; the executor prepares every declared program before the first frame (Executor::prepare)"
        ))
    }

    /// The bind group for `group` of `program`, filled from the slots its layout names;
    /// `uniforms` gives the bytes of each uniform block under its WGSL variable's name, as
    /// slots and scratch resources are named. A name the program's shader declares no
    /// uniform of in this group, one given twice, or a uniform the program uses given no
    /// bytes is an error listing the group's uniforms; bytes for a uniform that only other
    /// entry points of the shader use are dropped, so one list serves them all.
    pub fn bind_group(
        &mut self,
        program: &impl Program,
        group: usize,
        uniforms: &[(&str, &[u8])],
    ) -> Result<wgpu::BindGroup> {
        let (layout, bgl) = program
            .layouts()
            .groups
            .get(group)
            .ok_or_else(|| self.err(format!("program has no bind group {group}")))?;
        self.check_uniform_names(layout, group, uniforms)?;
        let mut entries = Vec::with_capacity(layout.entries.len());
        for e in &layout.entries {
            let bound = match &e.source {
                BindingSource::Slot(name) => self.bound(name)?,
                BindingSource::Scratch(name, _) => self.bound(name)?,
                BindingSource::Uniform(name) => {
                    let bytes = uniforms
                        .iter()
                        .find(|(n, _)| n == name)
                        .map(|(_, d)| *d)
                        .ok_or_else(|| {
                            self.err(format!(
                                "uniform `{name}` (binding {}) of `{}` was given no bytes; pass (\"{name}\", bytes) (uniforms of group {group}: {})",
                                e.binding,
                                layout.label,
                                uniform_names(layout)
                            ))
                        })?;
                    self.uniform(bytes)?
                }
                BindingSource::Sampler(kind) => {
                    BoundResource::Sampler(self.programs.sampler(self.device, *kind))
                }
            };
            entries.push((e.binding, bound));
        }
        Ok(self.cached_bind_group(layout.label, bgl.clone(), entries))
    }

    /// Every name in `uniforms` must be a uniform of `layout` (or one its shader declares
    /// for other entry points), given once: a misspelt or stale name would otherwise be
    /// ignored while the block it meant goes unfilled.
    fn check_uniform_names(
        &self,
        layout: &crate::layout::BindingLayout,
        group: usize,
        uniforms: &[(&str, &[u8])],
    ) -> Result<()> {
        for (i, (name, _)) in uniforms.iter().enumerate() {
            let known = layout
                .entries
                .iter()
                .any(|e| matches!(&e.source, BindingSource::Uniform(n) if n == name))
                || layout.unused_uniforms.iter().any(|n| n == name);
            if !known {
                return Err(self.err(format!(
                    "`{}` has no uniform `{name}` in group {group}; name the WGSL variable (uniforms of group {group}: {})",
                    layout.label,
                    uniform_names(layout)
                )));
            }
            if uniforms[..i].iter().any(|(n, _)| n == name) {
                return Err(self.err(format!(
                    "uniform `{name}` of `{}` is given twice; give its bytes once",
                    layout.label
                )));
            }
        }
        Ok(())
    }

    fn uniform(&mut self, bytes: &[u8]) -> Result<BoundResource> {
        let (buffer, offset, size) =
            self.programs
                .uniforms
                .push(self.device, bytes)
                .ok_or_else(|| {
                    self.err(format!(
                        "uniform block of {} bytes exceeds {CHUNK}; bind it through a slot",
                        bytes.len()
                    ))
                })?;
        Ok(BoundResource::Buffer {
            buffer,
            offset,
            size,
        })
    }

    fn cached_bind_group(
        &mut self,
        label: &str,
        layout: wgpu::BindGroupLayout,
        entries: Vec<(u32, BoundResource)>,
    ) -> wgpu::BindGroup {
        let frame = self.programs.frame;
        let key = BindGroupKey { layout, entries };
        if let Some((bg, last)) = self.programs.bind_groups.get_mut(&key) {
            *last = frame;
            return bg.clone();
        }
        let wgpu_entries: Vec<wgpu::BindGroupEntry> = key
            .entries
            .iter()
            .map(|(binding, r)| wgpu::BindGroupEntry {
                binding: *binding,
                resource: match r {
                    BoundResource::Buffer {
                        buffer,
                        offset,
                        size,
                    } => wgpu::BindingResource::Buffer(wgpu::BufferBinding {
                        buffer,
                        offset: *offset,
                        size: wgpu::BufferSize::new(*size),
                    }),
                    BoundResource::View(v) => wgpu::BindingResource::TextureView(v),
                    BoundResource::Sampler(s) => wgpu::BindingResource::Sampler(s),
                },
            })
            .collect();
        let bg = self.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some(label),
            layout: &key.layout,
            entries: &wgpu_entries,
        });
        self.programs.bind_groups.insert(key, (bg.clone(), frame));
        self.programs.bind_groups_created += 1;
        bg
    }

    /// Immediate data for `program`: set it on the pass with `set_on_compute` or
    /// `set_on_render`. Natively where the device has `IMMEDIATES`, else as a uniform
    /// block.
    pub fn immediates(&mut self, program: &impl Program, bytes: &[u8]) -> Result<Immediates> {
        let layouts = program.layouts();
        let inner = match layouts.immediates {
            ImmediateMode::None => ImmediatesInner::None,
            ImmediateMode::Native { size } => {
                if bytes.len() as u32 > size {
                    return Err(self.err(format!(
                        "{} bytes of immediates for a program declared with {size}",
                        bytes.len()
                    )));
                }
                ImmediatesInner::Native(bytes.to_vec())
            }
            ImmediateMode::Uniform { group } => {
                let (layout, bgl) = &layouts.groups[group as usize];
                let bound = self.uniform(bytes)?;
                let bind_group =
                    self.cached_bind_group(layout.label, bgl.clone(), vec![(0, bound)]);
                ImmediatesInner::Uniform { group, bind_group }
            }
        };
        Ok(Immediates { inner })
    }

    /// Records the compute program `name` once over `workgroups`, its group 0 built from
    /// the slots its layout names and `uniforms` (bytes by WGSL variable name, as for
    /// [`bind_group`](Self::bind_group)): the shape of most of a pass's dispatches. A
    /// direct grid with a zero dimension records nothing.
    /// A program with a second group, or several dispatches sharing one bind group,
    /// records through [`compute`](Self::compute) and [`compute_pass`](Self::compute_pass).
    pub fn dispatch_compute(
        &mut self,
        name: &str,
        uniforms: &[(&str, &[u8])],
        workgroups: Workgroups<'_>,
    ) -> Result<()> {
        let program = self.compute(name)?;
        let group = self.bind_group(&*program, 0, uniforms)?;
        let mut pass = self.compute_pass();
        pass.set_pipeline(&program.pipeline);
        pass.set_bind_group(0, &group, &[]);
        match workgroups {
            Workgroups::Direct([x, y, z]) if x > 0 && y > 0 && z > 0 => {
                pass.dispatch_workgroups(x, y, z)
            }
            Workgroups::Direct(_) => {}
            Workgroups::Indirect(buffer, offset) => {
                pass.dispatch_workgroups_indirect(buffer, offset)
            }
        }
        Ok(())
    }

    /// The compute pass to dispatch in. For a batched pass it is the batch's shared compute
    /// pass (dispatches of consecutive passes then need no pass boundary; wgpu still puts
    /// the barrier each dependent dispatch needs between them), and dropping the guard
    /// leaves it open. Otherwise a compute pass labelled with this pass's name begins, and
    /// ends when the guard drops. Either way the commands go in the order they are given.
    pub fn compute_pass(&mut self) -> ComputePassGuard<'_> {
        if self.batched {
            ComputePassGuard::shared(self.shared.get(self.encoder))
        } else {
            ComputePassGuard::own(
                self.encoder
                    .begin_compute_pass(&wgpu::ComputePassDescriptor {
                        label: Some(self.name),
                        timestamp_writes: None,
                    })
                    .forget_lifetime(),
            )
        }
    }

    /// Begins a render pass labelled with this pass's name over `colors` and `depth`
    /// (slots or scratch textures), with the load and store ops the compiler derived for
    /// slots and clear-and-discard for scratch targets. The pass's timestamps bracket it.
    pub fn render_pass(
        &mut self,
        colors: &[ColorAttachment],
        depth: Option<DepthAttachment>,
    ) -> Result<wgpu::RenderPass<'_>> {
        let ops_of = |ctx: &Self, name: &str| -> AttachmentOps {
            ctx.attachment_ops(name).unwrap_or(AttachmentOps {
                load: LoadOp::Clear,
                store: StoreOp::Discard,
            })
        };
        let mut color_views = Vec::with_capacity(colors.len());
        for c in colors {
            let (_, view) = self.target_view(c.target)?;
            color_views.push((view, ops_of(self, c.target), c.clear));
        }
        let depth_view = match depth {
            Some(d) => {
                let (_, view) = self.target_view(d.target)?;
                Some((view, ops_of(self, d.target), d.clear))
            }
            None => None,
        };
        let store = |s: StoreOp| match s {
            StoreOp::Store => wgpu::StoreOp::Store,
            StoreOp::Discard => wgpu::StoreOp::Discard,
        };
        let attachments: Vec<Option<wgpu::RenderPassColorAttachment>> = color_views
            .iter()
            .map(|(view, ops, clear)| {
                Some(wgpu::RenderPassColorAttachment {
                    view,
                    depth_slice: None,
                    resolve_target: None,
                    ops: wgpu::Operations {
                        load: match ops.load {
                            LoadOp::Load => wgpu::LoadOp::Load,
                            LoadOp::Clear => wgpu::LoadOp::Clear(*clear),
                        },
                        store: store(ops.store),
                    },
                })
            })
            .collect();
        let depth_attachment =
            depth_view.as_ref().map(
                |(view, ops, clear)| wgpu::RenderPassDepthStencilAttachment {
                    view,
                    depth_ops: Some(wgpu::Operations {
                        load: match ops.load {
                            LoadOp::Load => wgpu::LoadOp::Load,
                            LoadOp::Clear => wgpu::LoadOp::Clear(*clear),
                        },
                        store: store(ops.store),
                    }),
                    stencil_ops: None,
                },
            );
        self.leave_batch("render_pass()");
        Ok(self.encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some(self.name),
            color_attachments: &attachments,
            depth_stencil_attachment: depth_attachment,
            timestamp_writes: None,
            occlusion_query_set: None,
            multiview_mask: None,
        }))
    }

    /// Copies `slot` (or a byte range of it) into this frame's readback buffer `name`.
    pub(crate) fn readback_copy(
        &mut self,
        name: &str,
        latency: u32,
        slot: &str,
        range: Option<std::ops::Range<u64>>,
    ) -> Result<()> {
        let (buffer, size) = self.buffer(slot)?;
        self.leave_batch("readback copy");
        let range = range.unwrap_or(0..size.next_multiple_of(4).min(buffer.size()));
        let copy = crate::record::readback::ReadbackCopy {
            name,
            latency,
            source: buffer,
            range,
            frame: self.frame_index,
        };
        self.readbacks
            .record(self.device, self.encoder, copy)
            .map_err(|m| self.err(m))
    }
}

/// The uniforms of `layout`, those its program uses and those only other entry points of
/// its shader use, for errors about them.
fn uniform_names(layout: &crate::layout::BindingLayout) -> String {
    let mut names: Vec<&str> = layout
        .entries
        .iter()
        .filter_map(|e| match &e.source {
            BindingSource::Uniform(n) => Some(n.as_ref()),
            _ => None,
        })
        .chain(layout.unused_uniforms.iter().map(|n| n.as_ref()))
        .collect();
    names.sort_unstable();
    if names.is_empty() {
        "none".to_string()
    } else {
        names.join(", ")
    }
}
