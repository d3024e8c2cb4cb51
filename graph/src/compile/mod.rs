//! Compile: a pure function from declared passes and resources to an execution plan. It
//! needs no device, so every rule here is tested headless.

pub mod cull;
pub mod limits;
pub mod order;
pub mod pool;
pub mod slots;
pub mod versions;

use crate::access::{Access, texture_usage_for};
use crate::adapter::AdapterClass;
use crate::builder::{GraphBuilder, VisibilityDecl};
use crate::error::{GraphError, Result};
use crate::names::feature_names;
use crate::node::PassNode;
use crate::pass::SetupContext;
use crate::pass::Visibility64;
use crate::plan::*;
use crate::program::{ProgramDesc, ProgramPlan};
use crate::resource::*;
use pool::Lifetime;
use std::sync::Arc;

/// What compile plans for: the adapter's features, limits and class (no device needed).
#[derive(Clone, Debug)]
pub struct CompileOptions {
    /// Features of the adapter the graph will run on (`Features::all()` to plan without
    /// one).
    pub adapter_features: wgpu::Features,
    /// Limits of the adapter: buffer, binding and texture sizes, workgroups per dimension.
    pub limits: wgpu::Limits,
    /// How the adapter's units divide between graphics and compute, which orders `auto`
    /// where measurements say a stage's best implementation differs by class.
    pub class: AdapterClass,
}

impl CompileOptions {
    /// Plans for an adapter with `adapter_features` and wgpu's default limits, which every
    /// Vulkan adapter meets; use [`CompileOptions::for_adapter`] to plan for a real one.
    pub fn new(adapter_features: wgpu::Features) -> Self {
        Self {
            adapter_features,
            limits: wgpu::Limits::default(),
            class: AdapterClass::default(),
        }
    }
    /// Plans for adapters of `class` (a graphics GPU unless told).
    pub fn with_class(mut self, class: AdapterClass) -> Self {
        self.class = class;
        self
    }
    /// Plans for these limits instead of wgpu's defaults, e.g. to test a limit check.
    pub fn with_limits(mut self, limits: wgpu::Limits) -> Self {
        self.limits = limits;
        self
    }
}

impl GraphBuilder {
    /// Checks and plans the graph for `options`' adapter; see [`CompileOptions`].
    pub fn compile(self, options: &CompileOptions) -> Result<CompiledGraph> {
        compile(self, options)
    }
}

/// What compile learnt from each pass's setup that later re-plans need again.
pub(crate) struct PassSetup {
    pub min_bytes: Vec<(String, u64)>,
    pub dispatches: Vec<(String, [u32; 3])>,
    pub programs: Vec<(String, Arc<ProgramDesc>)>,
}

/// A plan plus the passes it runs.
pub struct CompiledGraph {
    /// The plan: order, batches, lifetimes, pool slots and usages; serialisable for dumps.
    pub plan: Plan,
    /// Unique per compiled graph: the executor keeps what it resolved for each pass (its
    /// programs) under it, so a steady frame finds them without building keys.
    pub(crate) id: u64,
    pub(crate) passes: Vec<PassNode>,
    pub(crate) setups: Vec<PassSetup>,
    /// Descriptors as declared, before size parameters were applied.
    declared: Vec<ResourceDesc>,
    limits: wgpu::Limits,
}

impl CompiledGraph {
    /// The current value of a size parameter.
    pub fn param(&self, name: &str) -> Option<u64> {
        self.plan.param(name)
    }

