//! Lifetimes of transient resources and their assignment to pool slots.
//!
//! wgpu has no memory aliasing, so sharing is by reuse: two transients whose lifetimes do
//! not overlap may live in the same physical buffer (sized for the larger) or the same
//! texture (identical descriptor). Resources whose lifetimes overlap never share a slot.

pub(crate) use crate::plan::{Lifetime, PoolSlot};
use crate::resource::{ResourceDesc, ResourceInfo, ResourceKind};

/// True for resources the graph allocates (as opposed to the caller or the history store).
pub fn is_pooled(kind: &ResourceKind) -> bool {
    matches!(
        kind,
        ResourceKind::Transient | ResourceKind::Scratch { .. } | ResourceKind::Exported
    )
}

pub struct PoolAssignment {
    pub slots: Vec<PoolSlot>,
    /// Per resource, its slot (pooled and used resources only).
    pub slot_of: Vec<Option<usize>>,
    pub bytes_without_reuse: u64,
    pub bytes_with_reuse: u64,
}

pub fn assign_slots(resources: &[ResourceInfo], lifetimes: &[Option<Lifetime>]) -> PoolAssignment {
    let mut pooled: Vec<usize> = (0..resources.len())
        .filter(|&r| is_pooled(&resources[r].kind) && lifetimes[r].is_some())
        .collect();
    pooled.sort_by_key(|&r| (lifetimes[r].map(|l| l.first), r));

    let mut slots: Vec<PoolSlot> = Vec::new();
    let mut slot_of = vec![None; resources.len()];
    for &r in &pooled {
        let life = lifetimes[r].expect("filtered to used resources");
        let desc = &resources[r].desc;
        let shareable = resources[r].kind != ResourceKind::Exported;
        let candidate = if shareable {
            best_slot(&slots, resources, desc, life.first)
        } else {
            None
        };
        let s = match candidate {
            Some(s) => s,
            None => {
                slots.push(PoolSlot {
                    index: slots.len(),
                    desc: desc.clone(),
                    bytes: 0,
                    members: Vec::new(),
                    last_use: 0,
                });
                slots.len() - 1
            }
        };
        let slot = &mut slots[s];
        if let (ResourceDesc::Buffer(have), ResourceDesc::Buffer(want)) = (&mut slot.desc, desc)
            && want.size > have.size
        {
            *have = want.clone();
        }
        slot.bytes = slot.desc.bytes();
        slot.members.push(r);
        slot.last_use = if shareable { life.last } else { usize::MAX };
        slot_of[r] = Some(s);
    }
    let bytes_without_reuse = pooled.iter().map(|&r| resources[r].desc.bytes()).sum();
    let bytes_with_reuse = slots.iter().map(|s| s.bytes).sum();
    PoolAssignment {
        slots,
        slot_of,
        bytes_without_reuse,
        bytes_with_reuse,
    }
}

/// A free, compatible slot: for buffers the smallest one that is large enough, else the
/// largest (which then grows); for textures one with the identical descriptor.
fn best_slot(
    slots: &[PoolSlot],
    resources: &[ResourceInfo],
    desc: &ResourceDesc,
    first: usize,
) -> Option<usize> {
    let free = slots.iter().filter(|s| {
        s.last_use < first
            && s.members
                .iter()
                .all(|&m| resources[m].kind != ResourceKind::Exported)
    });
    match desc {
        ResourceDesc::Buffer(want) => {
            let buffers: Vec<&PoolSlot> = free
                .filter(|s| matches!(s.desc, ResourceDesc::Buffer(_)))
                .collect();
            let fits = buffers
                .iter()
                .filter(|s| s.bytes >= want.size)
                .min_by_key(|s| (s.bytes, s.index));
            fits.or_else(|| {
                buffers
                    .iter()
                    .max_by_key(|s| (s.bytes, usize::MAX - s.index))
            })
            .map(|s| s.index)
        }
        ResourceDesc::Texture(_) => free.filter(|s| &s.desc == desc).map(|s| s.index).next(),
    }
}
