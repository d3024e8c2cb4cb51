//! Resources the graph schedules: their descriptors, kinds and versioned handles.
//!
//! A handle names one *version* of a resource. Every write produces the next version, so a
//! pass that holds an old handle after someone else wrote the resource is caught at compile
//! time instead of racing on the GPU.

use serde::{Serialize, Serializer};
use std::borrow::Cow;
use std::marker::PhantomData;

/// Index of a resource inside one graph.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize)]
pub struct ResourceId(pub(crate) u32);

impl ResourceId {
    pub fn index(self) -> usize {
        self.0 as usize
    }
}

/// Marker for buffer handles (storage, uniform and indirect-argument buffers).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Buffer {}
/// Marker for texture handles.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Texture {}

/// A typed, versioned reference to a resource.
#[derive(Debug, PartialEq, Eq, Hash)]
pub struct Handle<K> {
    pub(crate) id: ResourceId,
    pub(crate) version: u32,
    _kind: PhantomData<K>,
}

impl<K> Clone for Handle<K> {
    fn clone(&self) -> Self {
        *self
    }
}
impl<K> Copy for Handle<K> {}

impl<K> Handle<K> {
    pub(crate) fn new(id: ResourceId, version: u32) -> Self {
        Self {
            id,
            version,
            _kind: PhantomData,
        }
    }
    /// Which resource this handle names, whatever its version.
    pub fn id(&self) -> ResourceId {
        self.id
    }
    /// The version named: 0 is the resource as declared, each write adds one.
    pub fn version(&self) -> u32 {
        self.version
    }
    /// Drops the kind, to bind buffers and textures in one list.
    pub fn erase(self) -> AnyHandle {
        AnyHandle {
            id: self.id,
            version: self.version,
        }
    }
}

/// A handle with its kind erased, used where slots of both kinds are bound together.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize)]
pub struct AnyHandle {
    /// Which resource.
    pub id: ResourceId,
    /// The version named: 0 is the resource as declared, each write adds one.
    pub version: u32,
}

impl<K> From<Handle<K>> for AnyHandle {
    fn from(h: Handle<K>) -> Self {
        h.erase()
    }
}

/// What a buffer holds, so a slot can check it is bound to the right kind of data.
#[derive(Clone, Debug, PartialEq, Eq, Hash, Serialize)]
pub struct Element {
    /// The type's name, compared when a slot checks what it is bound to and shown in dumps.
    pub name: Cow<'static, str>,
    /// Bytes per element.
    pub size: u32,
}

impl Element {
    /// A 32-bit word.
    pub const U32: Element = Element::named("u32", 4);
    /// A 64-bit word (visibility buffers).
    pub const U64: Element = Element::named("u64", 8);
    /// A 32-bit float.
    pub const F32: Element = Element::named("f32", 4);
    /// Four 32-bit floats.
    pub const VEC4_F32: Element = Element::named("vec4<f32>", 16);
    /// Three u32: `dispatch_workgroups_indirect` arguments.
    pub const DISPATCH_ARGS: Element = Element::named("DispatchIndirectArgs", 12);
    /// Four u32: `draw_indirect` arguments.
    pub const DRAW_ARGS: Element = Element::named("DrawIndirectArgs", 16);
    /// Bytes with no structure (staging, readback).
    pub const BYTES: Element = Element::named("u8", 1);

    /// An element type of `size` bytes, named `name` in dumps and messages.
    pub const fn named(name: &'static str, size: u32) -> Element {
        Element {
            name: Cow::Borrowed(name),
            size,
        }
    }

    /// Resolves the element names a pipeline file may use without declaring a size.
    pub fn from_known_name(name: &str) -> Option<Element> {
        [
            Self::U32,
            Self::U64,
            Self::F32,
            Self::VEC4_F32,
            Self::DISPATCH_ARGS,
            Self::DRAW_ARGS,
            Self::BYTES,
        ]
        .into_iter()
        .find(|e| e.name == name)
    }
}

/// A buffer's element type and count (fixed, or from a size parameter).
#[derive(Clone, Debug, PartialEq, Eq, Hash, Serialize)]
pub struct BufferDesc {
    /// Bytes. `u64::MAX` marks a size that overflowed, which compile reports.
    pub size: u64,
    /// What the buffer holds; a slot bound to it checks this.
    pub element: Element,
    /// The element count comes from this size parameter, set at compile time and changeable
    /// at run time ([`crate::CompiledGraph::set_param`]); `size` is then resolved from it.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub count_param: Option<String>,
}

