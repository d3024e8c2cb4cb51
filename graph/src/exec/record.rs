//! What a pass sees while recording: its bound resources by slot name, cached programs and
//! bind groups, and the command encoder.

use crate::access::Access;
use crate::builder::PassNode;
use crate::error::{GraphError, Result};
use crate::exec::layout::{
    BindingLayout, BindingSource, buffer_binding_type, texture_binding_type,
};
use crate::exec::physical::Physical;
use crate::exec::programs::{
    BindGroupKey, BoundResource, CHUNK, ComputeProgram, ModuleKey, ProgramKey, Programs,
};
use crate::plan::{AttachmentOps, Plan};
use crate::resource::ResourceDesc;
use meshlight_shaders::{PassShader, ShaderDefs};
use std::sync::Arc;

/// Describes a compute pipeline in terms of the pass's shader, defs and slot layouts.
pub struct ComputeDesc<'a> {
    pub shader: &'a PassShader,
    pub entry: &'static str,
    pub defs: &'a dyn ShaderDefs,
    pub layouts: &'a [BindingLayout],
}

pub struct RecordContext<'a> {
    pub(crate) device: &'a wgpu::Device,
    pub(crate) queue: &'a wgpu::Queue,
    pub(crate) features: wgpu::Features,
    pub(crate) encoder: &'a mut wgpu::CommandEncoder,
    pub(crate) node: &'a PassNode,
    pub(crate) pass_index: usize,
    pub(crate) plan: &'a Plan,
    pub(crate) physical: &'a [Option<Physical>],
    pub(crate) programs: &'a mut Programs,
}

impl<'a> RecordContext<'a> {
    pub fn device(&self) -> &wgpu::Device {
        self.device
    }
    pub fn queue(&self) -> &wgpu::Queue {
        self.queue
    }
    /// Features enabled on the device (the pass's optional features among them).
    pub fn features(&self) -> wgpu::Features {
        self.features
    }
    pub fn encoder(&mut self) -> &mut wgpu::CommandEncoder {
        self.encoder
    }
    pub fn pass_name(&self) -> &str {
        &self.node.name
    }

    fn err(&self, message: String) -> GraphError {
        GraphError::Record {
            pass: self.node.name.clone(),
            message,
        }
    }

