//! How a pass uses a resource, and the wgpu usage flags each use needs.

use serde::Serialize;

/// How a pass uses a resource through a slot: the graph derives barriers-free ordering,
/// usages, load/store ops and binding types from it.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Access {
    /// Read-only storage buffer or texture (`var<storage, read>`).
    StorageRead,
    /// Uniform buffer.
    Uniform,
    /// Sampled texture.
    Sampled,
    /// Indirect dispatch or draw arguments.
    Indirect,
    /// Vertex buffer.
    Vertex,
    /// Index buffer.
    Index,
    /// Source of a copy.
    CopySrc,
    /// Write-only storage: the pass overwrites what it touches and reads nothing.
    StorageWrite,
    /// Colour render target.
    RenderTarget,
    /// Depth render target.
    DepthTarget,
    /// Destination of a copy or a clear.
    CopyDst,
    /// Read-write storage: atomics, in-place updates, accumulation onto earlier contents.
    StorageReadWrite,
    /// Cleared by the pass, then read and written (atomic counters, `atomicMax` targets):
    /// read-write inside the pass, but nothing written before it matters, so a fresh
    /// transient needs no writer.
    ClearedReadWrite,
}

impl Access {
    /// True when the pass depends on what earlier passes wrote.
    pub fn reads(self) -> bool {
        !matches!(
            self,
            Access::StorageWrite
                | Access::RenderTarget
                | Access::DepthTarget
                | Access::CopyDst
                | Access::ClearedReadWrite
        )
    }
    /// True when the pass makes a new version of the resource.
    pub fn writes(self) -> bool {
        matches!(
            self,
            Access::StorageWrite
                | Access::RenderTarget
                | Access::DepthTarget
                | Access::CopyDst
                | Access::StorageReadWrite
                | Access::ClearedReadWrite
        )
    }
    /// True for storage accesses the shader both reads and writes (atomics).
    pub fn read_write_storage(self) -> bool {
        matches!(self, Access::StorageReadWrite | Access::ClearedReadWrite)
    }
    /// The access's name in dumps and messages, e.g. `storage-read`.
    pub fn name(self) -> &'static str {
        match self {
            Access::StorageRead => "storage-read",
            Access::Uniform => "uniform",
            Access::Sampled => "sampled",
            Access::Indirect => "indirect",
            Access::Vertex => "vertex",
            Access::Index => "index",
            Access::CopySrc => "copy-src",
            Access::StorageWrite => "storage-write",
            Access::RenderTarget => "render-target",
            Access::DepthTarget => "depth-target",
            Access::CopyDst => "copy-dst",
            Access::StorageReadWrite => "storage-read-write",
            Access::ClearedReadWrite => "cleared-read-write",
        }
    }
    /// The buffer usage this access needs, or `None` when a buffer cannot be used this way.
    pub fn buffer_usage(self) -> Option<wgpu::BufferUsages> {
        use wgpu::BufferUsages as U;
        Some(match self {
            Access::StorageRead | Access::StorageWrite | Access::StorageReadWrite => U::STORAGE,
            // The clear is a fill command, which needs COPY_DST.
            Access::ClearedReadWrite => U::STORAGE | U::COPY_DST,
            Access::Uniform => U::UNIFORM,
            Access::Indirect => U::INDIRECT,
            Access::Vertex => U::VERTEX,
            Access::Index => U::INDEX,
            Access::CopySrc => U::COPY_SRC,
            Access::CopyDst => U::COPY_DST,
            Access::Sampled | Access::RenderTarget | Access::DepthTarget => return None,
        })
    }
    /// The texture usage this access needs, or `None` when a texture cannot be used this
    /// way.
    pub fn texture_usage(self) -> Option<wgpu::TextureUsages> {
        use wgpu::TextureUsages as U;
        Some(match self {
            Access::StorageRead | Access::StorageWrite | Access::StorageReadWrite => {
                U::STORAGE_BINDING
            }
            Access::ClearedReadWrite => U::STORAGE_BINDING | U::COPY_DST,
            Access::Sampled => U::TEXTURE_BINDING,
            Access::RenderTarget | Access::DepthTarget => U::RENDER_ATTACHMENT,
            Access::CopySrc => U::COPY_SRC,
            Access::CopyDst => U::COPY_DST,
            Access::Uniform | Access::Indirect | Access::Vertex | Access::Index => return None,
        })
    }
}

/// The texture usage `access` needs on a texture of `format`: read-write storage on an
/// `R64Uint` texture is 64-bit atomics, which need `STORAGE_ATOMIC` too.
pub fn texture_usage_for(
    access: Access,
    format: wgpu::TextureFormat,
) -> Option<wgpu::TextureUsages> {
    let usage = access.texture_usage()?;
    Some(
        if access.read_write_storage() && format == wgpu::TextureFormat::R64Uint {
            usage | wgpu::TextureUsages::STORAGE_ATOMIC
        } else {
            usage
        },
    )
}

/// Device features a slot of `access` on a texture of `format` needs.
pub fn texture_features_for(access: Access, format: wgpu::TextureFormat) -> wgpu::Features {
    if access.read_write_storage() && format == wgpu::TextureFormat::R64Uint {
        wgpu::Features::TEXTURE_ATOMIC | wgpu::Features::TEXTURE_INT64_ATOMIC
    } else {
        wgpu::Features::empty()
    }
}

/// True when a slot with these uses depends on contents written before its pass: some use
/// reads, and none overwrites or clears first.
pub fn reads_earlier(mut accesses: impl Iterator<Item = Access> + Clone) -> bool {
    let overwrites = accesses.clone().any(|a| a.writes() && !a.reads());
    !overwrites && accesses.any(Access::reads)
}
