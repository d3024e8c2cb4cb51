//! Resources the graph schedules: their descriptors, kinds and versioned handles.
//!
//! A handle names one *version* of a resource. Every write produces the next version, so a
//! pass that holds an old handle after someone else wrote the resource is caught at compile
//! time instead of racing on the GPU.

use serde::Serialize;
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
    pub fn id(&self) -> ResourceId {
        self.id
    }
    pub fn version(&self) -> u32 {
        self.version
    }
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
    pub id: ResourceId,
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
    pub name: Cow<'static, str>,
    pub size: u32,
}

impl Element {
    pub const U32: Element = Element {
        name: Cow::Borrowed("u32"),
        size: 4,
    };
    pub const U64: Element = Element {
        name: Cow::Borrowed("u64"),
        size: 8,
    };
    pub const F32: Element = Element {
        name: Cow::Borrowed("f32"),
        size: 4,
    };
    pub const VEC4_F32: Element = Element {
        name: Cow::Borrowed("vec4<f32>"),
        size: 16,
    };
    /// Three u32: `dispatch_workgroups_indirect` arguments.
    pub const DISPATCH_ARGS: Element = Element {
        name: Cow::Borrowed("DispatchIndirectArgs"),
        size: 12,
    };
    /// Four u32: `draw_indirect` arguments.
    pub const DRAW_ARGS: Element = Element {
        name: Cow::Borrowed("DrawIndirectArgs"),
        size: 16,
    };
    /// Bytes with no structure (staging, readback).
    pub const BYTES: Element = Element {
        name: Cow::Borrowed("u8"),
        size: 1,
    };

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

#[derive(Clone, Debug, PartialEq, Eq, Hash, Serialize)]
pub struct BufferDesc {
    pub size: u64,
    pub element: Element,
}

impl BufferDesc {
    pub fn array(element: Element, count: u64) -> Self {
        Self {
            size: element.size as u64 * count,
            element,
        }
    }
    pub fn elements(&self) -> u64 {
        self.size / self.element.size.max(1) as u64
    }
}

#[derive(Clone, Debug, PartialEq, Eq, Hash, Serialize)]
pub struct TextureDesc {
    #[serde(serialize_with = "crate::plan::ser_format")]
    pub format: wgpu::TextureFormat,
    pub width: u32,
    pub height: u32,
    pub mip_levels: u32,
}

impl TextureDesc {
    pub fn d2(format: wgpu::TextureFormat, width: u32, height: u32) -> Self {
        Self {
            format,
            width,
            height,
            mip_levels: 1,
        }
    }
    pub fn bytes(&self) -> u64 {
        let block = self.format.block_copy_size(None).unwrap_or(4) as u64;
        (0..self.mip_levels)
            .map(|m| ((self.width >> m).max(1) as u64) * ((self.height >> m).max(1) as u64) * block)
            .sum()
    }
}

#[derive(Clone, Debug, PartialEq, Eq, Hash, Serialize)]
#[serde(tag = "type", rename_all = "snake_case")]
pub enum ResourceDesc {
    Buffer(BufferDesc),
    Texture(TextureDesc),
}

impl ResourceDesc {
    pub fn bytes(&self) -> u64 {
        match self {
            ResourceDesc::Buffer(b) => b.size,
            ResourceDesc::Texture(t) => t.bytes(),
        }
    }
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
        #[serde(serialize_with = "crate::plan::ser_buffer_usage_or_texture")]
        usage: ImportedUsage,
    },
    /// Written this frame and read next frame through its `prev` twin.
    History { prev: ResourceId },
    /// Last frame's contents of a history resource; read-only.
    HistoryPrev { current: ResourceId },
    /// A transient the caller reads back after the frame; kept out of slot sharing.
    Exported,
    /// Scratch memory owned by a single pass, declared in its setup.
    Scratch { pass: usize },
}

/// The usage an imported resource was created with.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ImportedUsage {
    Buffer(wgpu::BufferUsages),
    Texture(wgpu::TextureUsages),
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
