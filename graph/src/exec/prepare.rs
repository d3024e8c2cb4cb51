//! Preparing a compiled graph for a device: every program its passes declared in setup
//! (composed shader modules, bind-group layouts read from the shaders, pipeline layouts,
//! pipelines) is built before the first frame, each pass's inside an error scope, so a
//! shader that does not match its slots or a pipeline the device refuses is an error
//! naming the pass before anything is recorded. Recording then only looks programs up.

use crate::compile::CompiledGraph;
use crate::contract::StageContract;
use crate::error::{GraphError, Result};
use crate::exec::context::GpuContext;
use crate::layout::{BindingSource, buffer_binding_type, texture_binding_type};
use crate::plan::Plan;
use crate::program::{Geometry, ProgramDesc, ProgramKind};
use crate::record::programs::{
    AnyProgram, ComputeProgram, IMMEDIATES_BLOCK, ImmediateMode, ModuleKey, ProgramKey,
    ProgramLayouts, Programs, RenderProgram,
};
use crate::resource::{ResourceDesc, TextureDesc};
use meshlight_shaders::ShaderDef;
use std::sync::Arc;

/// Builds every program of every pass `graph` runs (skipped passes declare none), once per
/// graph: later calls for the same graph return at once. A pass's validation errors (a
/// pipeline or layout the device refuses, a limit it passes) are
/// [`GraphError::Prepare`] naming the pass.
pub(crate) fn prepare(
    programs: &mut Programs,
    gpu: &GpuContext,
    graph: &CompiledGraph,
) -> Result<()> {
    if programs.is_prepared(graph.id) {
        return Ok(());
    }
    profiling::scope!("meshlight::prepare");
    let plan = &graph.plan;
    for &p in &plan.order {
        let node = &graph.passes[p];
        let declared = &graph.setups[p].programs;
        if declared.is_empty() {
            continue;
        }
        profiling::scope!("meshlight::prepare pass", node.name.as_str());
        let scope = gpu.device.push_error_scope(wgpu::ErrorFilter::Validation);
        let mut builder = ProgramBuilder {
            device: &gpu.device,
            features: gpu.features,
            name: &node.name,
            contract: &node.contract,
            stage_slots: &node.stage_slots,
            plan,
            pass_index: p,
            programs: &mut *programs,
            graph_id: graph.id,
        };
        let built = declared
            .iter()
            .enumerate()
            .try_for_each(|(index, (_, desc))| builder.build(index, desc));
        let refused = pollster::block_on(scope.pop());
        built?;
        if let Some(e) = refused {
            return Err(GraphError::Prepare {
                pass: node.name.clone(),
                message: e.to_string(),
            });
        }
    }
    programs.prepared(graph.id);
    Ok(())
}

/// What building one pass's programs reads: the device, the pass's contract and the
/// plan's view of what its slots bind.
struct ProgramBuilder<'a> {
    device: &'a wgpu::Device,
    features: wgpu::Features,
    /// The pass instance's name, for labels and errors.
    name: &'a str,
    /// The pass's stage contract with its unbound optional slots removed.
    contract: &'a StageContract,
    /// Every slot of the stage, bound or not.
    stage_slots: &'a [&'static str],
    plan: &'a Plan,
    pass_index: usize,
    programs: &'a mut Programs,
    graph_id: u64,
}

