//! Caches that make a steady frame cheap to record: composed shader modules and pipelines
//! by (shader, entry, defs, layouts); bind-group layouts by their entries; bind groups by
//! the exact resources they bind; and a per-frame arena for small uniform blocks.

use crate::error::{GraphError, Result};
use crate::layout::{BindingLayout, SamplerKind};
use crate::program::ProgramDesc;
use crate::record::reflect::{ShaderGlobal, globals};
use meshlight_shaders::{PassShader, ShaderDef, ShaderLibrary};
use std::collections::HashMap;
use std::sync::Arc;

/// The name of the uniform the immediates fallback binds at binding 0 of its own group.
/// The graph fills it itself in [`RecordContext::immediates`], so the shader's variable may
/// be called anything.
pub(crate) const IMMEDIATES_BLOCK: &str = "immediates";

/// The bind-group layouts a program was built with, and where its immediate data goes.
pub struct ProgramLayouts {
    pub(crate) groups: Vec<(BindingLayout, wgpu::BindGroupLayout)>,
    pub(crate) immediates: ImmediateMode,
}

/// How a program receives its immediate data.
#[derive(Clone, Debug)]
pub(crate) enum ImmediateMode {
    None,
    /// `set_immediates` on the pass (the device has `IMMEDIATES`).
    Native {
        size: u32,
    },
    /// A uniform block in bind group `group`, binding 0 (the fallback).
    Uniform {
        group: u32,
    },
}

/// Anything with bind-group layouts: compute and render programs alike.
pub trait Program {
    /// The bind-group layouts the program was built with; bind groups for it are made from
    /// these.
    fn layouts(&self) -> &ProgramLayouts;
}

/// A compute pipeline and the bind-group layouts it was built with.
pub struct ComputeProgram {
    /// The pipeline, to set on a compute pass.
    pub pipeline: wgpu::ComputePipeline,
    pub(crate) layouts: ProgramLayouts,
}

/// A render pipeline (vertex or mesh geometry) and the bind-group layouts it was built with.
pub struct RenderProgram {
    /// The pipeline, to set on a render pass.
    pub pipeline: wgpu::RenderPipeline,
    pub(crate) layouts: ProgramLayouts,
}

impl<P: Program> Program for Arc<P> {
    fn layouts(&self) -> &ProgramLayouts {
        (**self).layouts()
    }
}
impl Program for ComputeProgram {
    fn layouts(&self) -> &ProgramLayouts {
        &self.layouts
    }
}
impl Program for RenderProgram {
    fn layouts(&self) -> &ProgramLayouts {
        &self.layouts
    }
}

#[derive(Clone, PartialEq, Eq, Hash)]
pub(crate) struct ModuleKey {
    pub shader: &'static str,
    pub defs: Vec<(&'static str, ShaderDef)>,
}

/// What makes two programs the same pipeline: the declaration (shader, entries, defs,
/// declared layouts, targets), the wgpu layout entries the bound resources resolve it to,
/// and the formats of its attachments.
#[derive(Clone, PartialEq, Eq, Hash)]
pub(crate) struct ProgramKey {
    pub desc: ProgramDesc,
    /// The declared layouts with the bindings read from the shader filled in.
    pub expanded: Vec<crate::layout::BindingLayout>,
    pub layouts: Vec<Vec<wgpu::BindGroupLayoutEntry>>,
    pub target_formats: Vec<wgpu::TextureFormat>,
    pub depth_format: Option<wgpu::TextureFormat>,
    pub native_immediates: bool,
}

#[derive(Clone, PartialEq, Eq, Hash)]
pub(crate) enum BoundResource {
    Buffer {
        buffer: wgpu::Buffer,
        offset: u64,
        size: u64,
    },
    View(wgpu::TextureView),
    Sampler(wgpu::Sampler),
}

#[derive(Clone, PartialEq, Eq, Hash)]
pub(crate) struct BindGroupKey {
    pub layout: wgpu::BindGroupLayout,
    pub entries: Vec<(u32, BoundResource)>,
}

#[derive(Clone)]
pub(crate) enum AnyProgram {
    Compute(Arc<ComputeProgram>),
    Render(Arc<RenderProgram>),
}

pub(crate) struct Programs {
    pub library: Option<ShaderLibrary>,
    modules: HashMap<ModuleKey, (wgpu::ShaderModule, Arc<Vec<ShaderGlobal>>)>,
    programs: HashMap<ProgramKey, AnyProgram>,
    /// Per (compiled graph, pass): its declared programs, by declaration index, once
    /// built or found. Layout entries and formats are fixed by the compiled graph, so a
    /// steady frame skips building and hashing a `ProgramKey`.
    resolved: HashMap<(u64, usize), Vec<Option<AnyProgram>>>,
    /// Compiled graphs whose every program is built (`exec::prepare`).
    prepared: std::collections::HashSet<u64>,
    layouts: HashMap<Vec<wgpu::BindGroupLayoutEntry>, wgpu::BindGroupLayout>,
    samplers: HashMap<SamplerKind, wgpu::Sampler>,
    /// Bind groups by the exact objects they bind, with the frame that last used each;
    /// one unused for a few frames is dropped, so it keeps no freed buffer alive.
    pub bind_groups: HashMap<BindGroupKey, (wgpu::BindGroup, u64)>,
    pub uniforms: UniformArena,
    pub pipelines_created: u32,
    pub bind_groups_created: u32,
    pub frame: u64,
}

impl Programs {
    pub fn new() -> Self {
        Self {
            library: None,
            modules: HashMap::new(),
            programs: HashMap::new(),
            resolved: HashMap::new(),
            prepared: Default::default(),
            layouts: HashMap::new(),
            samplers: HashMap::new(),
            bind_groups: HashMap::new(),
            uniforms: UniformArena::default(),
            pipelines_created: 0,
            bind_groups_created: 0,
            frame: 0,
        }
    }