impl BufferDesc {
    /// `count` elements; a product past `u64::MAX` is kept as an overflow for compile to
    /// report, never wrapped.
    pub fn array(element: Element, count: u64) -> Self {
        Self {
            size: (element.size as u64).saturating_mul(count),
            element,
            count_param: None,
        }
    }
    /// As many elements as the size parameter `param` says (declared with
    /// [`crate::GraphBuilder::size_param`]).
    pub fn array_param(element: Element, param: &str) -> Self {
        Self {
            size: 0,
            element,
            count_param: Some(param.to_string()),
        }
    }
    /// Raw bytes of one element type.
    pub fn bytes(element: Element, size: u64) -> Self {
        Self {
            size,
            element,
            count_param: None,
        }
    }
    /// How many whole elements fit in `size`.
    pub fn elements(&self) -> u64 {
        self.size / self.element.size.max(1) as u64
    }
    pub(crate) fn overflowed(&self) -> bool {
        self.size == u64::MAX
    }
}

/// A texture's format, size, mips and layers.
#[derive(Clone, Debug, PartialEq, Eq, Hash, Serialize)]
pub struct TextureDesc {
    /// The format; a slot that declares one checks it.
    #[serde(serialize_with = "crate::names::ser_format")]
    pub format: wgpu::TextureFormat,
    /// Width of mip 0, in texels.
    pub width: u32,
    /// Height of mip 0, in texels.
    pub height: u32,
    /// Mip levels, at least 1.
    pub mip_levels: u32,
    /// Array layers; 1 is a plain 2-D texture, more make a 2-D array.
    pub layers: u32,
}

impl TextureDesc {
    /// A 2-D texture of one mip and one layer.
    pub fn d2(format: wgpu::TextureFormat, width: u32, height: u32) -> Self {
        Self {
            format,
            width,
            height,
            mip_levels: 1,
            layers: 1,
        }
    }
    /// A full mip chain down to 1×1 (`floor(log2(max(w, h))) + 1` levels).
    pub fn with_full_mips(mut self) -> Self {
        self.mip_levels = 32 - self.width.max(self.height).max(1).leading_zeros();
        self
    }
    /// Sets the mip count (see [`TextureDesc::with_full_mips`] for a whole chain).
    pub fn with_mips(mut self, mip_levels: u32) -> Self {
        self.mip_levels = mip_levels;
        self
    }
    /// Sets the layer count; more than 1 makes a 2-D array.
    pub fn with_layers(mut self, layers: u32) -> Self {
        self.layers = layers;
        self
    }
    /// Bytes of every mip and layer, for pool accounting.
    pub fn bytes(&self) -> u64 {
        let block = self.format.block_copy_size(None).unwrap_or(4) as u64;
        let per_layer: u64 = (0..self.mip_levels.min(32))
            .map(|m| ((self.width >> m).max(1) as u64) * ((self.height >> m).max(1) as u64) * block)
            .sum();
        per_layer.saturating_mul(self.layers.max(1) as u64)
    }
    /// Every mip and layer.
    pub fn full_range(&self) -> TextureRange {
        TextureRange {
            base_mip: 0,
            mip_count: self.mip_levels,
            base_layer: 0,
            layer_count: self.layers,
        }
    }
    /// Width and height of mip `level`.
    pub fn mip_size(&self, level: u32) -> (u32, u32) {
        ((self.width >> level).max(1), (self.height >> level).max(1))
    }
}

/// A part of a texture a slot binds: mips `base_mip..base_mip + mip_count` of layers
/// `base_layer..base_layer + layer_count`. Two slots of one pass may bind one texture when
/// their ranges are disjoint, so a pass can read mip N − 1 while writing mip N.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize)]
pub struct TextureRange {
    /// First mip.
    pub base_mip: u32,
    /// Mips from `base_mip`; `u32::MAX` means "to the last" until [`TextureRange::resolve`].
    pub mip_count: u32,
    /// First array layer.
    pub base_layer: u32,
    /// Layers from `base_layer`; `u32::MAX` means "to the last" until [`TextureRange::resolve`].
    pub layer_count: u32,
}