    fn slot_resource(&self, slot: &str) -> Result<usize> {
        let pass = &self.plan.passes[self.pass_index];
        pass.slots
            .iter()
            .find(|s| s.slot == slot)
            .map(|s| s.resource)
            .ok_or_else(|| GraphError::UnknownSlot {
                pass: self.node.name.clone(),
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
    fn scratch_resource(&self, name: &str) -> Result<usize> {
        let full = format!("{}/{}", self.node.name, name);
        self.plan.passes[self.pass_index]
            .scratch
            .iter()
            .copied()
            .find(|&r| self.plan.resources[r].info.name == full)
            .ok_or_else(|| {
                self.err(format!(
                    "no scratch buffer `{name}`; declare it in setup with scratch_buffer"
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

    /// True when `slot` is bound (always, unless the slot is optional).
    pub fn is_bound(&self, slot: &str) -> bool {
        self.node.contract.slot(slot).is_some()
    }
    /// The buffer bound to `slot`, and its size in bytes (the pooled buffer may be larger).
    pub fn buffer(&self, slot: &str) -> Result<(&'a wgpu::Buffer, u64)> {
        self.buffer_of(self.slot_resource(slot)?)
    }
    pub fn scratch(&self, name: &str) -> Result<(&'a wgpu::Buffer, u64)> {
        self.buffer_of(self.scratch_resource(name)?)
    }
    pub fn texture(&self, slot: &str) -> Result<(&'a wgpu::Texture, &'a wgpu::TextureView)> {
        match self.physical(self.slot_resource(slot)?)? {
            Physical::Texture { texture, view } => Ok((texture, view)),
            Physical::Buffer { .. } => {
                Err(self.err(format!("slot `{slot}` holds a buffer, not a texture")))
            }
        }
    }
    /// The descriptor of the resource bound to `slot`.
    pub fn desc(&self, slot: &str) -> Result<&'a ResourceDesc> {
        Ok(&self.plan.resources[self.slot_resource(slot)?].info.desc)
    }
    /// Load and store ops the compiler derived for a render or depth target slot.
    pub fn attachment_ops(&self, slot: &str) -> Option<AttachmentOps> {
        self.plan.passes[self.pass_index]
            .slots
            .iter()
            .find(|s| s.slot == slot)
            .and_then(|s| s.ops)
    }

    fn layout_entries(&self, layout: &BindingLayout) -> Result<Vec<wgpu::BindGroupLayoutEntry>> {
        let contract = &self.node.contract;
        layout
            .entries
            .iter()
            .map(|e| {
                let ty = match &e.source {
                    BindingSource::Slot(name) => {
                        let slot = contract.slot(name).ok_or_else(|| GraphError::UnknownSlot {
                            pass: self.node.name.clone(),
                            stage: contract.stage.to_string(),
                            slot: name.to_string(),
                            available: contract.slot_names().join(", "),
                        })?;
                        match self.desc(name)? {
                            ResourceDesc::Buffer(_) => buffer_binding_type(slot.access),
                            ResourceDesc::Texture(t) => texture_binding_type(slot.access, t.format),
                        }
                        .ok_or_else(|| {
                            self.err(format!(
                                "slot `{name}` ({}) cannot be bound in a bind group",
                                slot.access.name()
                            ))
                        })?
                    }
                    BindingSource::Scratch(_, access) => {
                        buffer_binding_type(*access).ok_or_else(|| {
                            self.err(format!("scratch access {} cannot be bound", access.name()))
                        })?
                    }
                    BindingSource::Uniform => {
                        buffer_binding_type(Access::Uniform).expect("uniform is a buffer binding")
                    }
                };
                Ok(wgpu::BindGroupLayoutEntry {
                    binding: e.binding,
                    visibility: layout.visibility,
                    ty,
                    count: None,
                })
            })
            .collect()
    }

    /// A compute pipeline, compiled once per (shader, entry, defs, layouts) and cached.
    pub fn compute_program(&mut self, desc: &ComputeDesc<'_>) -> Result<Arc<ComputeProgram>> {
        let layouts = desc
            .layouts
            .iter()
            .map(|l| self.layout_entries(l))
            .collect::<Result<Vec<_>>>()?;
        let key = ProgramKey {
            module: ModuleKey {
                shader: desc.shader.name,
                defs: desc.defs.shader_defs(),
            },
            entry: desc.entry,
            declared: desc.layouts.to_vec(),
            layouts,
        };
        if let Some(p) = self.programs.compute_program(&key) {
            return Ok(p);
        }
        let module = self.programs.module(
            self.device,
            self.features,
            &self.node.name,
            desc.shader,
            key.module.clone(),
        )?;
        let bgls: Vec<(BindingLayout, wgpu::BindGroupLayout)> = desc
            .layouts
            .iter()
            .zip(&key.layouts)
            .map(|(l, entries)| {
                (
                    l.clone(),
                    self.programs.layout(self.device, l.label, entries.clone()),
                )
            })
            .collect();
        let refs: Vec<Option<&wgpu::BindGroupLayout>> = bgls.iter().map(|(_, l)| Some(l)).collect();
        let label = format!("{}::{}", desc.shader.name, desc.entry);
        let layout = self
            .device
            .create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                label: Some(&label),
                bind_group_layouts: &refs,
                immediate_size: 0,
            });
        let pipeline = self
            .device
            .create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                label: Some(&label),
                layout: Some(&layout),
                module: &module,
                entry_point: Some(desc.entry),
                compilation_options: Default::default(),
                cache: None,
            });
        Ok(self.programs.insert_compute_program(
            key,
            ComputeProgram {
                pipeline,
                layouts: bgls,
            },
        ))
    }

    /// The bind group for `group` of `program`, filled from the slots its layout names;
    /// `uniforms` gives the bytes of each `Uniform` binding, by binding index.
    pub fn bind_group(
        &mut self,
        program: &ComputeProgram,
        group: usize,
        uniforms: &[(u32, &[u8])],
    ) -> Result<wgpu::BindGroup> {
        let (layout, bgl) = program
            .layouts
            .get(group)
            .ok_or_else(|| self.err(format!("program has no bind group {group}")))?;
        let mut entries = Vec::with_capacity(layout.entries.len());
        for e in &layout.entries {
            let bound = match &e.source {
                BindingSource::Slot(name) => match self.physical(self.slot_resource(name)?)? {
                    Physical::Buffer { buffer, size } => BoundResource::Buffer {
                        buffer: buffer.clone(),
                        offset: 0,
                        size: (*size).max(4),
                    },
                    Physical::Texture { view, .. } => BoundResource::View(view.clone()),
                },
                BindingSource::Scratch(name, _) => {
                    let (buffer, size) = self.scratch(name)?;
                    BoundResource::Buffer {
                        buffer: buffer.clone(),
                        offset: 0,
                        size: size.max(4),
                    }
                }
                BindingSource::Uniform => {
                    let bytes = uniforms
                        .iter()
                        .find(|(b, _)| *b == e.binding)
                        .map(|(_, d)| *d)
                        .ok_or_else(|| {
                            self.err(format!(
                                "no bytes given for uniform binding {} of `{}`",
                                e.binding, layout.label
                            ))
                        })?;
                    let (buffer, offset, size) = self
                        .programs
                        .uniforms
                        .push(self.device, bytes)
                        .ok_or_else(|| {
                            self.err(format!(
                                "uniform block of {} bytes exceeds {CHUNK}; bind it through a slot",
                                bytes.len()
                            ))
                        })?;
                    BoundResource::Buffer {
                        buffer,
                        offset,
                        size,
                    }
                }
            };
            entries.push((e.binding, bound));
        }
        let key = BindGroupKey {
            layout: bgl.clone(),
            entries,
        };
        if let Some(bg) = self.programs.bind_groups.get(&key) {
            return Ok(bg.clone());
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
                },
            })
            .collect();
        let bg = self.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some(layout.label),
            layout: bgl,
            entries: &wgpu_entries,
        });
        self.programs.bind_groups.insert(key, bg.clone());
        Ok(bg)
    }

    /// Begins a compute pass labelled with this pass's name.
    pub fn compute_pass(&mut self) -> wgpu::ComputePass<'_> {
        self.encoder
            .begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some(&self.node.name),
                timestamp_writes: None,
            })
    }
}
