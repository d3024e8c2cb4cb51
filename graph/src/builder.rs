//! The code-first API: declare resources, add passes with slot bindings, compile.

use crate::choice::Choice;
use crate::error::{GraphError, Result};
use crate::node::PassNode;
use crate::pass::Pass;
use crate::resource::*;

/// How a slot is bound when a pass is added.
#[derive(Clone, Debug)]
enum Target {
    Handle(AnyHandle),
    Name(String),
    /// Left unbound though a resource of the slot's name exists.
    Nothing,
}

/// Slot → resource bindings of one pass. Slots left out bind to the resource of the same
/// name, at its current version.
#[derive(Clone, Debug, Default)]
pub struct Bindings {
    entries: Vec<(String, Target, Option<TextureRange>)>,
    /// (frame input the pass reads, the frame input supplied for it).
    inputs: Vec<(String, String)>,
}

impl Bindings {
    /// No bindings: every slot binds the resource of its own name.
    pub fn new() -> Self {
        Self::default()
    }
    /// Binds `slot` to this version of a resource; a stale version is caught at compile.
    pub fn bind(mut self, slot: &str, handle: impl Into<AnyHandle>) -> Self {
        self.entries
            .push((slot.to_string(), Target::Handle(handle.into()), None));
        self
    }
    /// Binds a slot to part of a texture: some mips or layers. Two slots of one pass may
    /// bind one texture when their ranges are disjoint (read mip N − 1, write mip N).
    pub fn bind_range(
        mut self,
        slot: &str,
        handle: impl Into<AnyHandle>,
        range: TextureRange,
    ) -> Self {
        self.entries
            .push((slot.to_string(), Target::Handle(handle.into()), Some(range)));
        self
    }
    /// Binds a slot to a resource by name, at its current version.
    pub fn bind_named(mut self, slot: &str, resource: &str) -> Self {
        self.entries
            .push((slot.to_string(), Target::Name(resource.to_string()), None));
        self
    }
    /// Supplies the pass's frame input `read` (e.g. `view`) from the frame input named
    /// `supplied`, so one stage can run once per view of a frame, each pass reading its
    /// own view. An input never mapped is read under its own name.
    pub fn input(mut self, read: &str, supplied: &str) -> Self {
        self.inputs.retain(|(r, _)| r != read);
        self.inputs.push((read.to_string(), supplied.to_string()));
        self
    }
    /// Leaves the optional slot `slot` unbound even where a resource of its name exists
    /// (a pipeline file writes `slot = ""`): a shadow view's cull that must not test
    /// the camera's depth pyramid. A required slot left so is an error at `add_pass`.
    pub fn unbind(mut self, slot: &str) -> Self {
        self.entries.push((slot.to_string(), Target::Nothing, None));
        self
    }
    /// [`Bindings::bind_named`] with a texture range.
    pub fn bind_named_range(mut self, slot: &str, resource: &str, range: TextureRange) -> Self {
        self.entries.push((
            slot.to_string(),
            Target::Name(resource.to_string()),
            Some(range),
        ));
        self
    }
}

/// A resource written this frame and read next frame.
#[derive(Clone, Copy, Debug)]
pub struct History<K> {
    /// Last frame's contents (read-only; zeroed on the first frame).
    pub prev: Handle<K>,
    /// This frame's contents, to be written.
    pub current: Handle<K>,
}