    /// Changes a size parameter: buffers sized by it get the new size, the pool is planned
    /// again, and the executor replaces the old objects (and history) on the next frame,
    /// without rebuilding or setting up any pass. On error the plan is left as it was.
    pub fn set_param(&mut self, name: &str, value: u64) -> Result<()> {
        let mut params = self.plan.params.clone();
        let Some(p) = params.iter_mut().find(|(n, _)| n == name) else {
            return Err(GraphError::NoSuchParam {
                param: name.to_string(),
                known: param_names(&self.plan.params),
            });
        };
        if p.1 == value {
            return Ok(());
        }
        p.1 = value;
        let mut infos: Vec<ResourceInfo> =
            self.plan.resources.iter().map(|r| r.info.clone()).collect();
        resolve_sizes(&mut infos, &self.declared, &params)?;
        for (p, node) in self.passes.iter().enumerate() {
            slots::check_min_bytes(&infos, node, &self.setups[p].min_bytes)?;
        }
        limits::check(
            &infos,
            &self.passes,
            &self.setups,
            &self.plan.order,
            &self.limits,
        )?;
        let lifetimes: Vec<Option<Lifetime>> =
            self.plan.resources.iter().map(|r| r.lifetime).collect();
        let pool = pool::assign_slots(&infos, &lifetimes);
        for (r, info) in infos.into_iter().enumerate() {
            self.plan.resources[r].info = info;
            self.plan.resources[r].pool_slot = pool.slot_of[r];
        }
        self.plan.pool_slots = pool.slots;
        self.plan.bytes_with_reuse = pool.bytes_with_reuse;
        self.plan.bytes_without_reuse = pool.bytes_without_reuse;
        self.plan.params = params;
        self.plan.generation += 1;
        Ok(())
    }
}

fn param_names(params: &[(String, u64)]) -> String {
    if params.is_empty() {
        return "none".into();
    }
    params
        .iter()
        .map(|(n, _)| n.as_str())
        .collect::<Vec<_>>()
        .join(", ")
}

/// Applies size parameters to buffer descriptors that name one.
fn resolve_sizes(
    resources: &mut [ResourceInfo],
    declared: &[ResourceDesc],
    params: &[(String, u64)],
) -> Result<()> {
    for (res, decl) in resources.iter_mut().zip(declared) {
        if let ResourceDesc::Buffer(b) = decl
            && let Some(param) = &b.count_param
        {
            let count = params
                .iter()
                .find(|(n, _)| n == param)
                .map(|(_, v)| *v)
                .ok_or_else(|| GraphError::UnknownParam {
                    resource: res.name.clone(),
                    param: param.clone(),
                    known: param_names(params),
                })?;
            let mut desc = BufferDesc::array(b.element.clone(), count);
            desc.count_param = Some(param.clone());
            res.desc = ResourceDesc::Buffer(desc);
        }
        if let ResourceDesc::Buffer(b) = &res.desc {
            if b.overflowed() {
                return Err(GraphError::SizeOverflow {
                    resource: res.name.clone(),
                });
            }
            // wgpu would take it and refuse the binding later, naming no parameter. An
            // import's declaration may say 0: the caller's buffer is what gets bound.
            if b.size == 0 && !matches!(res.kind, ResourceKind::Imported { .. }) {
                return Err(GraphError::EmptyBuffer {
                    resource: res.name.clone(),
                    param: b.count_param.clone(),
                });
            }
        }
    }
    Ok(())
}

