//! Runs compiled graphs frame after frame: allocates pooled resources, swaps history,
//! records each live pass into its own labelled encoder inside an error scope, submits
//! once, and reports per-pass timings. Nothing here waits for the GPU: timestamps and
//! readbacks come back through rings of map-read buffers frames later.

use crate::compile::CompiledGraph;
use crate::error::{GraphError, Result};
use crate::exec::context::GpuContext;
use crate::exec::frame::FrameData;
use crate::exec::physical::{self, Physical, PhysicalPool};
use crate::exec::programs::Programs;
use crate::exec::readback::{Readback, Readbacks};
use crate::exec::record::RecordContext;
use crate::exec::timing::{GpuTimings, Timestamps};
use crate::exec::views::ViewCache;
use crate::resource::{ImportedUsage, ResourceDesc, ResourceKind};
use serde::Serialize;
use std::collections::{HashMap, VecDeque};
use std::time::Instant;

#[derive(Clone)]
enum Import {
    Buffer(wgpu::Buffer),
    Texture(wgpu::Texture),
}

/// Caller-owned resources for one frame, by resource name.
#[derive(Default, Clone)]
pub struct Imports {
    entries: HashMap<String, Import>,
}

impl Imports {
    pub fn new() -> Self {
        Self::default()
    }
    pub fn buffer(mut self, name: &str, buffer: &wgpu::Buffer) -> Self {
        self.entries
            .insert(name.to_string(), Import::Buffer(buffer.clone()));
        self
    }
    /// Its views are made once per texture and kept by the executor, so bind groups over
    /// an imported texture are found in the cache frame after frame.
    pub fn texture(mut self, name: &str, texture: &wgpu::Texture) -> Self {
        self.entries
            .insert(name.to_string(), Import::Texture(texture.clone()));
        self
    }
}

#[derive(Clone, Debug, Serialize)]
pub struct PassTiming {
    pub name: String,
    /// GPU time between the pass's timestamps; known once the GPU has finished the frame
    /// (see [`Executor::finish`]), `None` before and on adapters without timestamps.
    pub gpu_us: Option<f64>,
    /// CPU time spent in the pass's `record`, including pipeline creation on first use.
    pub cpu_record_us: f64,
}

#[derive(Clone, Debug, Serialize)]
pub struct FrameStats {
    pub frame: u64,
    pub passes: Vec<PassTiming>,
    /// CPU time of the whole frame on the executor's side (it never waits for the GPU).
    pub cpu_frame_us: f64,
    /// The part of `cpu_frame_us` spent in `queue.submit` (mostly driver work).
    pub cpu_submit_us: f64,
    /// Sum of `gpu_us`, when known.
    pub gpu_total_us: Option<f64>,
    /// The newest earlier frame whose GPU timings had come back when this one was recorded.
    pub gpu_latest: Option<GpuTimings>,
    /// Frames submitted whose timestamps the GPU had not yet delivered, this one included:
    /// above 1 means the CPU records ahead while the GPU works.
    pub frames_in_flight: u32,
    pub bytes_with_reuse: u64,
    pub bytes_without_reuse: u64,
    /// Bytes the executor's pool holds, in use or kept for reuse.
    pub pool_bytes_held: u64,
    /// GPU resources created this frame (zero once a steady graph has warmed up).
    pub allocations: u32,
    pub pipelines_created: u32,
    /// Bind groups created this frame (zero once steady: they are cached by what they bind).
    pub bind_groups_created: u32,
}

/// A history pair and what it was made for.
struct HistoryEntry {
    pair: [Physical; 2],
    desc: ResourceDesc,
    buffer_usage: wgpu::BufferUsages,
    texture_usage: wgpu::TextureUsages,
    /// The frame that created it: `prev` holds real contents only on later frames.
    created: u64,
}

pub struct Executor {
    pub gpu: GpuContext,
    pool: PhysicalPool,
    programs: Programs,
    views: ViewCache,
    histories: HashMap<String, HistoryEntry>,
    exported: HashMap<String, Physical>,
    timestamps: Option<Timestamps>,
    readbacks: Readbacks,
    timings: VecDeque<GpuTimings>,
    last_stats: Option<FrameStats>,
    frame: u64,
    /// Calls that waited for the GPU ([`Executor::finish`], [`Executor::read_buffer`]):
    /// frames themselves never do, and tests check this stays zero while frames run.
    pub blocking_waits: u64,
    /// Write per-pass timestamps where the adapter has them (off for CPU-overhead runs).
    pub gpu_timing: bool,
    /// Record every pass of a frame into one command buffer instead of one each. Off by
    /// default: a pass's own buffer lets a validation error that wgpu defers to
    /// `finish` name that pass; on, such an error names the frame. For measuring what the
    /// command-buffer boundaries cost.
    pub one_command_buffer: bool,
}