    pub fn begin_frame(&mut self, frame: u64) {
        self.frame = frame;
        self.uniforms.begin_frame();
        self.bind_groups.retain(|_, (_, last)| {
            frame.saturating_sub(*last) <= crate::record::physical::EVICT_AFTER_FRAMES
        });
    }

    pub fn layout(
        &mut self,
        device: &wgpu::Device,
        label: &str,
        entries: Vec<wgpu::BindGroupLayoutEntry>,
    ) -> wgpu::BindGroupLayout {
        self.layouts
            .entry(entries)
            .or_insert_with_key(|entries| {
                device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                    label: Some(label),
                    entries,
                })
            })
            .clone()
    }

    pub fn sampler(&mut self, device: &wgpu::Device, kind: SamplerKind) -> wgpu::Sampler {
        self.samplers
            .entry(kind)
            .or_insert_with(|| device.create_sampler(&kind.descriptor()))
            .clone()
    }

    /// The composed module of `key`, and the resource globals it declares (for layouts
    /// read from the shader).
    pub fn module(
        &mut self,
        device: &wgpu::Device,
        features: wgpu::Features,
        pass: &str,
        shader: &PassShader,
        key: ModuleKey,
    ) -> Result<(wgpu::ShaderModule, Arc<Vec<ShaderGlobal>>)> {
        if let Some(m) = self.modules.get(&key) {
            return Ok(m.clone());
        }
        let library = match &mut self.library {
            Some(l) => l,
            None => self
                .library
                .insert(
                    ShaderLibrary::new(capabilities_for(features)).map_err(|source| {
                        GraphError::Shader {
                            pass: pass.to_string(),
                            source,
                        }
                    })?,
                ),
        };
        let naga = library
            .compose(shader, &key.defs)
            .map_err(|source| GraphError::Shader {
                pass: pass.to_string(),
                source,
            })?;
        let globals = Arc::new(globals(&naga).map_err(|message| GraphError::Record {
            pass: pass.to_string(),
            message: format!("shader `{}` ({}): {message}", shader.name, shader.file_path),
        })?);
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some(shader.name),
            source: wgpu::ShaderSource::Naga(std::borrow::Cow::Owned(naga)),
        });
        self.modules.insert(key, (module.clone(), globals.clone()));
        Ok((module, globals))
    }

    pub fn compute(&self, key: &ProgramKey) -> Option<Arc<ComputeProgram>> {
        match self.programs.get(key) {
            Some(AnyProgram::Compute(p)) => Some(p.clone()),
            _ => None,
        }
    }
    pub fn render(&self, key: &ProgramKey) -> Option<Arc<RenderProgram>> {
        match self.programs.get(key) {
            Some(AnyProgram::Render(p)) => Some(p.clone()),
            _ => None,
        }
    }
    pub fn resolved(&self, graph: u64, pass: usize, index: usize) -> Option<&AnyProgram> {
        self.resolved.get(&(graph, pass))?.get(index)?.as_ref()
    }
    pub fn resolve(&mut self, graph: u64, pass: usize, index: usize, program: AnyProgram) {
        let slots = self.resolved.entry((graph, pass)).or_default();
        if slots.len() <= index {
            slots.resize(index + 1, None);
        }
        slots[index] = Some(program);
    }

    /// Whether every program of compiled graph `graph` is built.
    pub fn is_prepared(&self, graph: u64) -> bool {
        self.prepared.contains(&graph)
    }
    /// Notes that every program of compiled graph `graph` is built.
    pub fn prepared(&mut self, graph: u64) {
        self.prepared.insert(graph);
    }

    pub fn insert(&mut self, key: ProgramKey, program: AnyProgram) {
        self.pipelines_created += 1;
        self.programs.insert(key, program);
    }
}