impl TextureRange {
    /// One mip of every layer (the layer count is filled in from the texture).
    pub fn mip(level: u32) -> Self {
        Self {
            base_mip: level,
            mip_count: 1,
            base_layer: 0,
            layer_count: u32::MAX,
        }
    }
    /// Mips `first..first + count` of every layer.
    pub fn mips(first: u32, count: u32) -> Self {
        Self {
            base_mip: first,
            mip_count: count,
            base_layer: 0,
            layer_count: u32::MAX,
        }
    }
    /// One layer, every mip.
    pub fn layer(layer: u32) -> Self {
        Self {
            base_mip: 0,
            mip_count: u32::MAX,
            base_layer: layer,
            layer_count: 1,
        }
    }
    /// `u32::MAX` counts mean "to the end"; resolves them against `desc`.
    pub fn resolve(self, desc: &TextureDesc) -> Self {
        let mip_count = if self.mip_count == u32::MAX {
            desc.mip_levels.saturating_sub(self.base_mip)
        } else {
            self.mip_count
        };
        let layer_count = if self.layer_count == u32::MAX {
            desc.layers.saturating_sub(self.base_layer)
        } else {
            self.layer_count
        };
        Self {
            mip_count,
            layer_count,
            ..self
        }
    }
    /// True when the two ranges share a mip of a layer, so two slots cannot bind them apart.
    pub fn overlaps(&self, other: &TextureRange) -> bool {
        let span =
            |a: u32, n: u32, b: u32, m: u32| a < b.saturating_add(m) && b < a.saturating_add(n);
        span(
            self.base_mip,
            self.mip_count,
            other.base_mip,
            other.mip_count,
        ) && span(
            self.base_layer,
            self.layer_count,
            other.base_layer,
            other.layer_count,
        )
    }
    /// `mips 1..2`, `layer 3`, … for dumps.
    pub fn label(&self) -> String {
        let mips = if self.mip_count == 1 {
            format!("mip {}", self.base_mip)
        } else {
            format!("mips {}..{}", self.base_mip, self.base_mip + self.mip_count)
        };
        if self.base_layer == 0 && self.layer_count <= 1 {
            mips
        } else {
            format!(
                "{mips}, layers {}..{}",
                self.base_layer,
                self.base_layer + self.layer_count
            )
        }
    }
    /// True when the range lies inside `desc`.
    pub fn fits(&self, desc: &TextureDesc) -> bool {
        self.mip_count > 0
            && self.layer_count > 0
            && self.base_mip as u64 + self.mip_count as u64 <= desc.mip_levels as u64
            && self.base_layer as u64 + self.layer_count as u64 <= desc.layers as u64
    }
}

/// A buffer or a texture, as declared.
#[derive(Clone, Debug, PartialEq, Eq, Hash, Serialize)]
#[serde(tag = "type", rename_all = "snake_case")]
pub enum ResourceDesc {
    /// A buffer.
    Buffer(BufferDesc),
    /// A texture.
    Texture(TextureDesc),
}

impl ResourceDesc {
    /// Bytes it takes on the GPU (every mip and layer of a texture).
    pub fn bytes(&self) -> u64 {
        match self {
            ResourceDesc::Buffer(b) => b.size,
            ResourceDesc::Texture(t) => t.bytes(),
        }
    }
    /// `"buffer"` or `"texture"`, for messages and dumps.
    pub fn kind_name(&self) -> &'static str {
        match self {
            ResourceDesc::Buffer(_) => "buffer",
            ResourceDesc::Texture(_) => "texture",
        }
    }
}

/// Who owns a resource and how long it lives.
#[derive(Clone, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum ResourceKind {
    /// Lives within one frame and is placed in a pool slot the graph chooses.
    Transient,
    /// Owned by the caller, who passes it in when the frame runs; `usage` is what it was
    /// created with, so a pass cannot ask for more than the caller allowed.
    Imported {
        /// What the caller allowed, as buffer or texture usage flags.
        #[serde(serialize_with = "ser_imported_usage")]
        usage: ImportedUsage,
    },
    /// Written this frame and read next frame through its `prev` twin.
    History {
        /// The `<name>.prev` resource that holds last frame's contents.
        prev: ResourceId,
    },
    /// Last frame's contents of a history resource; read-only.
    HistoryPrev {
        /// The history resource this frame writes.
        current: ResourceId,
    },
    /// A transient the caller reads back after the frame; kept out of slot sharing.
    Exported,
    /// Scratch memory owned by a single pass, declared in its setup.
    Scratch {
        /// Index of the owning pass, in the order passes were added.
        pass: usize,
    },
}

/// The usage an imported resource was created with.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ImportedUsage {
    Buffer(wgpu::BufferUsages),
    Texture(wgpu::TextureUsages),
}

/// Serialises an import's usage as the flag names of its buffer or texture usage.
fn ser_imported_usage<S: Serializer>(u: &ImportedUsage, s: S) -> Result<S::Ok, S::Error> {
    match u {
        ImportedUsage::Buffer(b) => crate::names::flag_names(b).serialize(s),
        ImportedUsage::Texture(t) => crate::names::flag_names(t).serialize(s),
    }
}

#[derive(Clone, Debug, Serialize)]
pub struct ResourceInfo {
    pub name: String,
    pub desc: ResourceDesc,
    pub kind: ResourceKind,
}

impl ResourceInfo {
    /// True when its contents outlive the frame, so passes writing it are never culled.
    pub fn is_visible_outside(&self) -> bool {
        matches!(
            self.kind,
            ResourceKind::Imported { .. } | ResourceKind::History { .. } | ResourceKind::Exported
        )
    }
    /// True when version 0 holds meaningful data before any pass writes it.
    pub fn starts_written(&self) -> bool {
        matches!(
            self.kind,
            ResourceKind::Imported { .. } | ResourceKind::HistoryPrev { .. }
        )
    }
}