impl ProgramBuilder<'_> {
    fn err(&self, message: String) -> GraphError {
        GraphError::Prepare {
            pass: self.name.to_string(),
            message,
        }
    }

    /// The resource a slot or scratch name of the pass binds.
    fn named(&self, name: &str) -> Result<usize> {
        let pass = &self.plan.passes[self.pass_index];
        if let Some(s) = pass.slots.iter().find(|s| s.slot == name) {
            return Ok(s.resource);
        }
        let full = format!("{}/{}", self.name, name);
        pass.scratch
            .iter()
            .copied()
            .find(|&r| self.plan.resources[r].info.name == full)
            .ok_or_else(|| {
                self.err(format!(
                    "`{name}` is neither a bound slot nor a scratch resource of the pass; bind the slot, or declare the scratch resource in setup"
                ))
            })
    }

    /// Builds declared program `index` (or finds an equal one another pass built) and
    /// notes it as what the pass's program resolves to.
    fn build(&mut self, index: usize, desc: &ProgramDesc) -> Result<()> {
        let key = self.program_key(desc)?;
        let program = match &desc.kind {
            ProgramKind::Compute { .. } => match self.programs.compute(&key) {
                Some(p) => AnyProgram::Compute(p),
                None => self.compute(key)?,
            },
            ProgramKind::Render { .. } => match self.programs.render(&key) {
                Some(p) => AnyProgram::Render(p),
                None => self.render(key)?,
            },
        };
        self.programs
            .resolve(self.graph_id, self.pass_index, index, program);
        Ok(())
    }

    /// The wgpu layout entries of a declared layout, from the bound resources.
    fn layout_entries(
        &self,
        layout: &crate::layout::BindingLayout,
    ) -> Result<Vec<wgpu::BindGroupLayoutEntry>> {
        let contract = &self.contract;
        layout
            .entries
            .iter()
            .map(|e| {
                let ty = match &e.source {
                    BindingSource::Slot(name) => {
                        let slot = contract.slot(name).ok_or_else(|| GraphError::UnknownSlot {
                            pass: self.name.to_string(),
                            stage: contract.stage.to_string(),
                            slot: name.to_string(),
                            available: contract.slot_names().join(", "),
                        })?;
                        self.binding_type(name, slot.access, e)?
                    }
                    BindingSource::Scratch(name, access) => self.binding_type(name, *access, e)?,
                    BindingSource::Uniform(_) => {
                        buffer_binding_type(crate::access::Access::Uniform)
                            .expect("uniform is a buffer binding")
                    }
                    BindingSource::Sampler(kind) => kind.binding_type(),
                };
                Ok(wgpu::BindGroupLayoutEntry {
                    binding: e.binding,
                    visibility: e.visibility.unwrap_or(layout.visibility),
                    ty,
                    count: None,
                })
            })
            .collect()
    }

    /// The binding type of the named slot or scratch resource used with `access` (as
    /// read-only or write-only storage when the layout entry says so).
    fn binding_type(
        &self,
        name: &str,
        access: crate::access::Access,
        entry: &crate::layout::LayoutEntry,
    ) -> Result<wgpu::BindingType> {
        let access = if entry.read_only {
            crate::access::Access::StorageRead
        } else if entry.write_only {
            crate::access::Access::StorageWrite
        } else {
            access
        };
        let r = self.named(name)?;
        match &self.plan.resources[r].info.desc {
            ResourceDesc::Buffer(_) => buffer_binding_type(access),
            ResourceDesc::Texture(t) => texture_binding_type(access, t.format, t.layers > 1),
        }
        .ok_or_else(|| {
            self.err(format!(
                "`{name}` ({}) cannot be bound in a bind group",
                access.name()
            ))
        })
    }

    fn target_format(&self, name: &str) -> Result<wgpu::TextureFormat> {
        let r = self.named(name)?;
        match &self.plan.resources[r].info.desc {
            ResourceDesc::Texture(TextureDesc { format, .. }) => Ok(*format),
            ResourceDesc::Buffer(_) => Err(self.err(format!(
                "render target `{name}` is a buffer; bind a texture"
            ))),
        }
    }

    fn program_key(&mut self, desc: &ProgramDesc) -> Result<ProgramKey> {
        let native_immediates = self.features.contains(wgpu::Features::IMMEDIATES);
        let expanded = if desc.layouts.iter().any(|l| l.reflect) {
            let (_, globals) = self.programs.module(
                self.device,
                self.features,
                self.name,
                desc.shader,
                module_key(desc, native_immediates),
            )?;
            let names = self.reflection_names();
            let entries = desc.entries();
            desc.layouts
                .iter()
                .enumerate()
                .map(|(group, l)| {
                    if !l.reflect {
                        return Ok(l.clone());
                    }
                    crate::record::reflect::expand(l, group as u32, &globals, &entries, &names)
                        .map_err(|m| {
                            self.err(format!(
                                "shader {} variable `{}`: {}",
                                desc.shader.file_path, m.variable, m.message
                            ))
                        })
                })
                .collect::<Result<Vec<_>>>()?
        } else {
            desc.layouts.clone()
        };
        let layouts = expanded
            .iter()
            .map(|l| self.layout_entries(l))
            .collect::<Result<Vec<_>>>()?;
        let (target_formats, depth_format) = match &desc.kind {
            ProgramKind::Render { targets, depth, .. } => (
                targets
                    .iter()
                    .map(|t| self.target_format(t.target))
                    .collect::<Result<Vec<_>>>()?,
                depth
                    .as_ref()
                    .map(|d| self.target_format(d.target))
                    .transpose()?,
            ),
            ProgramKind::Compute { .. } => (Vec::new(), None),
        };
        Ok(ProgramKey {
            desc: desc.clone(),
            expanded,
            layouts,
            target_formats,
            depth_format,
            native_immediates,
        })
    }

    /// The pass's slots and scratch resources, for layouts read from the shader.
    fn reflection_names(&self) -> crate::record::reflect::Names {
        let contract = &self.contract;
        let slots = contract
            .slots
            .iter()
            .map(|s| {
                let element = match &s.kind {
                    crate::contract::SlotKind::Buffer { element: Some(e) } => e.size,
                    _ => 0,
                };
                (s.name, s.access, element)
            })
            .collect();
        let prefix = format!("{}/", self.name);
        let scratch = self.plan.passes[self.pass_index]
            .scratch
            .iter()
            .filter_map(|&r| {
                let name = self.plan.resources[r].info.name.strip_prefix(&prefix)?;
                Some(name.to_string())
            })
            .collect();
        crate::record::reflect::Names {
            stage: contract.stage,
            slots,
            all_slots: self.stage_slots.to_vec(),
            scratch,
        }
    }

    /// The module, bind-group layouts and pipeline layout of a program.
    fn build_layouts(
        &mut self,
        key: &ProgramKey,
    ) -> Result<(wgpu::ShaderModule, ProgramLayouts, wgpu::PipelineLayout)> {
        let desc = &key.desc;
        let immediates = if desc.immediate_size == 0 {
            ImmediateMode::None
        } else if key.native_immediates {
            ImmediateMode::Native {
                size: desc.immediate_size,
            }
        } else {
            ImmediateMode::Uniform {
                group: desc.layouts.len() as u32,
            }
        };
        let (module, _) = self.programs.module(
            self.device,
            self.features,
            self.name,
            desc.shader,
            module_key(desc, key.native_immediates),
        )?;
        let mut groups: Vec<(crate::layout::BindingLayout, wgpu::BindGroupLayout)> = key
            .expanded
            .iter()
            .zip(&key.layouts)
            .map(|(l, entries)| {
                (
                    l.clone(),
                    self.programs.layout(self.device, l.label, entries.clone()),
                )
            })
            .collect();
        if let ImmediateMode::Uniform { .. } = immediates {
            let visibility = desc
                .layouts
                .first()
                .map(|l| l.visibility)
                .unwrap_or(wgpu::ShaderStages::all());
            let l = crate::layout::BindingLayout::with_visibility("immediates", visibility)
                .uniform(0, IMMEDIATES_BLOCK);
            let entries = self.layout_entries(&l)?;
            let bgl = self.programs.layout(self.device, l.label, entries);
            groups.push((l, bgl));
        }
        let refs: Vec<Option<&wgpu::BindGroupLayout>> =
            groups.iter().map(|(_, l)| Some(l)).collect();
        let label = format!("{}::{}", desc.shader.name, desc.entries().join("+"));
        let layout = self
            .device
            .create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                label: Some(&label),
                bind_group_layouts: &refs,
                immediate_size: match immediates {
                    ImmediateMode::Native { size } => size,
                    _ => 0,
                },
            });
        Ok((module, ProgramLayouts { groups, immediates }, layout))
    }

    /// Builds the compute program of `key` and caches it for any pass that asks for the
    /// same one.
    fn compute(&mut self, key: ProgramKey) -> Result<AnyProgram> {
        let ProgramKind::Compute { entry } = key.desc.kind else {
            unreachable!("built for a compute program")
        };
        let desc = &key.desc;
        let (module, layouts, layout) = self.build_layouts(&key)?;
        let label = format!("{}::{entry}", desc.shader.name);
        let pipeline = self
            .device
            .create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                label: Some(&label),
                layout: Some(&layout),
                module: &module,
                entry_point: Some(entry),
                compilation_options: Default::default(),
                cache: None,
            });
        let program = AnyProgram::Compute(Arc::new(ComputeProgram { pipeline, layouts }));
        self.programs.insert(key, program.clone());
        Ok(program)
    }

    /// Builds the render (vertex or mesh) program of `key` and caches it.
    fn render(&mut self, key: ProgramKey) -> Result<AnyProgram> {
        let desc = &key.desc;
        let ProgramKind::Render {
            geometry,
            fragment,
            targets,
            depth,
            primitive,
        } = &desc.kind
        else {
            unreachable!("built for a render program")
        };
        let (module, layouts, layout) = self.build_layouts(&key)?;
        let label = format!("{}::{}", desc.shader.name, desc.entries().join("+"));
        let color_states: Vec<Option<wgpu::ColorTargetState>> = targets
            .iter()
            .zip(&key.target_formats)
            .map(|(t, format)| {
                Some(wgpu::ColorTargetState {
                    format: *format,
                    blend: t.blend,
                    write_mask: t.write_mask,
                })
            })
            .collect();
        let fragment_state = fragment.map(|entry| wgpu::FragmentState {
            module: &module,
            entry_point: Some(entry),
            compilation_options: Default::default(),
            targets: &color_states,
        });
        let depth_stencil =
            depth
                .as_ref()
                .zip(key.depth_format)
                .map(|(d, format)| wgpu::DepthStencilState {
                    format,
                    depth_write_enabled: Some(d.write),
                    depth_compare: Some(d.compare),
                    stencil: Default::default(),
                    bias: Default::default(),
                });
        let primitive_state = wgpu::PrimitiveState {
            topology: primitive.topology,
            strip_index_format: None,
            front_face: primitive.front_face,
            cull_mode: primitive.cull_mode,
            unclipped_depth: primitive.unclipped_depth
                && self.features.contains(wgpu::Features::DEPTH_CLIP_CONTROL),
            polygon_mode: wgpu::PolygonMode::Fill,
            conservative: false,
        };
        let pipeline = match geometry {
            Geometry::Vertex { entry } => {
                self.device
                    .create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                        label: Some(&label),
                        layout: Some(&layout),
                        vertex: wgpu::VertexState {
                            module: &module,
                            entry_point: Some(entry),
                            compilation_options: Default::default(),
                            buffers: &[],
                        },
                        primitive: primitive_state,
                        depth_stencil,
                        multisample: Default::default(),
                        fragment: fragment_state,
                        multiview_mask: None,
                        cache: None,
                    })
            }
            Geometry::Mesh { task, mesh } => {
                if !self
                    .features
                    .contains(wgpu::Features::EXPERIMENTAL_MESH_SHADER)
                {
                    return Err(GraphError::MissingFeature {
                        pass: self.name.to_string(),
                        stage: self.contract.stage.to_string(),
                        features: "EXPERIMENTAL_MESH_SHADER".into(),
                        instead: "open the device with the plan's `enabled_features`".into(),
                    });
                }
                self.device
                    .create_mesh_pipeline(&wgpu::MeshPipelineDescriptor {
                        label: Some(&label),
                        layout: Some(&layout),
                        task: task.map(|entry| wgpu::TaskState {
                            module: &module,
                            entry_point: Some(entry),
                            compilation_options: Default::default(),
                        }),
                        mesh: wgpu::MeshState {
                            module: &module,
                            entry_point: Some(mesh),
                            compilation_options: Default::default(),
                        },
                        primitive: primitive_state,
                        depth_stencil,
                        multisample: Default::default(),
                        fragment: fragment_state,
                        multiview: None,
                        cache: None,
                    })
            }
        };
        let program = AnyProgram::Render(Arc::new(RenderProgram { pipeline, layouts }));
        self.programs.insert(key, program.clone());
        Ok(program)
    }
}

/// The module a program composes: its shader with its defs, and `IMMEDIATES` set for how
/// immediate data reaches it.
fn module_key(desc: &ProgramDesc, native_immediates: bool) -> ModuleKey {
    let mut defs: Vec<(&'static str, ShaderDef)> = desc.defs.clone();
    if desc.immediate_size != 0 {
        defs.retain(|(n, _)| *n != "IMMEDIATES");
        defs.push(("IMMEDIATES", ShaderDef::Bool(native_immediates)));
    }
    ModuleKey {
        shader: desc.shader.name,
        defs,
    }
}
