//! Caches that make a steady frame cheap to record: composed shader modules and pipelines
//! by (shader, entry, defs, layouts); bind-group layouts by their entries; bind groups by
//! the exact resources they bind; and a per-frame arena for small uniform blocks.

use crate::error::{GraphError, Result};
use meshlight_shaders::{PassShader, ShaderDef, ShaderLibrary};
use std::collections::HashMap;
use std::sync::Arc;

/// A compute pipeline and the bind-group layouts it was built with.
pub struct ComputeProgram {
    pub pipeline: wgpu::ComputePipeline,
    pub(crate) layouts: Vec<(crate::exec::BindingLayout, wgpu::BindGroupLayout)>,
}

#[derive(Clone, PartialEq, Eq, Hash)]
pub(crate) struct ModuleKey {
    pub shader: &'static str,
    pub defs: Vec<(&'static str, ShaderDef)>,
}

#[derive(Clone, PartialEq, Eq, Hash)]
pub(crate) struct ProgramKey {
    pub module: ModuleKey,
    pub entry: &'static str,
    /// The declared layouts: two passes whose wgpu layouts agree but whose slots differ
    /// must not share a program, since the program remembers where each binding comes from.
    pub declared: Vec<crate::exec::BindingLayout>,
    pub layouts: Vec<Vec<wgpu::BindGroupLayoutEntry>>,
}

#[derive(Clone, PartialEq, Eq, Hash)]
pub(crate) enum BoundResource {
    Buffer {
        buffer: wgpu::Buffer,
        offset: u64,
        size: u64,
    },
    View(wgpu::TextureView),
}

#[derive(Clone, PartialEq, Eq, Hash)]
pub(crate) struct BindGroupKey {
    pub layout: wgpu::BindGroupLayout,
    pub entries: Vec<(u32, BoundResource)>,
}

pub(crate) struct Programs {
    pub library: Option<ShaderLibrary>,
    modules: HashMap<ModuleKey, wgpu::ShaderModule>,
    compute: HashMap<ProgramKey, Arc<ComputeProgram>>,
    layouts: HashMap<Vec<wgpu::BindGroupLayoutEntry>, wgpu::BindGroupLayout>,
    pub bind_groups: HashMap<BindGroupKey, wgpu::BindGroup>,
    pub uniforms: UniformArena,
    pub pipelines_created: u32,
}

impl Programs {
    pub fn new() -> Self {
        Self {
            library: None,
            modules: HashMap::new(),
            compute: HashMap::new(),
            layouts: HashMap::new(),
            bind_groups: HashMap::new(),
            uniforms: UniformArena::default(),
            pipelines_created: 0,
        }
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

    pub fn module(
        &mut self,
        device: &wgpu::Device,
        features: wgpu::Features,
        pass: &str,
        shader: &PassShader,
        key: ModuleKey,
    ) -> Result<wgpu::ShaderModule> {
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
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some(shader.name),
            source: wgpu::ShaderSource::Naga(std::borrow::Cow::Owned(naga)),
        });
        self.modules.insert(key, module.clone());
        Ok(module)
    }

    pub fn compute_program(&self, key: &ProgramKey) -> Option<Arc<ComputeProgram>> {
        self.compute.get(key).cloned()
    }
    pub fn insert_compute_program(
        &mut self,
        key: ProgramKey,
        program: ComputeProgram,
    ) -> Arc<ComputeProgram> {
        self.pipelines_created += 1;
        let p = Arc::new(program);
        self.compute.insert(key, p.clone());
        p
    }
}

/// naga capabilities matching the device's enabled features, so the composer accepts
/// exactly the shaders the device can run.
pub fn capabilities_for(features: wgpu::Features) -> naga::valid::Capabilities {
    use naga::valid::Capabilities as C;
    let mut caps = C::empty();
    if features.contains(wgpu::Features::SHADER_INT64) {
        caps |= C::SHADER_INT64;
    }
    if features.contains(wgpu::Features::SHADER_INT64_ATOMIC_MIN_MAX) {
        caps |= C::SHADER_INT64_ATOMIC_MIN_MAX;
    }
    if features.contains(wgpu::Features::SHADER_INT64_ATOMIC_ALL_OPS) {
        caps |= C::SHADER_INT64_ATOMIC_ALL_OPS;
    }
    if features.contains(wgpu::Features::SUBGROUP) {
        caps |= C::SUBGROUP;
    }
    if features.contains(wgpu::Features::TEXTURE_INT64_ATOMIC) {
        caps |= C::TEXTURE_INT64_ATOMIC;
    }
    caps
}

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