pub fn compile(builder: GraphBuilder, options: &CompileOptions) -> Result<CompiledGraph> {
    profiling::scope!("meshlight::compile");
    let GraphBuilder {
        mut resources,
        passes,
        deferred,
        params,
        visibility,
        ..
    } = builder;
    if let Some(e) = deferred.into_iter().next() {
        return Err(e);
    }

    // Keep, for each pass given several implementations, the one the adapter runs.
    let mut choices: Vec<Option<ChoicePlan>> = Vec::with_capacity(passes.len());
    let mut chosen_passes = Vec::with_capacity(passes.len());
    for mut node in passes {
        match node.alternatives.take() {
            None => choices.push(None),
            Some(mut choice) => {
                // The node holds the first candidate; the choice, the others.
                choice.candidates.insert(0, node.pass);
                let (pass, plan) =
                    crate::choice::resolve(&node.name, choice, options.class, |c| {
                        crate::choice::missing_features(
                            c,
                            options.adapter_features,
                            &options.limits,
                            options.class,
                            &params,
                            node.contract.slot_names(),
                        )
                    })?;
                node.pass = pass;
                choices.push(Some(plan));
            }
        }
        chosen_passes.push(node);
    }
    let passes = chosen_passes;
    visibility_forms(&mut resources, &passes, &visibility)?;

    // Setup each pass against the adapter's features and limits.
    let mut setups = Vec::with_capacity(passes.len());
    let mut enabled = wgpu::Features::empty();
    let mut scratch_of: Vec<Vec<usize>> = Vec::with_capacity(passes.len());
    for (p, node) in passes.iter().enumerate() {
        let textures = node
            .bound_slots()
            .filter_map(|(s, h)| match &resources[h.id.index()].desc {
                ResourceDesc::Texture(t) => Some((s.name, t.format)),
                ResourceDesc::Buffer(_) => None,
            })
            .collect();
        let mut ctx = SetupContext::new(
            options.adapter_features,
            &options.limits,
            options.class,
            &params,
            node.contract.slot_names(),
        )
        .with_textures(textures);
        node.pass.setup(&mut ctx).map_err(|e| match e {
            GraphError::Parameter { message, .. } => GraphError::Parameter {
                pass: node.name.clone(),
                message,
            },
            other => other,
        })?;
        // A pass skipped on this adapter class declares nothing, its inputs included.
        if ctx.skipped.is_none()
            && let Some((read, supplied)) =
                (node.inputs.iter()).find(|(read, _)| !ctx.frame_inputs.iter().any(|i| i == read))
        {
            return Err(GraphError::Parameter {
                pass: node.name.clone(),
                message: format!(
                    "it reads no frame input `{read}` (it reads: {}), so `{supplied}` cannot be supplied for it; remove that input mapping",
                    if ctx.frame_inputs.is_empty() {
                        "none".to_string()
                    } else {
                        ctx.frame_inputs.join(", ")
                    }
                ),
            });
        }
        // 64-bit texture atomics on a bound R64Uint texture are a requirement of the
        // binding itself, whatever the pass declared.
        for (slot, h) in node.bound_slots() {
            if let ResourceDesc::Texture(t) = &resources[h.id.index()].desc {
                for a in slot.accesses() {
                    ctx.required |= crate::access::texture_features_for(a, t.format);
                    // `RecordContext::clear` on a texture is a texture clear; a pass that
                    // clears with its own dispatch does without it.
                    if a == Access::ClearedReadWrite {
                        ctx.optional |= wgpu::Features::CLEAR_TEXTURE;
                    }
                }
            }
        }
        let missing = ctx.required - options.adapter_features;
        if !missing.is_empty() {
            return Err(GraphError::MissingFeature {
                pass: node.name.clone(),
                stage: node.contract.stage.to_string(),
                features: feature_names(missing),
                instead: format!(
                    "pick another implementation of stage `{}` (or `auto`) or another adapter (MESHLIGHT_ADAPTER)",
                    node.contract.stage
                ),
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
                desc: s.desc.clone(),
                kind: ResourceKind::Scratch { pass: p },
            });
            mine.push(resources.len() - 1);
        }
        scratch_of.push(mine);
        setups.push(ctx);
    }
    let declared: Vec<ResourceDesc> = resources.iter().map(|r| r.desc.clone()).collect();
    resolve_sizes(&mut resources, &declared, &params)?;

    for (node, setup) in passes.iter().zip(&setups) {
        slots::check_slots(&resources, node)?;
        slots::check_min_bytes(&resources, node, &setup.min_bytes)?;
    }

    let table = versions::derive_edges(&resources, &passes)?;
    let names: Vec<String> = passes.iter().map(|p| p.name.clone()).collect();
    let dag = order::build_dag(passes.len(), &table.edges);
    let topo = order::topological_order(&dag, &names)?;
    let side_effects: Vec<bool> = setups.iter().map(|s| s.side_effect).collect();
    let live = cull::live_passes(&resources, &passes, &side_effects, &table.edges);
    let order: Vec<usize> = topo.into_iter().filter(|&p| live[p]).collect();
    let is_readback: Vec<bool> = passes
        .iter()
        .map(|p| p.contract.stage == crate::readback::STAGE)
        .collect();
    let order = order::sink_readbacks(&dag, order, &is_readback);
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

    let (buffer_usage, texture_usage) = usages(&resources, &passes, &setups, &scratch_of, &order);

    let mut versions = vec![0u32; resources.len()];
    for &(r, v) in table.writer.keys() {
        versions[r] = versions[r].max(v);
    }

    let pass_plans = passes
        .iter()
        .zip(&setups)
        .enumerate()
        .map(|(p, (node, setup))| PassPlan {
            name: node.name.clone(),
            stage: node.contract.stage,
            implementation: node.pass.implementation().name,
            choice: choices[p].clone(),
            slots: slot_uses(&resources, &table, &live, node),
            scratch: scratch_of[p].clone(),
            shader_defs: setup
                .shader_defs
                .iter()
                .map(|(n, v)| (n.clone(), format!("{v:?}")))
                .collect(),
            programs: setup
                .programs
                .iter()
                .map(|(n, d)| ProgramPlan::new(n, d))
                .collect(),
            frame_inputs: (setup.frame_inputs.iter())
                .map(|read| node.supplied_input(read).to_string())
                .collect(),
            required_features: setup.required,
            optional_features: setup.optional,
            side_effect: setup.side_effect,
            recording: recording(&resources, node, setup, &scratch_of[p]),
            skipped: setup.skipped.clone(),
            notes: setup.notes.clone(),
        })
        .collect::<Vec<_>>();
    let batches = batches_of(&pass_plans, &order);

    let pass_setups: Vec<PassSetup> = setups
        .into_iter()
        .map(|s| PassSetup {
            min_bytes: s.min_bytes,
            dispatches: s.dispatches,
            programs: s
                .programs
                .into_iter()
                .map(|(n, d)| (n, Arc::new(d)))
                .collect(),
        })
        .collect();
    limits::check(&resources, &passes, &pass_setups, &order, &options.limits)?;

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

    static NEXT_ID: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(0);
    Ok(CompiledGraph {
        id: NEXT_ID.fetch_add(1, std::sync::atomic::Ordering::Relaxed),
        plan: Plan {
            passes: pass_plans,
            order,
            batches,
            culled,
            resources: resource_plans,
            edges: table.edges,
            pool_slots: pool.slots,
            bytes_without_reuse: pool.bytes_without_reuse,
            bytes_with_reuse: pool.bytes_with_reuse,
            enabled_features: enabled,
            params,
            generation: 0,
            class: options.class,
        },
        passes,
        setups: pass_setups,
        declared,
        limits: options.limits.clone(),
    })
}