/// New versions of the resources a pass wrote.
#[derive(Clone, Debug)]
pub struct PassOutputs {
    /// The pass that wrote them, named in errors.
    pub pass: String,
    written: Vec<(&'static str, AnyHandle)>,
}

impl PassOutputs {
    fn find(&self, slot: &str) -> Result<AnyHandle> {
        self.written
            .iter()
            .find(|(s, _)| *s == slot)
            .map(|(_, h)| *h)
            .ok_or_else(|| GraphError::NotWritten {
                pass: self.pass.clone(),
                slot: slot.to_string(),
                written: self
                    .written
                    .iter()
                    .map(|(s, _)| *s)
                    .collect::<Vec<_>>()
                    .join(", "),
            })
    }
    /// The new version of the buffer written through `slot`.
    pub fn buffer(&self, slot: &str) -> Result<Handle<Buffer>> {
        self.find(slot).map(|h| Handle::new(h.id, h.version))
    }
    /// The new version of the texture written through `slot`.
    pub fn texture(&self, slot: &str) -> Result<Handle<Texture>> {
        self.find(slot).map(|h| Handle::new(h.id, h.version))
    }
    /// Each written slot with the new version it made, in contract slot order.
    pub fn written(&self) -> &[(&'static str, AnyHandle)] {
        &self.written
    }
}

/// Declares a frame: resources, then passes in the order their effects should apply.
///
/// Compiling needs no device: the plan orders the passes, culls those whose writes
/// nothing reads, and pools the transients.
///
/// ```
/// use meshlight_graph::synthetic::NoopPass;
/// use meshlight_graph::*;
///
/// # fn main() -> Result<()> {
/// let mut g = GraphBuilder::new();
/// g.create_buffer("visible", BufferDesc::array(Element::U32, 1024));
/// g.create_buffer("debug", BufferDesc::array(Element::U32, 16));
/// let image = g.create_buffer("image", BufferDesc::array(Element::U32, 64 * 64));
/// g.export(image);
/// // Passes that record nothing, with the slots of a cull, a raster and a debug view;
/// // a slot binds the resource of its own name unless `Bindings` says otherwise.
/// let pass = |reads: &[&'static str], writes: &[&'static str]| NoopPass {
///     slots: reads
///         .iter()
///         .map(|r| Slot::read(r, Element::U32, ""))
///         .chain(writes.iter().map(|w| Slot::buffer(w, Access::StorageWrite, Element::U32, "")))
///         .collect(),
/// };
/// g.add_pass("cull", pass(&[], &["visible"]), Bindings::new())?;
/// g.add_pass("debug_view", pass(&["visible"], &["debug"]), Bindings::new())?;
/// g.add_pass("raster", pass(&["visible"], &["image"]), Bindings::new())?;
///
/// let plan = g.compile(&CompileOptions::new(wgpu::Features::empty()))?.plan;
/// let names = |passes: &[usize]| -> Vec<String> {
///     passes.iter().map(|&p| plan.passes[p].name.clone()).collect()
/// };
/// assert_eq!(names(&plan.order), ["cull", "raster"]);
/// // Nothing reads what the debug view writes, and `debug` is not exported.
/// assert_eq!(names(&plan.culled), ["debug_view"]);
/// # Ok(())
/// # }
/// ```
#[derive(Default)]
pub struct GraphBuilder {
    pub(crate) resources: Vec<ResourceInfo>,
    pub(crate) passes: Vec<PassNode>,
    /// The newest version of each resource seen so far, to resolve by-name bindings.
    current: Vec<u32>,
    /// Errors found while declaring, reported by `compile` so declaration code stays
    /// linear.
    pub(crate) deferred: Vec<GraphError>,
    /// Size parameters and their values, in declaration order.
    pub(crate) params: Vec<(String, u64)>,
    /// Visibility targets whose form (buffer or texture) the pass clearing them decides.
    pub(crate) visibility: Vec<VisibilityDecl>,
}

/// A 64-bit visibility target declared with [`GraphBuilder::create_visibility64`].
#[derive(Clone, Copy, Debug)]
pub(crate) struct VisibilityDecl {
    pub id: ResourceId,
    pub width: u32,
    pub height: u32,
}

impl GraphBuilder {
    /// An empty graph.
    pub fn new() -> Self {
        Self::default()
    }

    fn add_resource(&mut self, name: &str, desc: ResourceDesc, kind: ResourceKind) -> ResourceId {
        if self.resources.iter().any(|r| r.name == name) {
            self.deferred.push(GraphError::DuplicateName {
                what: "resource",
                name: name.to_string(),
            });
        }
        self.resources.push(ResourceInfo {
            name: name.to_string(),
            desc,
            kind,
        });
        self.current.push(0);
        ResourceId(self.resources.len() as u32 - 1)
    }