/// naga capabilities matching the device's enabled features, so the composer accepts
/// exactly the shaders the device can run.
pub fn capabilities_for(features: wgpu::Features) -> naga::valid::Capabilities {
    FEATURE_CAPABILITIES
        .iter()
        .filter(|(feature, _)| features.contains(*feature))
        .fold(naga::valid::Capabilities::empty(), |caps, (_, cap)| {
            caps | *cap
        })
}

/// Each device feature that lets a shader use more of naga, with the capability it
/// grants.
const FEATURE_CAPABILITIES: [(wgpu::Features, naga::valid::Capabilities); 8] = {
    use naga::valid::Capabilities as C;
    use wgpu::Features as F;
    [
        (F::SHADER_INT64, C::SHADER_INT64),
        (
            F::SHADER_INT64_ATOMIC_MIN_MAX,
            C::SHADER_INT64_ATOMIC_MIN_MAX,
        ),
        (
            F::SHADER_INT64_ATOMIC_ALL_OPS,
            C::SHADER_INT64_ATOMIC_ALL_OPS,
        ),
        (F::SUBGROUP, C::SUBGROUP),
        (F::TEXTURE_ATOMIC, C::TEXTURE_ATOMIC),
        (F::TEXTURE_INT64_ATOMIC, C::TEXTURE_INT64_ATOMIC),
        (F::IMMEDIATES, C::IMMEDIATES),
        (F::EXPERIMENTAL_MESH_SHADER, C::MESH_SHADER),
    ]
};

/// Uniform blocks of one frame, packed into shared buffers at 256-byte alignment and
/// written once before the frame is submitted. Offsets repeat frame to frame, so bind
/// groups that use them are found in the cache.
#[derive(Default)]
pub(crate) struct UniformArena {
    chunks: Vec<wgpu::Buffer>,
    staged: Vec<Vec<u8>>,
    chunk: usize,
    offset: u64,
}

pub(crate) const CHUNK: u64 = 64 * 1024;
const ALIGN: u64 = 256;

impl UniformArena {
    pub fn begin_frame(&mut self) {
        self.chunk = 0;
        self.offset = 0;
        for s in &mut self.staged {
            s.clear();
        }
    }

    /// `None` when the block is larger than one chunk (such data belongs in a slot).
    pub fn push(
        &mut self,
        device: &wgpu::Device,
        bytes: &[u8],
    ) -> Option<(wgpu::Buffer, u64, u64)> {
        let size = (bytes.len() as u64).max(16).next_multiple_of(16);
        if size > CHUNK {
            return None;
        }
        if self.offset + size > CHUNK {
            self.chunk += 1;
            self.offset = 0;
        }
        while self.chunks.len() <= self.chunk {
            self.chunks
                .push(device.create_buffer(&wgpu::BufferDescriptor {
                    label: Some("meshlight uniforms"),
                    size: CHUNK,
                    usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
                    mapped_at_creation: false,
                }));
            self.staged.push(Vec::new());
        }
        let staged = &mut self.staged[self.chunk];
        staged.resize(self.offset as usize, 0);
        staged.extend_from_slice(bytes);
        staged.resize((self.offset + size) as usize, 0);
        let at = self.offset;
        self.offset = (self.offset + size).next_multiple_of(ALIGN);
        Some((self.chunks[self.chunk].clone(), at, size))
    }

    pub fn flush(&self, queue: &wgpu::Queue) {
        for (buffer, bytes) in self.chunks.iter().zip(&self.staged) {
            if !bytes.is_empty() {
                queue.write_buffer(buffer, 0, bytes);
            }
        }
    }
}