/// Whether a pass can be recorded inside a batch's shared compute pass (see
/// [`Recording`]): the first thing found that needs the command encoder, else `Compute`.
fn recording(
    resources: &[ResourceInfo],
    node: &PassNode,
    setup: &SetupContext<'_>,
    scratch: &[usize],
) -> Recording {
    // A skipped pass records nothing, so it never holds a batch up.
    if setup.skipped.is_some() {
        return Recording::Compute;
    }
    if let Some(why) = &setup.needs_encoder {
        return Recording::Encoder(why.clone());
    }
    if let Some((name, _)) = setup
        .programs
        .iter()
        .find(|(_, d)| !matches!(d.kind, crate::program::ProgramKind::Compute { .. }))
    {
        return Recording::Encoder(format!("render program `{name}`"));
    }
    let encoder_access = |a: Access| {
        matches!(
            a,
            Access::CopySrc
                | Access::CopyDst
                | Access::RenderTarget
                | Access::DepthTarget
                | Access::Vertex
                | Access::Index
        )
    };
    for (slot, h) in node.bound_slots() {
        if let Some(a) = slot.accesses().find(|&a| encoder_access(a)) {
            return Recording::Encoder(format!("slot `{}` is {}", slot.name, a.name()));
        }
        let texture = matches!(resources[h.id.index()].desc, ResourceDesc::Texture(_));
        if texture
            && slot.accesses().any(|a| a == Access::ClearedReadWrite)
            && !setup.clears_itself.iter().any(|s| s == slot.name)
        {
            return Recording::Encoder(format!("clears texture slot `{}`", slot.name));
        }
    }
    for (decl, _) in setup.scratch.iter().zip(scratch) {
        if let Some(a) = decl.accesses.iter().copied().find(|&a| encoder_access(a)) {
            return Recording::Encoder(format!("scratch `{}` is {}", decl.name, a.name()));
        }
    }
    Recording::Compute
}