    /// The handle to the first version of a newly declared resource: every declaration
    /// returns one, typed by the caller as a buffer or a texture.
    fn add_first_version<K>(
        &mut self,
        name: &str,
        desc: ResourceDesc,
        kind: ResourceKind,
    ) -> Handle<K> {
        Handle::new(self.add_resource(name, desc, kind), 0)
    }

    /// A transient buffer: the graph allocates it from its pool and may share the memory with
    /// resources whose lifetimes do not overlap.
    pub fn create_buffer(&mut self, name: &str, desc: BufferDesc) -> Handle<Buffer> {
        self.add_first_version(name, ResourceDesc::Buffer(desc), ResourceKind::Transient)
    }
    /// A transient texture; see [`GraphBuilder::create_buffer`].
    pub fn create_texture(&mut self, name: &str, desc: TextureDesc) -> Handle<Texture> {
        self.add_first_version(name, ResourceDesc::Texture(desc), ResourceKind::Transient)
    }
    /// A transient `width × height` 64-bit visibility target whose form follows the pass
    /// that clears it ([`crate::Pass::visibility64`]): a buffer of `u64` for a rasteriser
    /// on storage-buffer atomics, an `R64Uint` texture for one on texture atomics. Every
    /// other pass bound to it sees that form, so swapping the rasteriser is one change.
    pub fn create_visibility64(&mut self, name: &str, width: u32, height: u32) -> AnyHandle {
        let pixels = width as u64 * height as u64;
        let desc = ResourceDesc::Buffer(BufferDesc::array(Element::U64, pixels));
        let id = self.add_resource(name, desc, ResourceKind::Transient);
        self.visibility.push(VisibilityDecl { id, width, height });
        AnyHandle { id, version: 0 }
    }
    /// A caller-owned buffer; `usage` is what the caller created it with.
    pub fn import_buffer(
        &mut self,
        name: &str,
        desc: BufferDesc,
        usage: wgpu::BufferUsages,
    ) -> Handle<Buffer> {
        self.import(
            name,
            ResourceDesc::Buffer(desc),
            ImportedUsage::Buffer(usage),
        )
    }
    /// A caller-owned texture; `usage` is what the caller created it with.
    pub fn import_texture(
        &mut self,
        name: &str,
        desc: TextureDesc,
        usage: wgpu::TextureUsages,
    ) -> Handle<Texture> {
        self.import(
            name,
            ResourceDesc::Texture(desc),
            ImportedUsage::Texture(usage),
        )
    }
    fn import<K>(&mut self, name: &str, desc: ResourceDesc, usage: ImportedUsage) -> Handle<K> {
        self.add_first_version(name, desc, ResourceKind::Imported { usage })
    }
    /// A buffer carried to the next frame: write `current`; read last frame's as `prev`
    /// (named `<name>.prev`).
    pub fn history_buffer(&mut self, name: &str, desc: BufferDesc) -> History<Buffer> {
        self.history(name, ResourceDesc::Buffer(desc))
    }
    /// A texture carried to the next frame; see [`GraphBuilder::history_buffer`].
    pub fn history_texture(&mut self, name: &str, desc: TextureDesc) -> History<Texture> {
        self.history(name, ResourceDesc::Texture(desc))
    }
    /// Declares `name` and `<name>.prev`, each pointing at the other.
    fn history<K>(&mut self, name: &str, desc: ResourceDesc) -> History<K> {
        let n = self.resources.len() as u32;
        let current: Handle<K> = self.add_first_version(
            name,
            desc.clone(),
            ResourceKind::History {
                prev: ResourceId(n + 1),
            },
        );
        let prev = self.add_first_version(
            &format!("{name}.prev"),
            desc,
            ResourceKind::HistoryPrev {
                current: current.id,
            },
        );
        History { prev, current }
    }
    /// Keeps a transient after the frame so the caller can read it back.
    pub fn export(&mut self, handle: impl Into<AnyHandle>) {
        let r = &mut self.resources[handle.into().id.index()];
        if r.kind == ResourceKind::Transient {
            r.kind = ResourceKind::Exported;
        }
    }

