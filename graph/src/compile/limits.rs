//! The adapter's limits, checked at compile time: a size the device would refuse (or
//! that would make wgpu panic) is a typed error naming the resource or pass and the limit.

use crate::access::Access;
use crate::compile::PassSetup;
use crate::error::{GraphError, Result};
use crate::node::PassNode;
use crate::resource::{ResourceDesc, ResourceInfo};

pub(crate) fn check(
    resources: &[ResourceInfo],
    passes: &[PassNode],
    setups: &[PassSetup],
    order: &[usize],
    limits: &wgpu::Limits,
) -> Result<()> {
    let over = |what: String, limit: &'static str, value: u64, max: u64, unit, hint: &str| {
        Err(GraphError::LimitExceeded {
            what,
            limit,
            value,
            max,
            unit,
            hint: hint.to_string(),
        })
    };
    for res in resources {
        match &res.desc {
            ResourceDesc::Buffer(b) => {
                if b.overflowed() {
                    return Err(GraphError::SizeOverflow {
                        resource: res.name.clone(),
                    });
                }
                if b.size > limits.max_buffer_size {
                    return over(
                        format!("buffer `{}`", res.name),
                        "max_buffer_size",
                        b.size,
                        limits.max_buffer_size,
                        "bytes",
                        "use a smaller count, split the data, or run on an adapter with larger buffers",
                    );
                }
            }
            ResourceDesc::Texture(t) => {
                let dim = t.width.max(t.height) as u64;
                if dim > limits.max_texture_dimension_2d as u64 {
                    return over(
                        format!("texture `{}`", res.name),
                        "max_texture_dimension_2d",
                        dim,
                        limits.max_texture_dimension_2d as u64,
                        "texels wide",
                        "render at a smaller size",
                    );
                }
                if t.layers as u64 > limits.max_texture_array_layers as u64 {
                    return over(
                        format!("texture `{}`", res.name),
                        "max_texture_array_layers",
                        t.layers as u64,
                        limits.max_texture_array_layers as u64,
                        "layers",
                        "use fewer layers",
                    );
                }
                let full = 32 - t.width.max(t.height).max(1).leading_zeros();
                if t.mip_levels == 0 || t.mip_levels > full {
                    return Err(GraphError::BadDeclaration {
                        resource: res.name.clone(),
                        problem: format!(
                            "{} mip levels; a {}×{} texture has 1 to {full}, declare a count in that range",
                            t.mip_levels, t.width, t.height
                        ),
                    });
                }
            }
        }
    }
    for &p in order {
        let node = &passes[p];
        for (slot, h) in node.bound_slots() {
            let res = &resources[h.id.index()];
            let ResourceDesc::Buffer(b) = &res.desc else {
                continue;
            };
            let (limit, max) = match slot.access {
                Access::Uniform => (
                    "max_uniform_buffer_binding_size",
                    limits.max_uniform_buffer_binding_size,
                ),
                Access::StorageRead
                | Access::StorageWrite
                | Access::StorageReadWrite
                | Access::ClearedReadWrite => (
                    "max_storage_buffer_binding_size",
                    limits.max_storage_buffer_binding_size,
                ),
                _ => continue,
            };
            if b.size > max {
                return over(
                    format!(
                        "buffer `{}` bound to slot `{}` of pass `{}`",
                        res.name, slot.name, node.name
                    ),
                    limit,
                    b.size,
                    max,
                    "bytes",
                    "bind a smaller buffer or split the data over several bindings",
                );
            }
        }
        for (label, groups) in &setups[p].dispatches {
            let max = limits.max_compute_workgroups_per_dimension;
            if let Some(&g) = groups.iter().find(|&&g| g > max) {
                return over(
                    format!("dispatch `{label}` of pass `{}`", node.name),
                    "max_compute_workgroups_per_dimension",
                    g as u64,
                    max as u64,
                    "workgroups",
                    "spread the grid over two dimensions, or lower the pass's size parameter",
                );
            }
        }
    }
    Ok(())
}