/// Every access any live pass makes, plus what the executor itself needs.
fn usages(
    resources: &[ResourceInfo],
    passes: &[PassNode],
    setups: &[SetupContext<'_>],
    scratch_of: &[Vec<usize>],
    order: &[usize],
) -> (Vec<wgpu::BufferUsages>, Vec<wgpu::TextureUsages>) {
    let mut buffer_usage = vec![wgpu::BufferUsages::empty(); resources.len()];
    let mut texture_usage = vec![wgpu::TextureUsages::empty(); resources.len()];
    let mut add = |r: usize, a: Access| {
        buffer_usage[r] |= a.buffer_usage().unwrap_or(wgpu::BufferUsages::empty());
        if let ResourceDesc::Texture(t) = &resources[r].desc {
            texture_usage[r] |=
                texture_usage_for(a, t.format).unwrap_or(wgpu::TextureUsages::empty());
        }
    };
    for &p in order {
        for (slot, h) in passes[p].bound_slots() {
            for a in slot.accesses() {
                add(h.id.index(), a);
            }
        }
        for (decl, &r) in setups[p].scratch.iter().zip(&scratch_of[p]) {
            for &a in &decl.accesses {
                add(r, a);
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
    (buffer_usage, texture_usage)
}

/// The plan's view of each slot: versions, the texture range, and for render and depth
/// targets the load and store ops.
fn slot_uses(
    resources: &[ResourceInfo],
    table: &versions::VersionTable,
    live: &[bool],
    node: &PassNode,
) -> Vec<SlotUse> {
    node.bound_slots()
        .zip(&node.ranges)
        .map(|((slot, h), range)| {
            let r = h.id.index();
            let writes_version = slot.writes().then_some(h.version + 1);
            let ops = slot
                .accesses()
                .any(|a| matches!(a, Access::RenderTarget | Access::DepthTarget))
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
            let range = match (&resources[r].desc, range) {
                (ResourceDesc::Texture(t), Some(range)) => Some(range.resolve(t)),
                _ => None,
            };
            SlotUse {
                slot: slot.name,
                resource: r,
                access: slot.access,
                also: slot.also.clone(),
                version: h.version,
                writes_version,
                ops,
                range,
            }
        })
        .collect()
}

/// Gives each target declared with `create_visibility64` the form its clearing pass
/// writes (a `u64` buffer unless that pass writes an `R64Uint` texture), and checks that
/// a pass writing one form is not bound to a resource declared as the other.
fn visibility_forms(
    resources: &mut [ResourceInfo],
    passes: &[PassNode],
    declared: &[VisibilityDecl],
) -> Result<()> {
    for decl in declared {
        let mut form: Option<(Visibility64, &str)> = None;
        for node in passes {
            let Some(wants) = node.pass.visibility64() else {
                continue;
            };
            if !node.bindings.iter().any(|h| h.id == decl.id) {
                continue;
            }
            match form {
                Some((other, by)) if other != wants => {
                    return Err(GraphError::Parameter {
                        pass: node.name.clone(),
                        message: format!(
                            "it writes the visibility target `{}` as a {}, but pass `{by}` writes it as a {}; pick implementations that agree (both on buffers or both on textures, or `auto` for both)",
                            resources[decl.id.index()].name,
                            form_name(wants),
                            form_name(other)
                        ),
                    });
                }
                _ => form = Some((wants, &node.name)),
            }
        }
        if let Some((Visibility64::Texture, _)) = form {
            resources[decl.id.index()].desc = ResourceDesc::Texture(TextureDesc::d2(
                wgpu::TextureFormat::R64Uint,
                decl.width,
                decl.height,
            ));
        }
    }
    for node in passes {
        let Some(wants) = node.pass.visibility64() else {
            continue;
        };
        for (slot, h) in node.bound_slots() {
            if slot.kind != crate::contract::SlotKind::Visibility64 {
                continue;
            }
            let res = &resources[h.id.index()];
            let is_texture = matches!(res.desc, ResourceDesc::Texture(_));
            if is_texture != (wants == Visibility64::Texture) {
                return Err(GraphError::DescriptorMismatch {
                    pass: node.name.clone(),
                    slot: slot.name.to_string(),
                    resource: res.name.clone(),
                    expected: format!(
                        "a {} (implementation `{}` writes one); declare `{}` with `visibility = {{ width_param = ..., height_param = ... }}` (`create_visibility64` in code) so it follows the implementation",
                        form_name(wants),
                        node.pass.implementation().name,
                        res.name
                    ),
                    found: format!("a {}", res.desc.kind_name()),
                });
            }
        }
    }
    Ok(())
}

fn form_name(v: Visibility64) -> &'static str {
    match v {
        Visibility64::Buffer => "buffer of u64",
        Visibility64::Texture => "r64uint texture",
    }
}
