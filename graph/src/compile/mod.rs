//! Compile: a pure function from declared passes and resources to an execution plan. It
//! needs no device, so every rule here is tested headless.

pub mod cull;
pub mod order;
pub mod pool;
pub mod versions;

use crate::access::Access;
use crate::builder::{GraphBuilder, PassNode};
use crate::contract::SlotKind;
use crate::error::{GraphError, Result};
use crate::pass::SetupContext;
use crate::plan::*;
use crate::resource::*;
use pool::Lifetime;
use std::collections::HashMap;

#[derive(Clone, Debug)]
pub struct CompileOptions {
    /// Features of the adapter the graph will run on (`Features::all()` to plan without one).
    pub adapter_features: wgpu::Features,
}

impl CompileOptions {
    pub fn new(adapter_features: wgpu::Features) -> Self {
        Self { adapter_features }
    }
}

/// A plan plus the passes it runs.
pub struct CompiledGraph {
    pub plan: Plan,
    pub(crate) passes: Vec<PassNode>,
}

impl CompiledGraph {
    pub fn pass_nodes(&self) -> &[PassNode] {
        &self.passes
    }
}

pub fn compile(builder: GraphBuilder, options: &CompileOptions) -> Result<CompiledGraph> {
    let GraphBuilder {
        mut resources,
        passes,
        deferred,
        ..
    } = builder;
    if let Some(e) = deferred.into_iter().next() {
        return Err(e);
    }

    // Setup each pass against the adapter's features.
    let mut setups = Vec::with_capacity(passes.len());
    let mut enabled = wgpu::Features::empty();
    let mut scratch_of: Vec<Vec<usize>> = Vec::with_capacity(passes.len());
    for (p, node) in passes.iter().enumerate() {
        let mut ctx = SetupContext::new(options.adapter_features, node.contract.slot_names());
        node.pass.setup(&mut ctx).map_err(|e| match e {
            GraphError::Parameter { message, .. } => GraphError::Parameter {
                pass: node.name.clone(),
                message,
            },
            other => other,
        })?;
        let missing = ctx.required - options.adapter_features;
        if !missing.is_empty() {
            return Err(GraphError::MissingFeature {
                pass: node.name.clone(),
                stage: node.contract.stage.to_string(),
                features: missing
                    .iter_names()
                    .map(|(n, _)| n)
                    .collect::<Vec<_>>()
                    .join(", "),
            });
        }
        enabled |= ctx.required | (ctx.optional & options.adapter_features);
        let mut mine = Vec::new();
        for s in &ctx.scratch {
            let name = format!("{}/{}", node.name, s.name);
            if resources.iter().any(|r| r.name == name) {
                return Err(GraphError::DuplicateName {
                    what: "resource",
                    name,
                });
            }
            resources.push(ResourceInfo {
                name,
                desc: ResourceDesc::Buffer(s.desc.clone()),
                kind: ResourceKind::Scratch { pass: p },
            });
            mine.push(resources.len() - 1);
        }
        scratch_of.push(mine);
        setups.push(ctx);
    }

    for (node, setup) in passes.iter().zip(&setups) {
        check_slots(&resources, node, setup)?;
    }

    let table = versions::derive_edges(&resources, &passes)?;
    let names: Vec<String> = passes.iter().map(|p| p.name.clone()).collect();
    let dag = order::build_dag(passes.len(), &table.edges);
    let topo = order::topological_order(&dag, &names)?;
    let side_effects: Vec<bool> = setups.iter().map(|s| s.side_effect).collect();
    let live = cull::live_passes(&resources, &passes, &side_effects, &table.edges);
    let order: Vec<usize> = topo.into_iter().filter(|&p| live[p]).collect();
    let culled: Vec<usize> = (0..passes.len()).filter(|&p| !live[p]).collect();

    // Lifetimes over the executed order.
    let mut lifetimes: Vec<Option<Lifetime>> = vec![None; resources.len()];
    let mut touch = |r: usize, at: usize| {
        let l = lifetimes[r].get_or_insert(Lifetime {
            first: at,
            last: at,
        });
        l.first = l.first.min(at);
        l.last = l.last.max(at);
    };
    for (at, &p) in order.iter().enumerate() {
        for h in &passes[p].bindings {
            touch(h.id.index(), at);
        }
        for &s in &scratch_of[p] {
            touch(s, at);
        }
    }
    for (r, res) in resources.iter().enumerate() {
        if res.kind == ResourceKind::Exported
            && let Some(l) = &mut lifetimes[r]
        {
            l.last = order.len().saturating_sub(1).max(l.last);
        }
    }
    let pool = pool::assign_slots(&resources, &lifetimes);

    // Usages: every access any live pass makes, plus what the executor itself needs.
    let mut buffer_usage = vec![wgpu::BufferUsages::empty(); resources.len()];
    let mut texture_usage = vec![wgpu::TextureUsages::empty(); resources.len()];
    for &p in &order {
        for (slot, h) in passes[p].contract.slots.iter().zip(&passes[p].bindings) {
            let r = h.id.index();
            buffer_usage[r] |= slot
                .access
                .buffer_usage()
                .unwrap_or(wgpu::BufferUsages::empty());
            texture_usage[r] |= slot
                .access
                .texture_usage()
                .unwrap_or(wgpu::TextureUsages::empty());
        }
        for (decl, &r) in setups[p].scratch.iter().zip(&scratch_of[p]) {
            for a in &decl.accesses {
                buffer_usage[r] |= a.buffer_usage().unwrap_or(wgpu::BufferUsages::empty());
            }
        }
    }
    for (r, res) in resources.iter().enumerate() {
        match res.kind {
            // Exported results are read back by copying.
            ResourceKind::Exported => {
                buffer_usage[r] |= wgpu::BufferUsages::COPY_SRC;
                texture_usage[r] |= wgpu::TextureUsages::COPY_SRC;
            }
            ResourceKind::History { .. } | ResourceKind::HistoryPrev { .. } => {
                buffer_usage[r] |= wgpu::BufferUsages::COPY_SRC | wgpu::BufferUsages::COPY_DST;
                texture_usage[r] |= wgpu::TextureUsages::COPY_SRC | wgpu::TextureUsages::COPY_DST;
            }
            _ => {}
        }
    }
    // A history pair shares one physical format, so both halves need both usages.
    for r in 0..resources.len() {
        if let ResourceKind::History { prev } = resources[r].kind {
            let (b, t) = (
                buffer_usage[r] | buffer_usage[prev.index()],
                texture_usage[r] | texture_usage[prev.index()],
            );
            buffer_usage[r] = b;
            buffer_usage[prev.index()] = b;
            texture_usage[r] = t;
            texture_usage[prev.index()] = t;
        }
    }

    let mut versions = vec![0u32; resources.len()];
    for &(r, v) in table.writer.keys() {
        versions[r] = versions[r].max(v);
    }

    let pass_plans = passes
        .iter()
        .zip(&setups)
        .enumerate()
        .map(|(p, (node, setup))| {
            let slots = node
                .contract
                .slots
                .iter()
                .zip(&node.bindings)
                .map(|(slot, h)| {
                    let r = h.id.index();
                    let writes_version = slot.access.writes().then_some(h.version + 1);
                    let ops = matches!(slot.access, Access::RenderTarget | Access::DepthTarget)
                        .then(|| {
                            let has_earlier = table.writer.contains_key(&(r, h.version))
                                || (h.version == 0 && resources[r].starts_written());
                            let v = h.version + 1;
                            let read_later = table
                                .readers
                                .get(&(r, v))
                                .is_some_and(|rs| rs.iter().any(|&x| live[x]))
                                || table.writer.get(&(r, v + 1)).is_some_and(|&w| live[w]);
                            AttachmentOps {
                                load: if has_earlier {
                                    LoadOp::Load
                                } else {
                                    LoadOp::Clear
                                },
                                store: if read_later || resources[r].is_visible_outside() {
                                    StoreOp::Store
                                } else {
                                    StoreOp::Discard
                                },
                            }
                        });
                    SlotUse {
                        slot: slot.name,
                        resource: r,
                        access: slot.access,
                        version: h.version,
                        writes_version,
                        ops,
                    }
                })
                .collect();
            PassPlan {
                name: node.name.clone(),
                stage: node.contract.stage,
                implementation: node.pass.implementation(),
                slots,
                scratch: scratch_of[p].clone(),
                shader_defs: setup
                    .shader_defs
                    .iter()
                    .map(|(n, v)| (n.clone(), format!("{v:?}")))
                    .collect(),
                required_features: setup.required,
                optional_features: setup.optional,
                side_effect: setup.side_effect,
            }
        })
        .collect();

    let resource_plans = resources
        .into_iter()
        .enumerate()
        .map(|(r, info)| ResourcePlan {
            info,
            versions: versions[r],
            lifetime: lifetimes[r],
            pool_slot: pool.slot_of[r],
            buffer_usage: buffer_usage[r],
            texture_usage: texture_usage[r],
        })
        .collect();

    Ok(CompiledGraph {
        plan: Plan {
            passes: pass_plans,
            order,
            culled,
            resources: resource_plans,
            edges: table.edges,
            pool_slots: pool.slots,
            bytes_without_reuse: pool.bytes_without_reuse,
            bytes_with_reuse: pool.bytes_with_reuse,
            enabled_features: enabled,
        },
        passes,
    })
}