    /// Declares a size parameter: buffers made with [`BufferDesc::array_param`] hold
    /// `value` elements, and [`crate::CompiledGraph::set_param`] changes it without rebuilding.
    pub fn size_param(&mut self, name: &str, value: u64) {
        match self.params.iter_mut().find(|(n, _)| n == name) {
            Some(p) => p.1 = value,
            None => self.params.push((name.to_string(), value)),
        }
    }

    /// Copies `range` (bytes; `None`: all) of `handle` to the CPU every frame, ready
    /// `latency` frames later through [`crate::Executor::take_readback`], which never
    /// waits for the GPU. The pass is named `readback:<name>` and is never culled.
    pub fn readback(
        &mut self,
        name: &str,
        handle: Handle<Buffer>,
        range: Option<std::ops::Range<u64>>,
        latency: u32,
    ) -> Result<()> {
        self.add_readback(name, range, latency, Bindings::new().bind("source", handle))
    }

    /// [`Self::readback`] of the newest version of the buffer named `resource`, for
    /// graphs loaded from pipeline files, where the caller has names, not handles.
    pub fn readback_named(
        &mut self,
        name: &str,
        resource: &str,
        range: Option<std::ops::Range<u64>>,
        latency: u32,
    ) -> Result<()> {
        let source = Bindings::new().bind_named("source", resource);
        self.add_readback(name, range, latency, source)
    }

    fn add_readback(
        &mut self,
        name: &str,
        range: Option<std::ops::Range<u64>>,
        latency: u32,
        source: Bindings,
    ) -> Result<()> {
        let pass = crate::readback::ReadbackPass::new(name, range, latency);
        self.add_pass(&format!("readback:{name}"), pass, source)
            .map(drop)
    }

    /// Looks a resource up by name, at its newest version.
    pub fn resource(&self, name: &str) -> Option<AnyHandle> {
        let i = self.resources.iter().position(|r| r.name == name)?;
        Some(AnyHandle {
            id: ResourceId(i as u32),
            version: self.current[i],
        })
    }
    /// Looks a resource up by name at an explicit version (pipeline files use `name@3`).
    pub fn resource_at(&self, name: &str, version: u32) -> Option<AnyHandle> {
        let i = self.resources.iter().position(|r| r.name == name)?;
        Some(AnyHandle {
            id: ResourceId(i as u32),
            version,
        })
    }
    /// Every resource declared so far, in declaration order (a handle's id indexes it).
    pub fn resources(&self) -> &[ResourceInfo] {
        &self.resources
    }

    /// Adds a pass instance named `name`. Slots not in `bindings` bind to the resource of
    /// the same name. Returns the new versions of what it writes.
    pub fn add_pass(
        &mut self,
        name: &str,
        pass: impl Pass + 'static,
        bindings: Bindings,
    ) -> Result<PassOutputs> {
        self.add_boxed_pass(name, Box::new(pass), bindings)
    }

    /// Adds a pass instance whose implementation compile picks among `choice`'s candidates
    /// (see [`Choice`]); every candidate must implement the same stage with the same slots.
    pub fn add_choice(
        &mut self,
        name: &str,
        choice: Choice,
        bindings: Bindings,
    ) -> Result<PassOutputs> {
        let Choice {
            selection,
            mut candidates,
            class_orders,
        } = choice;
        if candidates.is_empty() {
            return Err(GraphError::Parameter {
                pass: name.to_string(),
                message: "a choice needs at least one candidate implementation".into(),
            });
        }
        let first = candidates.remove(0);
        let contract = first.implementation().contract;
        for c in &candidates {
            let other = c.implementation().contract;
            if other.stage != contract.stage || other.slot_names() != contract.slot_names() {
                return Err(GraphError::Parameter {
                    pass: name.to_string(),
                    message: format!(
                        "candidate `{}` implements stage `{}` with slots [{}], but `{}` implements `{}` with [{}]; a choice's candidates must share one contract",
                        c.implementation().name,
                        other.stage,
                        other.slot_names().join(", "),
                        first.implementation().name,
                        contract.stage,
                        contract.slot_names().join(", ")
                    ),
                });
            }
        }
        let outputs = self.add_boxed_pass(name, first, bindings)?;
        if let Some(node) = self.passes.last_mut() {
            node.alternatives = Some(Choice {
                selection,
                candidates,
                class_orders,
            });
        }
        Ok(outputs)
    }

