//! Physical GPU resources behind pool slots, kept across frames so a steady graph
//! allocates nothing after its first frame, and freed once no frame has used them for a
//! few frames (after a size parameter grew, say).

use crate::resource::{ResourceDesc, TextureDesc, TextureRange};

/// Frames an unused pooled object is kept before it is freed: long enough for a caller
/// that alternates between two graphs to keep both warm.
pub const EVICT_AFTER_FRAMES: u64 = 3;

/// A GPU resource as a pass sees it.
#[derive(Clone, Debug)]
pub enum Physical {
    Buffer {
        buffer: wgpu::Buffer,
        size: u64,
    },
    Texture {
        texture: wgpu::Texture,
        view: wgpu::TextureView,
    },
}

struct Entry {
    physical: Physical,
    buffer_usage: wgpu::BufferUsages,
    texture_usage: wgpu::TextureUsages,
    bytes: u64,
    taken: bool,
    last_used: u64,
}

#[derive(Default)]
pub struct PhysicalPool {
    entries: Vec<Entry>,
    /// Allocations made by the current frame.
    pub allocations: u32,
    frame: u64,
}

impl PhysicalPool {
    /// Starts frame `frame`: frees what no frame used for [`EVICT_AFTER_FRAMES`] frames.
    pub fn begin_frame(&mut self, frame: u64) {
        self.allocations = 0;
        self.frame = frame;
        self.entries
            .retain(|e| frame.saturating_sub(e.last_used) <= EVICT_AFTER_FRAMES);
        for e in &mut self.entries {
            e.taken = false;
        }
    }

    /// Bytes of every object the pool holds, in use or kept for reuse.
    pub fn held_bytes(&self) -> u64 {
        self.entries.iter().map(|e| e.bytes).sum()
    }

    /// A resource for `desc` with at least these usages: the smallest free match, else new.
    pub fn acquire(
        &mut self,
        device: &wgpu::Device,
        label: &str,
        desc: &ResourceDesc,
        buffer_usage: wgpu::BufferUsages,
        texture_usage: wgpu::TextureUsages,
    ) -> Physical {
        let found = self
            .entries
            .iter()
            .enumerate()
            .filter(|(_, e)| !e.taken && fits(e, desc, buffer_usage, texture_usage))
            .min_by_key(|(i, e)| (e.bytes, *i))
            .map(|(i, _)| i);
        let i = match found {
            Some(i) => i,
            None => {
                self.allocations += 1;
                self.entries.push(Entry {
                    physical: create(device, label, desc, buffer_usage, texture_usage),
                    buffer_usage,
                    texture_usage,
                    bytes: desc.bytes(),
                    taken: false,
                    last_used: self.frame,
                });
                self.entries.len() - 1
            }
        };
        self.entries[i].taken = true;
        self.entries[i].last_used = self.frame;
        self.entries[i].physical.clone()
    }
}

fn fits(e: &Entry, desc: &ResourceDesc, bu: wgpu::BufferUsages, tu: wgpu::TextureUsages) -> bool {
    match (&e.physical, desc) {
        (Physical::Buffer { size, .. }, ResourceDesc::Buffer(b)) => {
            *size >= b.size && *size <= b.size.max(256) * 2 && e.buffer_usage.contains(bu)
        }
        (Physical::Texture { texture, .. }, ResourceDesc::Texture(t)) => {
            texture.format() == t.format
                && texture.width() == t.width
                && texture.height() == t.height
                && texture.mip_level_count() == t.mip_levels
                && texture.depth_or_array_layers() == t.layers
                && e.texture_usage.contains(tu)
        }
        _ => false,
    }
}

pub fn create(
    device: &wgpu::Device,
    label: &str,
    desc: &ResourceDesc,
    bu: wgpu::BufferUsages,
    tu: wgpu::TextureUsages,
) -> Physical {
    match desc {
        ResourceDesc::Buffer(b) => {
            // Zero-sized bindings are invalid; keep at least one element.
            let size = b.size.max(16).next_multiple_of(4);
            let buffer = device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size,
                usage: bu,
                mapped_at_creation: false,
            });
            Physical::Buffer {
                buffer,
                size: b.size,
            }
        }
        ResourceDesc::Texture(t) => create_texture(device, label, t, tu),
    }
}

pub fn create_texture(
    device: &wgpu::Device,
    label: &str,
    t: &TextureDesc,
    usage: wgpu::TextureUsages,
) -> Physical {
    let texture = device.create_texture(&wgpu::TextureDescriptor {
        label: Some(label),
        size: wgpu::Extent3d {
            width: t.width,
            height: t.height,
            depth_or_array_layers: t.layers,
        },
        mip_level_count: t.mip_levels,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format: t.format,
        usage,
        view_formats: &[],
    });
    let view = whole_view(&texture);
    Physical::Texture { texture, view }
}

/// True when a texture is bound as a 2-D array: it has more than one layer.
pub fn is_array(texture: &wgpu::Texture) -> bool {
    texture.depth_or_array_layers() > 1
}

/// The view of every mip and layer.
pub fn whole_view(texture: &wgpu::Texture) -> wgpu::TextureView {
    texture.create_view(&wgpu::TextureViewDescriptor {
        dimension: Some(if is_array(texture) {
            wgpu::TextureViewDimension::D2Array
        } else {
            wgpu::TextureViewDimension::D2
        }),
        ..Default::default()
    })
}

/// A view of `range`; 2-D arrays stay arrays even when the range holds one layer, so a
/// slot's binding type does not depend on which layer it binds.
pub fn range_view(texture: &wgpu::Texture, range: TextureRange) -> wgpu::TextureView {
    texture.create_view(&wgpu::TextureViewDescriptor {
        label: Some("meshlight range view"),
        dimension: Some(if is_array(texture) {
            wgpu::TextureViewDimension::D2Array
        } else {
            wgpu::TextureViewDimension::D2
        }),
        base_mip_level: range.base_mip,
        mip_level_count: Some(range.mip_count),
        base_array_layer: range.base_layer,
        array_layer_count: Some(range.layer_count),
        ..Default::default()
    })
}