impl Executor {
    pub fn new(gpu: GpuContext) -> Self {
        Self {
            gpu,
            pool: PhysicalPool::default(),
            programs: Programs::new(),
            views: ViewCache::default(),
            histories: HashMap::new(),
            exported: HashMap::new(),
            timestamps: None,
            readbacks: Readbacks::default(),
            timings: VecDeque::new(),
            last_stats: None,
            frame: 0,
            blocking_waits: 0,
            gpu_timing: true,
            one_command_buffer: false,
        }
    }

    pub fn device(&self) -> &wgpu::Device {
        &self.gpu.device
    }
    pub fn queue(&self) -> &wgpu::Queue {
        &self.gpu.queue
    }
    /// Frames executed so far (the index the next frame gets).
    pub fn frame_index(&self) -> u64 {
        self.frame
    }
    /// Bytes of pooled objects the executor holds; drops once objects no frame uses are
    /// freed (a few frames after a size parameter changed).
    pub fn pool_bytes_held(&self) -> u64 {
        self.pool.held_bytes()
    }

    /// Reads back an exported transient or the current half of a history resource, as left
    /// by the last frame. Waits for the GPU: for tests and one-shot tools; frames use
    /// `GraphBuilder::readback` and [`Executor::take_readback`].
    pub fn read_buffer(&mut self, name: &str) -> Result<Vec<u8>> {
        match self.last_physical(name)? {
            Physical::Buffer { buffer, size } => self.gpu.read_buffer(&buffer, 0, size),
            Physical::Texture { .. } => Err(GraphError::Readback(format!(
                "`{name}` is a texture; read it with Executor::read_texture"
            ))),
        }
    }

    /// Reads back mip 0, layer 0 of an exported or history texture as the last frame left
    /// it, rows tightly packed. Waits for the GPU, like [`Self::read_buffer`].
    pub fn read_texture(&mut self, name: &str) -> Result<Vec<u8>> {
        match self.last_physical(name)? {
            Physical::Texture { texture, .. } => self.gpu.read_texture(&texture),
            Physical::Buffer { .. } => Err(GraphError::Readback(format!(
                "`{name}` is a buffer; read it with Executor::read_buffer"
            ))),
        }
    }

    fn last_physical(&mut self, name: &str) -> Result<Physical> {
        let physical = self
            .exported
            .get(name)
            .or_else(|| {
                self.histories
                    .get(name)
                    .map(|h| &h.pair[((self.frame + 1) % 2) as usize])
            })
            .ok_or_else(|| {
                GraphError::Readback(format!(
                    "`{name}` is neither an exported nor a history resource of the last frame"
                ))
            })?
            .clone();
        self.blocking_waits += 1;
        Ok(physical)
    }

    /// Lets finished GPU work report back (map callbacks), without waiting.
    fn poll(&mut self) -> Result<()> {
        self.gpu
            .device
            .poll(wgpu::PollType::Poll)
            .map_err(|e| GraphError::Readback(e.to_string()))?;
        self.collect();
        Ok(())
    }

    fn collect(&mut self) {
        self.readbacks.collect(self.frame);
        if let Some(ts) = &mut self.timestamps {
            let period = self.gpu.queue.get_timestamp_period() as f64;
            for t in ts.harvest(period) {
                if let Some(stats) = self.last_stats.as_mut().filter(|s| s.frame == t.frame) {
                    for (p, (_, us)) in stats.passes.iter_mut().zip(&t.passes) {
                        p.gpu_us = Some(*us);
                    }
                    stats.gpu_total_us = Some(t.total_us);
                }
                self.timings.push_back(t);
                if self.timings.len() > 256 {
                    self.timings.pop_front();
                }
            }
        }
    }

    /// The oldest frame's bytes of readback `name` that are ready: copied at least its
    /// latency frames ago and finished by the GPU. Never waits; `None` until then.
    pub fn take_readback(&mut self, name: &str) -> Result<Option<Readback>> {
        self.poll()?;
        if !self.readbacks.known(name) {
            return Err(GraphError::Readback(format!(
                "no readback `{name}` has run; declare it with GraphBuilder::readback and execute a frame"
            )));
        }
        Ok(self.readbacks.take(name))
    }

    /// Copies dropped because the GPU was further behind than the readback rings hold.
    pub fn readbacks_dropped(&self) -> u64 {
        self.readbacks.dropped() + self.timestamps.as_ref().map_or(0, |t| t.dropped())
    }

    /// GPU timings of the frames the GPU has finished since the last call, oldest first.
    /// Never waits.
    pub fn take_gpu_timings(&mut self) -> Result<Vec<GpuTimings>> {
        self.poll()?;
        Ok(self.timings.drain(..).collect())
    }

