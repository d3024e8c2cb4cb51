//! Each slot against the resource bound to it: kind, element or format, texture range,
//! size, usage, and which slots of one pass may share a resource.

use crate::contract::{Slot, SlotKind};
use crate::error::{GraphError, Result};
use crate::names::format_name;
use crate::node::PassNode;
use crate::resource::*;

pub(crate) fn check_slots(resources: &[ResourceInfo], node: &PassNode) -> Result<()> {
    // Per resource, the slots of this pass already seen on it: (slot, writes, range).
    let mut seen: Vec<(ResourceId, &Slot, Option<TextureRange>)> = Vec::new();
    for ((slot, h), range) in node.bound_slots().zip(&node.ranges) {
        let res = &resources[h.id.index()];
        let mismatch = |expected: String, found: String| GraphError::DescriptorMismatch {
            pass: node.name.clone(),
            slot: slot.name.to_string(),
            resource: res.name.clone(),
            expected,
            found,
        };
        check_kind(slot, &res.desc).map_err(|(e, f)| mismatch(e, f))?;
        let range = match (&res.desc, range) {
            (ResourceDesc::Texture(t), Some(r)) => {
                let r = r.resolve(t);
                if !r.fits(t) {
                    return Err(mismatch(
                        format!(
                            "mips {}..{} and layers {}..{}",
                            r.base_mip,
                            r.base_mip as u64 + r.mip_count as u64,
                            r.base_layer,
                            r.base_layer as u64 + r.layer_count as u64
                        ),
                        format!("a texture of {} mips and {} layers", t.mip_levels, t.layers),
                    ));
                }
                Some(r)
            }
            (ResourceDesc::Buffer(_), Some(_)) => {
                return Err(mismatch(
                    "a texture (the binding names mips or layers)".into(),
                    "a buffer".into(),
                ));
            }
            (ResourceDesc::Texture(t), None) => Some(t.full_range()),
            (ResourceDesc::Buffer(_), None) => None,
        };
        for access in slot.accesses() {
            check_usage(res, node, slot, access)?;
        }
        if slot.writes()
            && let ResourceKind::HistoryPrev { .. } = res.kind
        {
            return Err(GraphError::ReadOnlyResource {
                pass: node.name.clone(),
                slot: slot.name.to_string(),
                resource: res.name.clone(),
                why: "last frame's history is read-only; write the current half instead",
            });
        }
        // One resource in two slots of one pass, one of them writing, would alias inside
        // a dispatch, unless the slots bind disjoint parts of a texture.
        for (id, other, other_range) in &seen {
            if *id != h.id || !(other.writes() || slot.writes()) {
                continue;
            }
            let disjoint = match (range, other_range) {
                (Some(a), Some(b)) => !a.overlaps(b),
                _ => false,
            };
            if !disjoint {
                return Err(GraphError::UsageNotAllowed {
                    pass: node.name.clone(),
                    slot: slot.name.to_string(),
                    resource: res.name.clone(),
                    access: slot.access_name(),
                    needed: "its own slot".into(),
                    reason: format!(
                        "another slot of this pass (`{}`) binds an overlapping part of it, and one of them writes; bind disjoint mips or layers, or another resource",
                        other.name
                    ),
                });
            }
        }
        seen.push((h.id, slot, range));
    }
    Ok(())
}

