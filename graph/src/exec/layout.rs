//! Bind-group layouts declared in terms of slots: a pass says which slot sits at which
//! binding, and the graph derives the wgpu binding type from the slot's access and the
//! bound resource, so layouts can never disagree with the contract.

use crate::access::Access;

#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub enum BindingSource {
    /// A contract slot.
    Slot(&'static str),
    /// A scratch buffer the pass declared in setup, used with this access.
    Scratch(&'static str, Access),
    /// A small uniform block whose bytes the pass passes when it builds the bind group.
    Uniform,
}

#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub struct LayoutEntry {
    pub binding: u32,
    pub source: BindingSource,
}

/// One bind group of a pipeline, as a labelled list of slot bindings.
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub struct BindingLayout {
    pub label: &'static str,
    pub visibility: wgpu::ShaderStages,
    pub entries: Vec<LayoutEntry>,
}

impl BindingLayout {
    pub fn compute(label: &'static str) -> Self {
        Self {
            label,
            visibility: wgpu::ShaderStages::COMPUTE,
            entries: Vec::new(),
        }
    }
    pub fn with_visibility(label: &'static str, visibility: wgpu::ShaderStages) -> Self {
        Self {
            label,
            visibility,
            entries: Vec::new(),
        }
    }
    pub fn slot(mut self, binding: u32, slot: &'static str) -> Self {
        self.entries.push(LayoutEntry {
            binding,
            source: BindingSource::Slot(slot),
        });
        self
    }
    pub fn scratch(mut self, binding: u32, name: &'static str, access: Access) -> Self {
        self.entries.push(LayoutEntry {
            binding,
            source: BindingSource::Scratch(name, access),
        });
        self
    }
    pub fn uniform(mut self, binding: u32) -> Self {
        self.entries.push(LayoutEntry {
            binding,
            source: BindingSource::Uniform,
        });
        self
    }
}

/// The wgpu binding type for a buffer used with `access`.
pub fn buffer_binding_type(access: Access) -> Option<wgpu::BindingType> {
    let ty = match access {
        Access::Uniform => wgpu::BufferBindingType::Uniform,
        Access::StorageRead => wgpu::BufferBindingType::Storage { read_only: true },
        Access::StorageWrite | Access::StorageReadWrite => {
            wgpu::BufferBindingType::Storage { read_only: false }
        }
        _ => return None,
    };
    Some(wgpu::BindingType::Buffer {
        ty,
        has_dynamic_offset: false,
        min_binding_size: None,
    })
}

/// The wgpu binding type for a texture of `format` used with `access`.
pub fn texture_binding_type(
    access: Access,
    format: wgpu::TextureFormat,
) -> Option<wgpu::BindingType> {
    let storage = |a| wgpu::BindingType::StorageTexture {
        access: a,
        format,
        view_dimension: wgpu::TextureViewDimension::D2,
    };
    Some(match access {
        Access::Sampled => wgpu::BindingType::Texture {
            sample_type: format
                .sample_type(None, None)
                .unwrap_or(wgpu::TextureSampleType::Float { filterable: false }),
            view_dimension: wgpu::TextureViewDimension::D2,
            multisampled: false,
        },
        Access::StorageRead => storage(wgpu::StorageTextureAccess::ReadOnly),
        Access::StorageWrite => storage(wgpu::StorageTextureAccess::WriteOnly),
        Access::StorageReadWrite if format == wgpu::TextureFormat::R64Uint => {
            storage(wgpu::StorageTextureAccess::Atomic)
        }
        Access::StorageReadWrite => storage(wgpu::StorageTextureAccess::ReadWrite),
        _ => return None,
    })
}
