//! A frame's resources: the pooled transients of the plan's slots, the caller's imports
//! (checked against their declarations), and history pairs swapped each frame.

use super::Executor;
use crate::compile::CompiledGraph;
use crate::error::{GraphError, Result};
use crate::record::physical::{self, Physical};
use crate::resource::{ImportedUsage, ResourceDesc, ResourceKind};
use std::collections::HashMap;

#[derive(Clone)]
pub(super) enum Import {
    Buffer(wgpu::Buffer),
    Texture(wgpu::Texture),
}

/// Caller-owned resources for one frame, by resource name.
#[derive(Default, Clone)]
pub struct Imports {
    entries: HashMap<String, Import>,
}

impl Imports {
    /// No imports yet.
    pub fn new() -> Self {
        Self::default()
    }
    /// Supplies a caller-owned buffer for the imported resource `name`.
    pub fn buffer(mut self, name: &str, buffer: &wgpu::Buffer) -> Self {
        self.entries
            .insert(name.to_string(), Import::Buffer(buffer.clone()));
        self
    }
    /// Supplies a caller-owned texture for the imported resource `name`. Its views are
    /// made once per texture and kept by the executor, so bind groups over an imported
    /// texture are found in the cache frame after frame.
    pub fn texture(mut self, name: &str, texture: &wgpu::Texture) -> Self {
        self.entries
            .insert(name.to_string(), Import::Texture(texture.clone()));
        self
    }
    /// These imports and `other`'s; a name in both takes `other`'s.
    pub fn merge(mut self, other: Imports) -> Self {
        self.entries.extend(other.entries);
        self
    }
}

/// A history pair and what it was made for.
pub(super) struct HistoryEntry {
    pub pair: [Physical; 2],
    desc: ResourceDesc,
    buffer_usage: wgpu::BufferUsages,
    texture_usage: wgpu::TextureUsages,
    /// The frame that created it: `prev` holds real contents only on later frames.
    created: u64,
}

/// The physical object behind every resource of one frame, and per resource whether a
/// history half holds last frame's contents.
pub(super) struct FrameResources {
    pub physical: Vec<Option<Physical>>,
    pub history_valid: Vec<bool>,
}

impl Executor {
    /// The physical object behind every resource this frame, and per resource whether a
    /// history half holds last frame's contents. Allocations run inside error scopes, so a
    /// failure is an error naming the resource, not a panic.
    pub(super) fn resolve_resources(
        &mut self,
        graph: &CompiledGraph,
        imports: &Imports,
    ) -> Result<FrameResources> {
        let plan = &graph.plan;
        let frame = self.frame;
        let mut physical: Vec<Option<Physical>> = vec![None; plan.resources.len()];
        let mut history_valid = vec![false; plan.resources.len()];
        let oom = self
            .gpu
            .device
            .push_error_scope(wgpu::ErrorFilter::OutOfMemory);
        let invalid = self
            .gpu
            .device
            .push_error_scope(wgpu::ErrorFilter::Validation);
        let mut labels = Vec::new();
        for slot in &plan.pool_slots {
            let members = &slot.members;
            let bu = members.iter().fold(wgpu::BufferUsages::empty(), |u, &m| {
                u | plan.resources[m].buffer_usage
            });
            let tu = members.iter().fold(wgpu::TextureUsages::empty(), |u, &m| {
                u | plan.resources[m].texture_usage
            });
            let label = members
                .iter()
                .map(|&m| plan.resources[m].info.name.as_str())
                .collect::<Vec<_>>()
                .join("+");
            let ph = self
                .pool
                .acquire(&self.gpu.device, &label, &slot.desc, bu, tu);
            labels.push(label);
            for &m in members {
                physical[m] = Some(match (&ph, &plan.resources[m].info.desc) {
                    (Physical::Buffer { buffer, .. }, ResourceDesc::Buffer(b)) => {
                        Physical::Buffer {
                            buffer: buffer.clone(),
                            size: b.size,
                        }
                    }
                    _ => ph.clone(),
                });
            }
        }
        let parity = (frame % 2) as usize;
        for (r, res) in plan.resources.iter().enumerate() {
            match &res.info.kind {
                ResourceKind::Imported { usage } => {
                    let Some(import) = imports.entries.get(&res.info.name) else {
                        if res.lifetime.is_none() {
                            continue;
                        }
                        return Err(GraphError::MissingImport {
                            resource: res.info.name.clone(),
                        });
                    };
                    let ph = match import {
                        Import::Buffer(b) => Physical::Buffer {
                            buffer: b.clone(),
                            size: b.size(),
                        },
                        Import::Texture(t) => Physical::Texture {
                            texture: t.clone(),
                            view: self.views.whole(t, frame),
                        },
                    };
                    check_import(&res.info.name, &res.info.desc, *usage, &ph)?;
                    physical[r] = Some(ph);
                }
                ResourceKind::History { prev } => {
                    let device = &self.gpu.device;
                    let name = &res.info.name;
                    let stale = self.histories.get(name).is_none_or(|h| {
                        h.desc != res.info.desc
                            || !h.buffer_usage.contains(res.buffer_usage)
                            || !h.texture_usage.contains(res.texture_usage)
                    });
                    if stale {
                        // New (or resized): both halves start zeroed, and `prev` holds
                        // nothing from an earlier frame.
                        let make = |half: &str| {
                            physical::create(
                                device,
                                &format!("{name} (history {half})"),
                                &res.info.desc,
                                res.buffer_usage,
                                res.texture_usage,
                            )
                        };
                        self.histories.insert(
                            name.clone(),
                            HistoryEntry {
                                pair: [make("a"), make("b")],
                                desc: res.info.desc.clone(),
                                buffer_usage: res.buffer_usage,
                                texture_usage: res.texture_usage,
                                created: frame,
                            },
                        );
                        labels.push(name.clone());
                    }
                    let h = &self.histories[name];
                    physical[r] = Some(h.pair[parity].clone());
                    physical[prev.index()] = Some(h.pair[1 - parity].clone());
                    let valid = h.created < frame;
                    history_valid[r] = valid;
                    history_valid[prev.index()] = valid;
                }
                _ => {}
            }
        }
        let failed = pollster::block_on(invalid.pop()).or(pollster::block_on(oom.pop()));
        if let Some(e) = failed {
            return Err(GraphError::Allocation {
                resource: labels.join(", "),
                message: e.to_string(),
            });
        }
        Ok(FrameResources {
            physical,
            history_valid,
        })
    }
}