/// Each slot against the resource bound to it: kind, element or format, size, usage.
fn check_slots(resources: &[ResourceInfo], node: &PassNode, setup: &SetupContext) -> Result<()> {
    let mut seen: HashMap<ResourceId, bool> = HashMap::new();
    for (slot, h) in node.contract.slots.iter().zip(&node.bindings) {
        let res = &resources[h.id.index()];
        let mismatch = |expected: String, found: String| GraphError::DescriptorMismatch {
            pass: node.name.clone(),
            slot: slot.name.to_string(),
            resource: res.name.clone(),
            expected,
            found,
        };
        match (&slot.kind, &res.desc) {
            (SlotKind::Buffer { element }, ResourceDesc::Buffer(b)) => {
                if let Some(e) = element
                    && e != &b.element
                {
                    return Err(mismatch(
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
                    return Err(mismatch(
                        format!("a {} texture", format_name(*f)),
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
                return Err(mismatch(
                    expected.to_string(),
                    format!("a {}", d.kind_name()),
                ));
            }
        }
        for (s, min) in setup.min_bytes.iter().filter(|(s, _)| s == slot.name) {
            if res.desc.bytes() < *min {
                return Err(mismatch(
                    format!("at least {min} bytes (slot {s})"),
                    format!("{} bytes", res.desc.bytes()),
                ));
            }
        }
        let usage_err = |needed: String, reason: String| GraphError::UsageNotAllowed {
            pass: node.name.clone(),
            slot: slot.name.to_string(),
            resource: res.name.clone(),
            access: slot.access.name().to_string(),
            needed,
            reason,
        };
        match &res.desc {
            ResourceDesc::Buffer(_) => {
                let Some(need) = slot.access.buffer_usage() else {
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
                    return Err(usage_err(
                        format!("{need:?}"),
                        format!("it was imported with only {have:?}; create it with {need:?} too"),
                    ));
                }
            }
            ResourceDesc::Texture(t) => {
                let Some(need) = slot.access.texture_usage() else {
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
                    return Err(usage_err(
                        format!("{need:?}"),
                        format!("it was imported with only {have:?}; create it with {need:?} too"),
                    ));
                }
            }
        }
        if slot.access.writes()
            && let ResourceKind::HistoryPrev { .. } = res.kind
        {
            return Err(GraphError::ReadOnlyResource {
                pass: node.name.clone(),
                slot: slot.name.to_string(),
                resource: res.name.clone(),
                why: "last frame's history is read-only; write the current half instead",
            });
        }
        // One resource in two slots of one pass, one of them writing, would alias inside a
        // dispatch (and wgpu rejects a writable storage binding that overlaps another).
        if let Some(&other_writes) = seen.get(&h.id)
            && (other_writes || slot.access.writes())
        {
            return Err(usage_err(
                "its own slot".into(),
                "the same resource is bound to another slot of this pass, and one of them writes"
                    .into(),
            ));
        }
        seen.insert(h.id, slot.access.writes());
    }
    Ok(())
}
