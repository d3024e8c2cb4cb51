//! Walks the passes in declaration order, checks every handle's version and derives the
//! dependency edges: writer → reader, reader → next writer, writer → next writer.

use crate::error::{GraphError, Result};
use crate::node::PassNode;
pub(crate) use crate::plan::{Edge, EdgeKind};
use crate::resource::{ResourceDesc, ResourceInfo, TextureRange};
use std::collections::HashMap;

/// Who wrote and who read each version of each resource.
#[derive(Default)]
pub struct VersionTable {
    pub writer: HashMap<(usize, u32), usize>,
    pub readers: HashMap<(usize, u32), Vec<usize>>,
    pub edges: Vec<Edge>,
}

pub fn derive_edges(resources: &[ResourceInfo], passes: &[PassNode]) -> Result<VersionTable> {
    let g = Graph { resources, passes };
    let mut t = VersionTable::default();
    let mut current = vec![0u32; resources.len()];
    // Reads of versions not yet written in declaration order (possible only with explicit
    // versions, as in pipeline files); resolved once every writer is known.
    let mut forward: Vec<(SlotUse, u32)> = Vec::new();

    for (p, node) in passes.iter().enumerate() {
        let slots: Vec<_> = node
            .bound_slots()
            .zip(&node.ranges)
            .map(|((s, h), range)| (s, h, range))
            .collect();
        // Reads first, against the versions before this pass: a pass that reads mip N − 1
        // and writes mip N of one texture reads what came before it, whatever the slot order.
        for (slot, h, _) in slots.iter().filter(|(s, _, _)| !s.writes()) {
            let r = h.id.index();
            let at = SlotUse::new(p, slot.name, r);
            let cur = current[r];
            if h.version < cur {
                return Err(g.stale(&t, at, h.version, cur));
            } else if h.version > cur {
                forward.push((at, h.version));
            } else {
                g.read_edge(&mut t, at, cur)?;
                t.readers.entry((r, cur)).or_default().push(p);
            }
        }
        // Then writes: one new version per resource, however many slots write parts of it.
        let mut written: Vec<usize> = Vec::new();
        for (slot, h, range) in slots.iter().filter(|(s, _, _)| s.writes()) {
            let r = h.id.index();
            let at = SlotUse::new(p, slot.name, r);
            let cur = if written.contains(&r) {
                current[r] - 1
            } else {
                current[r]
            };
            if h.version != cur {
                return Err(g.stale(&t, at, h.version, current[r]));
            }
            if slot.reads() {
                g.read_edge(&mut t, at, cur)?;
            } else if partial(&resources[r], **range)
                && let Some(&w) = t.writer.get(&(r, cur))
            {
                // Writing some mips or layers keeps the rest: the new version carries what
                // the earlier writer left there, so that writer is needed as much as this one.
                push(&mut t.edges, w, p, r, cur, EdgeKind::ReadAfterWrite);
            }
            if written.contains(&r) {
                continue;
            }
            if let Some(&w) = t.writer.get(&(r, cur)) {
                push(&mut t.edges, w, p, r, cur, EdgeKind::WriteAfterWrite);
            }
            for &reader in t.readers.get(&(r, cur)).into_iter().flatten() {
                push(&mut t.edges, reader, p, r, cur, EdgeKind::WriteAfterRead);
            }
            t.writer.insert((r, cur + 1), p);
            current[r] = cur + 1;
            written.push(r);
        }
    }
    for (at, v) in forward {
        let (p, r) = (at.pass, at.resource);
        let Some(&w) = t.writer.get(&(r, v)) else {
            return Err(g.no_writer(at, v));
        };
        push(&mut t.edges, w, p, r, v, EdgeKind::ReadAfterWrite);
        if let Some(&next) = t.writer.get(&(r, v + 1)) {
            push(&mut t.edges, p, next, r, v, EdgeKind::WriteAfterRead);
        }
        t.readers.entry((r, v)).or_default().push(p);
    }
    t.edges.sort();
    t.edges.dedup();
    Ok(t)
}

/// True when `range` covers only part of the texture `res`.
fn partial(res: &ResourceInfo, range: Option<TextureRange>) -> bool {
    match (&res.desc, range) {
        (ResourceDesc::Texture(t), Some(r)) => r.resolve(t) != t.full_range(),
        _ => false,
    }
}

/// Pass `pass` binding resource `resource` through `slot`: where a version error points.
#[derive(Clone, Copy)]
struct SlotUse<'s> {
    pass: usize,
    slot: &'s str,
    resource: usize,
}

impl<'s> SlotUse<'s> {
    fn new(pass: usize, slot: &'s str, resource: usize) -> Self {
        Self {
            pass,
            slot,
            resource,
        }
    }
}

/// The resources and passes being walked, whose names version errors give.
#[derive(Clone, Copy)]
struct Graph<'g> {
    resources: &'g [ResourceInfo],
    passes: &'g [PassNode],
}

impl Graph<'_> {
    /// `at` binds version `given` where `current` is the newest; names who wrote that.
    fn stale(self, t: &VersionTable, at: SlotUse, given: u32, current: u32) -> GraphError {
        GraphError::StaleVersion {
            pass: self.passes[at.pass].name.clone(),
            slot: at.slot.to_string(),
            resource: self.resources[at.resource].name.clone(),
            given,
            current,
            writer: t
                .writer
                .get(&(at.resource, current))
                .map(|&w| self.passes[w].name.clone())
                .unwrap_or_default(),
        }
    }

    /// The read-after-write edge from the writer of version `v` to the pass reading it at
    /// `at`; none for the first version of what starts written (imports, history).
    fn read_edge(self, t: &mut VersionTable, at: SlotUse, v: u32) -> Result<()> {
        let r = at.resource;
        match t.writer.get(&(r, v)) {
            Some(&w) => push(&mut t.edges, w, at.pass, r, v, EdgeKind::ReadAfterWrite),
            None if v == 0 && self.resources[r].starts_written() => {}
            None => return Err(self.no_writer(at, v)),
        }
        Ok(())
    }

    fn no_writer(self, at: SlotUse, version: u32) -> GraphError {
        GraphError::ReadWithoutWriter {
            pass: self.passes[at.pass].name.clone(),
            slot: at.slot.to_string(),
            resource: self.resources[at.resource].name.clone(),
            version,
        }
    }
}

fn push(
    edges: &mut Vec<Edge>,
    from: usize,
    to: usize,
    resource: usize,
    version: u32,
    kind: EdgeKind,
) {
    if from != to {
        edges.push(Edge {
            from,
            to,
            resource,
            version,
            kind,
        });
    }
}
