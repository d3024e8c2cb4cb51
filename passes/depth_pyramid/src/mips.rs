//! The one place the pass builds a bind group itself: group 1, a write-only view of
//! each pyramid level.
//!
//! The graph binds one view per slot, and a storage-texture binding takes one mip, so
//! the graph cannot bind the `pyramid` slot's levels separately. The program's layout
//! still comes from the declared slots (group 1 is `pyramid` at every binding, which the
//! graph types as a write-only `r32float` storage texture); only the views are made here,
//! from the texture the graph bound to the slot. Bindings past the pyramid's last level
//! get a view of the last level, which the shader never writes through them.
//!
//! Bind groups are cached per (pipeline, texture, first level), so a steady frame
//! creates none; a history pyramid alternates between two textures, which both stay
//! cached. The cache is bounded, since a resize brings new textures.

use meshlight_graph::prelude::*;
use std::sync::Mutex;

/// Cached bind groups, at most this many (the oldest goes first).
const CACHED: usize = 8;

struct Entry {
    pipeline: wgpu::ComputePipeline,
    texture: wgpu::Texture,
    first_level: u32,
    bind_group: wgpu::BindGroup,
}

/// Group 1 of the pass's programs: per-level views of the `pyramid` slot's texture.
#[derive(Default)]
pub struct MipViews {
    cache: Mutex<Vec<Entry>>,
}

impl Clone for MipViews {
    /// A clone starts with an empty cache: bind groups belong to one device.
    fn clone(&self) -> Self {
        Self::default()
    }
}

impl std::fmt::Debug for MipViews {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let cached = self.cache.lock().map(|c| c.len()).unwrap_or(0);
        f.debug_struct("MipViews").field("cached", &cached).finish()
    }
}

impl MipViews {
    /// The bind group of `bindings` views of the `pyramid` slot's texture, levels
    /// `first_level`, `first_level + 1`, …, for group 1 of `program`.
    pub fn bind_group(
        &self,
        ctx: &mut RecordContext<'_>,
        program: &ComputeProgram,
        first_level: u32,
        bindings: u32,
    ) -> Result<wgpu::BindGroup> {
        let (texture, _) = ctx.texture(crate::PYRAMID)?;
        let mut cache = self.cache.lock().unwrap_or_else(|e| e.into_inner());
        if let Some(e) = cache.iter().find(|e| {
            e.pipeline == program.pipeline && e.texture == texture && e.first_level == first_level
        }) {
            return Ok(e.bind_group.clone());
        }
        let last = texture.mip_level_count() - 1;
        let views: Vec<wgpu::TextureView> = (0..bindings)
            .map(|b| {
                let level = (first_level + b).min(last);
                texture.create_view(&wgpu::TextureViewDescriptor {
                    label: Some("depth_pyramid level"),
                    base_mip_level: level,
                    mip_level_count: Some(1),
                    ..Default::default()
                })
            })
            .collect();
        let entries: Vec<wgpu::BindGroupEntry> = views
            .iter()
            .zip(0..)
            .map(|(view, binding)| wgpu::BindGroupEntry {
                binding,
                resource: wgpu::BindingResource::TextureView(view),
            })
            .collect();
        let bind_group = ctx.device().create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("depth_pyramid_levels"),
            layout: &program.pipeline.get_bind_group_layout(1),
            entries: &entries,
        });
        if cache.len() == CACHED {
            cache.remove(0);
        }
        cache.push(Entry {
            pipeline: program.pipeline.clone(),
            texture,
            first_level,
            bind_group: bind_group.clone(),
        });
        Ok(bind_group)
    }
}