/// The slot's expected kind against the descriptor, as (expected, found) on mismatch.
fn check_kind(slot: &Slot, desc: &ResourceDesc) -> std::result::Result<(), (String, String)> {
    match (&slot.kind, desc) {
        (SlotKind::Buffer { element }, ResourceDesc::Buffer(b)) => {
            if let Some(e) = element
                && e != &b.element
            {
                return Err((
                    format!("a buffer of {} ({} bytes each)", e.name, e.size),
                    format!(
                        "a buffer of {} ({} bytes each)",
                        b.element.name, b.element.size
                    ),
                ));
            }
        }
        (SlotKind::Texture { format }, ResourceDesc::Texture(t)) => {
            if let Some(f) = format
                && *f != t.format
            {
                return Err((
                    format!("a {} texture", format_name(*f)),
                    format!("a {} texture", format_name(t.format)),
                ));
            }
        }
        (SlotKind::Visibility64, ResourceDesc::Buffer(b)) => {
            if b.element != Element::U64 {
                return Err((
                    "a 64-bit visibility target (a buffer of u64 or an r64uint texture)".into(),
                    format!("a buffer of {}", b.element.name),
                ));
            }
        }
        (SlotKind::Visibility64, ResourceDesc::Texture(t)) => {
            if t.format != wgpu::TextureFormat::R64Uint {
                return Err((
                    "a 64-bit visibility target (a buffer of u64 or an r64uint texture)".into(),
                    format!("a {} texture", format_name(t.format)),
                ));
            }
        }
        (SlotKind::Buffer { .. }, d) | (SlotKind::Texture { .. }, d) => {
            let expected = if matches!(slot.kind, SlotKind::Buffer { .. }) {
                "a buffer"
            } else {
                "a texture"
            };
            return Err((expected.to_string(), format!("a {}", d.kind_name())));
        }
    }
    Ok(())
}

fn check_usage(
    res: &ResourceInfo,
    node: &PassNode,
    slot: &Slot,
    access: crate::access::Access,
) -> Result<()> {
    let usage_err = |needed: String, reason: String| GraphError::UsageNotAllowed {
        pass: node.name.clone(),
        slot: slot.name.to_string(),
        resource: res.name.clone(),
        access: access.name().to_string(),
        needed,
        reason,
    };
    let imported_without = |need: &dyn std::fmt::Debug, have: &dyn std::fmt::Debug| {
        usage_err(
            format!("{need:?}"),
            format!("it was imported with only {have:?}; create it with {need:?} too"),
        )
    };
    match &res.desc {
        ResourceDesc::Buffer(_) => {
            let Some(need) = access.buffer_usage() else {
                return Err(usage_err(
                    "a texture".into(),
                    "a buffer cannot be used this way".into(),
                ));
            };
            if let ResourceKind::Imported {
                usage: ImportedUsage::Buffer(have),
            } = res.kind
                && !have.contains(need)
            {
                return Err(imported_without(&need, &have));
            }
        }
        ResourceDesc::Texture(t) => {
            let Some(need) = crate::access::texture_usage_for(access, t.format) else {
                return Err(usage_err(
                    "a buffer".into(),
                    "a texture cannot be used this way".into(),
                ));
            };
            if need.contains(wgpu::TextureUsages::STORAGE_BINDING)
                && t.format.is_depth_stencil_format()
            {
                return Err(usage_err(
                    format!("{need:?}"),
                    format!(
                        "depth format {} cannot be a storage texture",
                        format_name(t.format)
                    ),
                ));
            }
            if let ResourceKind::Imported {
                usage: ImportedUsage::Texture(have),
            } = res.kind
                && !have.contains(need)
            {
                return Err(imported_without(&need, &have));
            }
        }
    }
    Ok(())
}

/// The sizes a pass asked for in setup, against the bound resources' current sizes.
pub(crate) fn check_min_bytes(
    resources: &[ResourceInfo],
    node: &PassNode,
    min_bytes: &[(String, u64)],
) -> Result<()> {
    for (slot, h) in node.bound_slots() {
        let res = &resources[h.id.index()];
        for (_, min) in min_bytes.iter().filter(|(s, _)| s == slot.name) {
            if res.desc.bytes() < *min {
                return Err(GraphError::DescriptorMismatch {
                    pass: node.name.clone(),
                    slot: slot.name.to_string(),
                    resource: res.name.clone(),
                    expected: format!("at least {min} bytes (slot {})", slot.name),
                    found: format!("{} bytes", res.desc.bytes()),
                });
            }
        }
    }
    Ok(())
}
