//! How a pass uses a resource, and the wgpu usage flags each use needs.

use serde::Serialize;

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
    /// Read-write storage: atomics, in-place updates, accumulation.
    StorageReadWrite,
}

impl Access {
    pub fn reads(self) -> bool {
        !matches!(
            self,
            Access::StorageWrite | Access::RenderTarget | Access::DepthTarget | Access::CopyDst
        )
    }
    pub fn writes(self) -> bool {
        matches!(
            self,
            Access::StorageWrite
                | Access::RenderTarget
                | Access::DepthTarget
                | Access::CopyDst
                | Access::StorageReadWrite
        )
    }
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
        }
    }
    /// The buffer usage this access needs, or `None` when a buffer cannot be used this way.
    pub fn buffer_usage(self) -> Option<wgpu::BufferUsages> {
        use wgpu::BufferUsages as U;
        Some(match self {
            Access::StorageRead | Access::StorageWrite | Access::StorageReadWrite => U::STORAGE,
            Access::Uniform => U::UNIFORM,
            Access::Indirect => U::INDIRECT,
            Access::Vertex => U::VERTEX,
            Access::Index => U::INDEX,
            Access::CopySrc => U::COPY_SRC,
            Access::CopyDst => U::COPY_DST,
            Access::Sampled | Access::RenderTarget | Access::DepthTarget => return None,
        })
    }
    /// The texture usage this access needs, or `None` when a texture cannot be used this way.
    pub fn texture_usage(self) -> Option<wgpu::TextureUsages> {
        use wgpu::TextureUsages as U;
        Some(match self {
            Access::StorageRead | Access::StorageWrite | Access::StorageReadWrite => {
                U::STORAGE_BINDING
            }
            Access::Sampled => U::TEXTURE_BINDING,
            Access::RenderTarget | Access::DepthTarget => U::RENDER_ATTACHMENT,
            Access::CopySrc => U::COPY_SRC,
            Access::CopyDst => U::COPY_DST,
            Access::Uniform | Access::Indirect | Access::Vertex | Access::Index => return None,
        })
    }
}