    /// Waits until the GPU has finished every submitted frame, and returns the last
    /// frame's statistics with its GPU timings filled in; every frame's readbacks become
    /// takeable, whatever their latency. For tools and tests that need
    /// this frame's results now; a render loop never calls it.
    pub fn finish(&mut self) -> Result<Option<FrameStats>> {
        self.blocking_waits += 1;
        self.gpu
            .device
            .poll(wgpu::PollType::wait_indefinitely())
            .map_err(|e| GraphError::Readback(e.to_string()))?;
        // Everything submitted has finished: the latency that keeps a render loop from
        // waiting has no purpose any more, so every frame's readbacks are released.
        self.readbacks.collect(u64::MAX);
        self.collect();
        Ok(self.last_stats.clone())
    }

    /// Runs one frame of a graph whose passes read no per-frame inputs.
    pub fn execute(&mut self, graph: &CompiledGraph, imports: &Imports) -> Result<FrameStats> {
        self.execute_frame(graph, imports, &FrameData::default())
    }

    /// Runs one frame with its inputs (view, instance count, …): passes read them in
    /// `record`, so nothing is rebuilt or recompiled when they change. Returns without
    /// waiting for the GPU.
    pub fn execute_frame(
        &mut self,
        graph: &CompiledGraph,
        imports: &Imports,
        frame_data: &FrameData,
    ) -> Result<FrameStats> {
        let frame_start = Instant::now();
        let plan = &graph.plan;
        let missing = plan.enabled_features - self.gpu.features;
        if !missing.is_empty() {
            return Err(GraphError::MissingFeature {
                pass: "(graph)".into(),
                stage: "(device)".into(),
                features: crate::compile::feature_names(missing),
                instead: "open the device with the plan's `enabled_features` (GpuAdapter::open)"
                    .into(),
            });
        }
        for &p in &plan.order {
            if let Some(input) = plan.passes[p]
                .frame_inputs
                .iter()
                .find(|i| frame_data.get(i).is_none())
            {
                return Err(GraphError::MissingFrameInput {
                    pass: plan.passes[p].name.clone(),
                    input: input.clone(),
                });
            }
        }
        self.poll()?;
        let frame = self.frame;
        self.pool.begin_frame(frame);
        self.programs.begin_frame(frame);
        self.views.begin_frame(frame);
        let pipelines_before = self.programs.pipelines_created;
        let bind_groups_before = self.programs.bind_groups_created;
        let (physical, history_valid) = self.resolve_resources(graph, imports)?;

        let timing = self.gpu_timing && self.gpu.features.contains(wgpu::Features::TIMESTAMP_QUERY);
        if timing
            && self
                .timestamps
                .as_ref()
                .is_none_or(|t| t.capacity() < plan.order.len() as u32 * 2)
        {
            let inside = self
                .gpu
                .features
                .contains(wgpu::Features::TIMESTAMP_QUERY_INSIDE_ENCODERS);
            self.timestamps = Some(Timestamps::new(
                &self.gpu.device,
                plan.order.len() as u32,
                inside,
            ));
        }

        let device = &self.gpu.device;
        let mut command_buffers = Vec::with_capacity(plan.order.len() + 1);
        let mut timings = Vec::with_capacity(plan.order.len());
        let mut shared = self.one_command_buffer.then(|| {
            device.create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("meshlight frame"),
            })
        });
        for (i, &p) in plan.order.iter().enumerate() {
            let node = &graph.passes[p];
            let t0 = Instant::now();
            let scope = device.push_error_scope(wgpu::ErrorFilter::Validation);
            let mut own = shared.is_none().then(|| {
                device.create_command_encoder(&wgpu::CommandEncoderDescriptor {
                    label: Some(&node.name),
                })
            });
            let encoder = match (own.as_mut(), shared.as_mut()) {
                (Some(e), _) | (None, Some(e)) => e,
                (None, None) => unreachable!("one of the two encoders exists"),
            };
            let ts = if timing {
                self.timestamps.as_ref()
            } else {
                None
            };
            if let Some(ts) = ts {
                ts.write(encoder, 2 * i as u32);
            }
            let mut ctx = RecordContext {
                device,
                queue: &self.gpu.queue,
                features: self.gpu.features,
                encoder,
                node,
                setup: &graph.setups[p],
                pass_index: p,
                plan,
                physical: &physical,
                programs: &mut self.programs,
                views: &mut self.views,
                readbacks: &mut self.readbacks,
                frame_data,
                frame_index: frame,
                history_valid: &history_valid,
            };
            let recorded = node.pass.record(&mut ctx);
            if let Some(ts) = ts {
                ts.write(ctx.encoder, 2 * i as u32 + 1);
            }
            let cb = own.map(wgpu::CommandEncoder::finish);
            let failed = match pollster::block_on(scope.pop()) {
                Some(e) => Err(GraphError::Validation {
                    pass: node.name.clone(),
                    message: e.to_string(),
                }),
                None => recorded,
            };
            if let Err(e) = failed {
                self.readbacks.abandon();
                return Err(e);
            }
            command_buffers.extend(cb);
            timings.push(PassTiming {
                name: node.name.clone(),
                gpu_us: None,
                cpu_record_us: t0.elapsed().as_secs_f64() * 1e6,
            });
        }

        if let Some(encoder) = shared {
            let scope = device.push_error_scope(wgpu::ErrorFilter::Validation);
            let cb = encoder.finish();
            if let Some(e) = pollster::block_on(scope.pop()) {
                self.readbacks.abandon();
                return Err(GraphError::Validation {
                    pass: "(the frame's command buffer)".into(),
                    message: e.to_string(),
                });
            }
            command_buffers.push(cb);
        }
        if let Some(ts) = self.timestamps.as_mut().filter(|_| timing) {
            let mut enc = device.create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("meshlight timestamps"),
            });
            let names = plan
                .order
                .iter()
                .map(|&p| plan.passes[p].name.clone())
                .collect();
            ts.resolve(device, &mut enc, frame, names);
            command_buffers.push(enc.finish());
        }
        self.programs.uniforms.flush(&self.gpu.queue);
        let scope = device.push_error_scope(wgpu::ErrorFilter::Validation);
        let submit_start = Instant::now();
        self.gpu.queue.submit(command_buffers);
        let cpu_submit_us = submit_start.elapsed().as_secs_f64() * 1e6;
        if let Some(e) = pollster::block_on(scope.pop()) {
            self.readbacks.abandon();
            if let Some(ts) = &mut self.timestamps {
                ts.abandon(frame);
            }
            return Err(GraphError::Validation {
                pass: "(submit)".into(),
                message: e.to_string(),
            });
        }
        self.readbacks.submitted();
        if let Some(ts) = &mut self.timestamps {
            ts.submitted();
        }

        // Keep this frame's exported transients readable until the next frame.
        self.exported.clear();
        for (r, res) in plan.resources.iter().enumerate() {
            if res.info.kind == ResourceKind::Exported
                && let Some(ph) = &physical[r]
            {
                self.exported.insert(res.info.name.clone(), ph.clone());
            }
        }
        let frames_in_flight = self
            .timestamps
            .as_ref()
            .filter(|_| timing)
            .map_or(0, |t| t.in_flight())
            .max(self.readbacks.in_flight()) as u32;
        self.frame += 1;
        let stats = FrameStats {
            frame,
            passes: timings,
            cpu_frame_us: frame_start.elapsed().as_secs_f64() * 1e6,
            cpu_submit_us,
            gpu_total_us: None,
            gpu_latest: self.timings.back().cloned(),
            frames_in_flight,
            bytes_with_reuse: plan.bytes_with_reuse,
            bytes_without_reuse: plan.bytes_without_reuse,
            pool_bytes_held: self.pool.held_bytes(),
            allocations: self.pool.allocations,
            pipelines_created: self.programs.pipelines_created - pipelines_before,
            bind_groups_created: self.programs.bind_groups_created - bind_groups_before,
        };
        self.last_stats = Some(stats.clone());
        Ok(stats)
    }

    /// The physical object behind every resource this frame, and per resource whether a
    /// history half holds last frame's contents. Allocations run inside error scopes, so a
    /// failure is an error naming the resource, not a panic.
    #[allow(clippy::type_complexity)]
    fn resolve_resources(
        &mut self,
        graph: &CompiledGraph,
        imports: &Imports,
    ) -> Result<(Vec<Option<Physical>>, Vec<bool>)> {
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
        Ok((physical, history_valid))
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
            if !buffer.usage().contains(u) {
                return mismatch(format!(
                    "declared usage {u:?}, the buffer has {:?}",
                    buffer.usage()
                ));
            }
            Ok(())
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
                return mismatch(format!(
                    "declared {:?} {}x{} with {} mips and {} layers, the texture is {:?} {}x{} with {} mips and {} layers",
                    t.format,
                    t.width,
                    t.height,
                    t.mip_levels,
                    t.layers,
                    texture.format(),
                    texture.width(),
                    texture.height(),
                    texture.mip_level_count(),
                    texture.depth_or_array_layers()
                ));
            }
            if !texture.usage().contains(u) {
                return mismatch(format!(
                    "declared usage {u:?}, the texture has {:?}",
                    texture.usage()
                ));
            }
            Ok(())
        }
        _ => mismatch("a buffer was declared and a texture given, or the reverse".into()),
    }
}