fn check_import(
    name: &str,
    desc: &ResourceDesc,
    declared: ImportedUsage,
    ph: &Physical,
) -> Result<()> {
    let mismatch = |message: String| {
        Err(GraphError::ImportMismatch {
            resource: name.to_string(),
            message,
        })
    };
    match (desc, ph, declared) {
        (ResourceDesc::Buffer(b), Physical::Buffer { buffer, .. }, ImportedUsage::Buffer(u)) => {
            if buffer.size() < b.size {
                return mismatch(format!(
                    "declared {} bytes, the buffer has {}",
                    b.size,
                    buffer.size()
                ));
            }
            usage_covers(u, buffer.usage(), "buffer").or_else(mismatch)
        }
        (
            ResourceDesc::Texture(t),
            Physical::Texture { texture, .. },
            ImportedUsage::Texture(u),
        ) => {
            if texture.format() != t.format
                || texture.width() != t.width
                || texture.height() != t.height
                || texture.mip_level_count() != t.mip_levels
                || texture.depth_or_array_layers() != t.layers
            {
                let shape =
                    |format: wgpu::TextureFormat, w: u32, h: u32, mips: u32, layers: u32| {
                        format!("{format:?} {w}x{h} with {mips} mips and {layers} layers")
                    };
                return mismatch(format!(
                    "declared {}, the texture is {}",
                    shape(t.format, t.width, t.height, t.mip_levels, t.layers),
                    shape(
                        texture.format(),
                        texture.width(),
                        texture.height(),
                        texture.mip_level_count(),
                        texture.depth_or_array_layers()
                    )
                ));
            }
            usage_covers(u, texture.usage(), "texture").or_else(mismatch)
        }
        _ => mismatch("a buffer was declared and a texture given, or the reverse".into()),
    }
}

/// An error naming both usages when an imported object lacks part of its declared usage.
fn usage_covers<U: bitflags::Flags + Copy + std::fmt::Debug>(
    declared: U,
    has: U,
    what: &str,
) -> std::result::Result<(), String> {
    if has.contains(declared) {
        Ok(())
    } else {
        Err(format!(
            "declared usage {declared:?}, the {what} has {has:?}"
        ))
    }
}