    /// [`GraphBuilder::add_pass`] for a pass already boxed, e.g. one a registry made.
    pub fn add_boxed_pass(
        &mut self,
        name: &str,
        pass: Box<dyn Pass>,
        bindings: Bindings,
    ) -> Result<PassOutputs> {
        if self.passes.iter().any(|p| p.name == name) {
            return Err(GraphError::DuplicateName {
                what: "pass",
                name: name.to_string(),
            });
        }
        let mut contract = pass.implementation().contract;
        for (slot, _, _) in &bindings.entries {
            if contract.slot(slot).is_none() {
                return Err(GraphError::UnknownSlot {
                    pass: name.to_string(),
                    stage: contract.stage.to_string(),
                    slot: slot.clone(),
                    available: contract.slot_names().join(", "),
                });
            }
        }
        let mut resolved = Vec::with_capacity(contract.slots.len());
        let mut ranges = Vec::with_capacity(contract.slots.len());
        let mut unbound_optional = Vec::new();
        for slot in &contract.slots {
            let entry = bindings
                .entries
                .iter()
                .rev()
                .find(|(s, _, _)| s == slot.name);
            let target = entry.map(|(_, t, _)| t.clone());
            let range = entry.and_then(|(_, _, r)| *r);
            let handle = match target {
                Some(Target::Nothing) if slot.optional => {
                    unbound_optional.push(slot.name);
                    continue;
                }
                Some(Target::Nothing) => {
                    return Err(GraphError::UnboundSlot {
                        pass: name.to_string(),
                        slot: slot.name.to_string(),
                    });
                }
                Some(Target::Handle(h)) => h,
                Some(Target::Name(res)) => {
                    self.resource(&res)
                        .ok_or_else(|| GraphError::UnknownResource {
                            pass: name.to_string(),
                            slot: slot.name.to_string(),
                            resource: res.clone(),
                        })?
                }
                None => match self.resource(slot.name) {
                    Some(h) => h,
                    None if slot.optional => {
                        unbound_optional.push(slot.name);
                        continue;
                    }
                    None => {
                        return Err(GraphError::UnboundSlot {
                            pass: name.to_string(),
                            slot: slot.name.to_string(),
                        });
                    }
                },
            };
            resolved.push(handle);
            ranges.push(range);
        }
        let stage_slots = contract.slot_names();
        // The node keeps only bound slots, so every later step sees slots and handles in step.
        contract
            .slots
            .retain(|s| !unbound_optional.contains(&s.name));
        // A pass makes one new version of each resource it writes, however many of its
        // slots write disjoint parts of it.
        let mut written = Vec::new();
        for (slot, handle) in contract.slots.iter().zip(&resolved) {
            if slot.writes() {
                let next = AnyHandle {
                    id: handle.id,
                    version: handle.version + 1,
                };
                let cur = &mut self.current[handle.id.index()];
                *cur = (*cur).max(next.version);
                written.push((slot.name, next));
            }
        }
        self.passes.push(PassNode {
            name: name.to_string(),
            pass,
            contract,
            stage_slots,
            bindings: resolved,
            ranges,
            inputs: bindings.inputs,
            alternatives: None,
        });
        Ok(PassOutputs {
            pass: name.to_string(),
            written,
        })
    }
}
