//! Bind-group layouts declared in terms of slots: a pass says which slot sits at which
//! binding, and the graph derives the wgpu binding type from the slot's access and the
//! bound resource, so layouts can never disagree with the contract.

use crate::access::Access;

/// What one binding of a layout binds.
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub enum BindingSource {
    /// A contract slot.
    Slot(&'static str),
    /// A scratch buffer the pass declared in setup, used with this access.
    Scratch(std::borrow::Cow<'static, str>, Access),
    /// A small uniform block, named as its WGSL variable: the pass gives its bytes under
    /// that name when it builds the bind group, as it names slots and scratch resources.
    Uniform(std::borrow::Cow<'static, str>),
    /// A sampler the graph creates and caches.
    Sampler(SamplerKind),
}

/// The samplers a layout can ask for. wgpu 30 has no min/max reduction samplers, so a
/// conservative depth pyramid takes the minimum of its texel loads itself.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum SamplerKind {
    /// Linear filtering, clamped to the edge.
    Linear,
    /// Nearest texel, clamped: for integer and non-filterable formats (r32float).
    Nearest,
    /// A depth comparison sampler (`less-equal`).
    Comparison,
}

impl SamplerKind {
    pub(crate) fn binding_type(self) -> wgpu::BindingType {
        wgpu::BindingType::Sampler(match self {
            SamplerKind::Linear => wgpu::SamplerBindingType::Filtering,
            SamplerKind::Nearest => wgpu::SamplerBindingType::NonFiltering,
            SamplerKind::Comparison => wgpu::SamplerBindingType::Comparison,
        })
    }
    pub(crate) fn descriptor(self) -> wgpu::SamplerDescriptor<'static> {
        let filter = match self {
            SamplerKind::Linear | SamplerKind::Comparison => wgpu::FilterMode::Linear,
            SamplerKind::Nearest => wgpu::FilterMode::Nearest,
        };
        wgpu::SamplerDescriptor {
            label: Some("meshlight sampler"),
            address_mode_u: wgpu::AddressMode::ClampToEdge,
            address_mode_v: wgpu::AddressMode::ClampToEdge,
            address_mode_w: wgpu::AddressMode::ClampToEdge,
            mag_filter: filter,
            min_filter: filter,
            mipmap_filter: match filter {
                wgpu::FilterMode::Linear => wgpu::MipmapFilterMode::Linear,
                wgpu::FilterMode::Nearest => wgpu::MipmapFilterMode::Nearest,
            },
            compare: (self == SamplerKind::Comparison).then_some(wgpu::CompareFunction::LessEqual),
            ..Default::default()
        }
    }
}

/// One binding of a [`BindingLayout`].
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub struct LayoutEntry {
    /// The `@binding` number in the group.
    pub binding: u32,
    /// What is bound there.
    pub source: BindingSource,
    /// Stages that see this binding; `None`: the layout's default.
    pub visibility: Option<wgpu::ShaderStages>,
    /// Bound read-only although the slot writes: a later dispatch of the same pass reads
    /// what an earlier one wrote (`var<storage, read>` in its shader).
    pub read_only: bool,
    /// Bound write-only although the slot also reads: a clearing dispatch stores into a
    /// texture the pass then uses with atomics (an `R64Uint` target has no render-pass
    /// clear, and wgpu's texture clear copies from a buffer).
    pub write_only: bool,
}

/// One bind group of a pipeline, as a labelled list of slot bindings.
///
/// A layout made [`Self::from_shader`] lists only what the shader cannot say (samplers);
/// every other binding the program's entry points use is read from the composed module
/// when the program is built: a WGSL global named like a slot binds that slot, one named
/// like a scratch resource binds it, a `var<uniform>` takes the bytes the pass gives under
/// the variable's name. A global that matches nothing, or writes a read-only slot, or
/// whose array element differs from the slot's, is an error naming the variable.
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub struct BindingLayout {
    /// The bind group layout's label, seen in wgpu's messages and GPU captures.
    pub label: &'static str,
    /// Stages that see an entry that does not set its own.
    pub visibility: wgpu::ShaderStages,
    /// The bindings, in the order they were listed.
    pub entries: Vec<LayoutEntry>,
    /// Fill in the shader's other bindings when the program is built.
    pub reflect: bool,
    /// Uniforms the shader declares in this group that none of the program's entry points
    /// uses, filled in by reflection: bytes given for them are accepted and dropped, so
    /// one list of a shader's uniforms serves each of its entry points, while a name the
    /// shader does not declare at all is still an error.
    pub(crate) unused_uniforms: Vec<std::borrow::Cow<'static, str>>,
}

impl BindingLayout {
    /// An empty layout for a compute program, entries listed by hand.
    pub fn compute(label: &'static str) -> Self {
        Self::with_visibility(label, wgpu::ShaderStages::COMPUTE)
    }
    /// An empty layout whose entries default to `visibility`.
    pub fn with_visibility(label: &'static str, visibility: wgpu::ShaderStages) -> Self {
        Self {
            label,
            visibility,
            entries: Vec::new(),
            reflect: false,
            unused_uniforms: Vec::new(),
        }
    }
    /// The layout of group 0 read from the shader, for a compute program (see the type's
    /// docs); chain `.sampler(..)` for what a name cannot say.
    pub fn from_shader(label: &'static str) -> Self {
        Self {
            reflect: true,
            ..Self::compute(label)
        }
    }
    /// [`Self::from_shader`] for a render program (explicit entries default to vertex +
    /// fragment; read ones get the stages that use them).
    pub fn from_shader_render(label: &'static str) -> Self {
        Self {
            reflect: true,
            ..Self::render(label)
        }
    }
    /// Vertex + fragment (+ mesh and task where a mesh program uses the layout).
    pub fn render(label: &'static str) -> Self {
        Self::with_visibility(label, wgpu::ShaderStages::VERTEX_FRAGMENT)
    }
    fn push(mut self, binding: u32, source: BindingSource) -> Self {
        self.entries.push(LayoutEntry {
            binding,
            source,
            visibility: None,
            read_only: false,
            write_only: false,
        });
        self
    }
    /// Binds `slot` at `binding`.
    pub fn slot(self, binding: u32, slot: &'static str) -> Self {
        self.push(binding, BindingSource::Slot(slot))
    }
    /// Binds the pass's scratch resource `name` at `binding`, used as `access`.
    pub fn scratch(self, binding: u32, name: &'static str, access: Access) -> Self {
        self.push(binding, BindingSource::Scratch(name.into(), access))
    }
    /// Binds a uniform buffer at `binding`, filled with the bytes the pass gives under
    /// `name` when it records; `name` is the WGSL variable's (a layout read from the
    /// shader checks that).
    pub fn uniform(self, binding: u32, name: &'static str) -> Self {
        self.push(binding, BindingSource::Uniform(name.into()))
    }
    /// Binds a sampler of `kind` at `binding`.
    pub fn sampler(self, binding: u32, kind: SamplerKind) -> Self {
        self.push(binding, BindingSource::Sampler(kind))
    }
    /// Binds the entry added last as read-only storage, whatever the slot's access.
    pub fn read_only(mut self) -> Self {
        if let Some(e) = self.entries.last_mut() {
            e.read_only = true;
        }
        self
    }
    /// Binds the entry added last as write-only storage, whatever the slot's access.
    pub fn write_only(mut self) -> Self {
        if let Some(e) = self.entries.last_mut() {
            e.write_only = true;
        }
        self
    }
    /// Gives the entry added last its own stages, e.g. a storage buffer only the fragment
    /// shader writes.
    pub fn visible_in(mut self, stages: wgpu::ShaderStages) -> Self {
        if let Some(e) = self.entries.last_mut() {
            e.visibility = Some(stages);
        }
        self
    }
}

/// The wgpu binding type for a buffer used with `access`.
pub fn buffer_binding_type(access: Access) -> Option<wgpu::BindingType> {
    let ty = match access {
        Access::Uniform => wgpu::BufferBindingType::Uniform,
        Access::StorageRead => wgpu::BufferBindingType::Storage { read_only: true },
        Access::StorageWrite | Access::StorageReadWrite | Access::ClearedReadWrite => {
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

/// The wgpu binding type for a texture of `format` used with `access`, seen as a 2-D
/// texture or, when `array` is set, a 2-D array.
pub fn texture_binding_type(
    access: Access,
    format: wgpu::TextureFormat,
    array: bool,
) -> Option<wgpu::BindingType> {
    let view_dimension = if array {
        wgpu::TextureViewDimension::D2Array
    } else {
        wgpu::TextureViewDimension::D2
    };
    let storage = |a| wgpu::BindingType::StorageTexture {
        access: a,
        format,
        view_dimension,
    };
    Some(match access {
        Access::Sampled => wgpu::BindingType::Texture {
            sample_type: format
                .sample_type(None, None)
                .unwrap_or(wgpu::TextureSampleType::Float { filterable: false }),
            view_dimension,
            multisampled: false,
        },
        Access::StorageRead => storage(wgpu::StorageTextureAccess::ReadOnly),
        Access::StorageWrite => storage(wgpu::StorageTextureAccess::WriteOnly),
        a if a.read_write_storage() && format == wgpu::TextureFormat::R64Uint => {
            storage(wgpu::StorageTextureAccess::Atomic)
        }
        a if a.read_write_storage() => storage(wgpu::StorageTextureAccess::ReadWrite),
        _ => return None,
    })
}
