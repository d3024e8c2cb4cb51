//! Runs compiled graphs frame after frame: allocates pooled resources, swaps history,
//! records the plan's batches into one command encoder (each compute batch into one
//! shared compute pass), submits one command buffer, and reports timings per batch or
//! per pass. Nothing here waits for the GPU: timestamps and readbacks come back through
//! rings of map-read buffers frames later.

use crate::compile::CompiledGraph;
use crate::error::{GraphError, Result};
use crate::exec::context::GpuContext;
use crate::exec::timing::{GpuTimings, Timestamps, TimingMode};
use crate::record::RecordContext;
use crate::record::fill::Fill;
use crate::record::frame::FrameData;
use crate::record::physical::{self, Physical, PhysicalPool};
use crate::record::programs::Programs;
use crate::record::readback::{Readback, Readbacks};
use crate::record::shared::{BatchStamps, SharedPass};
use crate::record::views::ViewCache;
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

/// The environment variable that turns batched recording off (`off`, `0`, `false`).
pub const BATCHING_ENV: &str = "MESHLIGHT_BATCHING";
/// The environment variable that turns checked mode on (`1`, `on`) or off (`0`, `off`).
pub const CHECKED_ENV: &str = "MESHLIGHT_CHECKED";

fn env_switch(name: &str) -> Option<bool> {
    match std::env::var(name)
        .ok()?
        .trim()
        .to_ascii_lowercase()
        .as_str()
    {
        "0" | "off" | "false" | "no" => Some(false),
        "1" | "on" | "true" | "yes" => Some(true),
        _ => None,
    }
}

/// One pass's GPU time in a frame measured per pass.
#[derive(Clone, Debug, Serialize)]
pub struct PassTiming {
    /// The pass, by name.
    pub name: String,
    /// The plan's batch the pass ran in.
    pub batch: usize,
    /// GPU time between the pass's timestamps, in `passes` timing mode only; known once
    /// the GPU has finished the frame (see [`Executor::finish`]), `None` before, in other
    /// modes and on adapters without timestamps.
    pub gpu_us: Option<f64>,
    /// CPU time spent in the pass's `record`, including pipeline creation on first use.
    pub cpu_record_us: f64,
}

/// One batch of a frame (see [`crate::plan::Batch`]).
#[derive(Clone, Debug, Serialize)]
pub struct BatchStats {
    /// The batch's label, as [`crate::Batch::label`] writes it.
    pub label: String,
    /// Its passes, in order.
    pub passes: Vec<String>,
    /// GPU time between the batch's timestamps, in `frame` timing mode only, once known.
    pub gpu_us: Option<f64>,
}

/// What one executed frame cost and did: CPU times, batches, GPU timings when measured.
#[derive(Clone, Debug, Serialize)]
pub struct FrameStats {
    /// The frame's index, counting from 0 since the executor was made.
    pub frame: u64,
    /// Per pass, in plan order, with CPU record time and GPU time when measured.
    pub passes: Vec<PassTiming>,
    /// The timing mode this frame ran with: which of `gpu_us` (per pass or per batch) fill
    /// in.
    pub timing: TimingMode,
    /// Per batch, in plan order.
    pub batches: Vec<BatchStats>,
    /// wgpu compute passes the shared batches opened (one per compute batch, more when a
    /// batched pass took the encoder).
    pub compute_passes: u32,
    /// Batched passes that took the encoder this frame (an error in checked mode).
    pub unplanned_splits: u32,
    /// CPU time of the whole frame on the executor's side (it never waits for the GPU).
    pub cpu_frame_us: f64,
    /// The part of `cpu_frame_us` spent in `queue.submit` (mostly driver work).
    pub cpu_submit_us: f64,
    /// The part of `cpu_frame_us` spent in `CommandEncoder::finish`, where wgpu encodes
    /// what the passes recorded (its validation, barriers and the driver's commands).
    pub cpu_finish_us: f64,
    /// Sum of the timed units' GPU times (batches or passes), when known.
    pub gpu_total_us: Option<f64>,
    /// From the first timestamp to the last: the frame's GPU time, gaps included.
    pub gpu_frame_us: Option<f64>,
    /// The newest earlier frame whose GPU timings had come back when this one was recorded.
    pub gpu_latest: Option<GpuTimings>,
    /// Frames submitted whose timestamps the GPU had not yet delivered, this one included:
    /// above 1 means the CPU records ahead while the GPU works.
    pub frames_in_flight: u32,
    /// Transient bytes the plan needs with pool slots shared (what it allocates).
    pub bytes_with_reuse: u64,
    /// Transient bytes it would need with a resource each, to show what sharing saves.
    pub bytes_without_reuse: u64,
    /// Bytes the executor's pool holds, in use or kept for reuse.
    pub pool_bytes_held: u64,
    /// GPU resources created this frame (zero once a steady graph has warmed up).
    pub allocations: u32,
    /// Render and compute pipelines created this frame (zero once steady: they are cached).
    pub pipelines_created: u32,
    /// Bind groups created this frame (zero once steady: they are cached by what they
    /// bind).
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

/// Runs compiled graphs frame after frame on one device: allocates and pools the physical
/// resources, caches programs and bind groups, times and reads back.
pub struct Executor {
    /// The device the executor runs on; callers make imported resources and surfaces on it.
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
    /// What to time on the GPU where the adapter has timestamps (`MESHLIGHT_TIMING`,
    /// default `frame`).
    pub timing: TimingMode,
    /// False turns timing off whatever `timing` says (CPU-overhead runs).
    pub gpu_timing: bool,
    /// In `passes` timing mode, write the stamps inside the batch's shared compute pass
    /// where the adapter has `TIMESTAMP_QUERY_INSIDE_PASSES` (else every pass gets a
    /// compute pass of its own).
    pub stamp_inside_passes: bool,
    /// Record consecutive compute-only passes into one shared compute pass (the plan's
    /// batches). On unless `MESHLIGHT_BATCHING=off`; off records every pass into compute
    /// passes of its own, for comparing the two paths.
    pub batching: bool,
    /// Checked mode: a validation error is traced to the pass that caused it (the frame is
    /// recorded again, a pass per encoder and error scope, and not submitted), and a
    /// batched pass that takes the encoder is an error. On in debug builds, or by
    /// `MESHLIGHT_CHECKED`. Unchecked, the frame costs one error scope and an error names
    /// the frame.
    pub checked: bool,
    /// One command buffer per frame (the default); false gives each batch its own, to
    /// measure what command-buffer boundaries cost.
    pub one_command_buffer: bool,
    shared: SharedPass,
    fill: Option<Fill>,
}

impl Executor {
    /// An executor on `gpu`; the environment variables of this crate set its checked,
    /// batching and timing modes.
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
            timing: TimingMode::from_env(),
            gpu_timing: true,
            stamp_inside_passes: true,
            batching: env_switch(BATCHING_ENV).unwrap_or(true),
            checked: env_switch(CHECKED_ENV).unwrap_or(cfg!(debug_assertions)),
            one_command_buffer: true,
            shared: SharedPass::default(),
            fill: None,
        }
    }

    /// The device, to create imported resources on.
    pub fn device(&self) -> &wgpu::Device {
        &self.gpu.device
    }
    /// The queue, to upload to imported resources before a frame.
    pub fn queue(&self) -> &wgpu::Queue {
        &self.gpu.queue
    }
    /// The timing mode frames run with: `timing`, or `Off` where timing is switched off
    /// or the adapter has no timestamps.
    pub fn timing_mode(&self) -> TimingMode {
        if self.gpu_timing && self.gpu.features.contains(wgpu::Features::TIMESTAMP_QUERY) {
            self.timing
        } else {
            TimingMode::Off
        }
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
                    match t.mode {
                        TimingMode::Passes => {
                            for (p, (_, us)) in stats.passes.iter_mut().zip(&t.passes) {
                                p.gpu_us = Some(*us);
                            }
                        }
                        _ => {
                            for (b, (_, us)) in stats.batches.iter_mut().zip(&t.passes) {
                                b.gpu_us = Some(*us);
                            }
                        }
                    }
                    stats.gpu_total_us = Some(t.total_us);
                    stats.gpu_frame_us = Some(t.frame_us);
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
            return Err(GraphError::DeviceLacksFeatures {
                features: crate::names::feature_names(missing),
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

        let mode = self.timing_mode();
        let inside_passes = self.stamp_inside_passes
            && self
                .gpu
                .features
                .contains(wgpu::Features::TIMESTAMP_QUERY_INSIDE_PASSES);
        // Per-pass stamps split every batch unless they can go inside the shared pass.
        let batching = self.batching && (mode != TimingMode::Passes || inside_passes);
        let units = match mode {
            TimingMode::Off => 0,
            TimingMode::Frame => plan.batches.len(),
            TimingMode::Passes => plan.order.len(),
        } as u32;
        if units > 0
            && self
                .timestamps
                .as_ref()
                .is_none_or(|t| t.capacity() < units * 2)
        {
            let inside = self
                .gpu
                .features
                .contains(wgpu::Features::TIMESTAMP_QUERY_INSIDE_ENCODERS);
            self.timestamps = Some(Timestamps::new(&self.gpu.device, units, inside));
        }

        let device = &self.gpu.device;
        let frame_scope = device.push_error_scope(wgpu::ErrorFilter::Validation);
        let mut command_buffers = Vec::with_capacity(2);
        let mut timings = Vec::with_capacity(plan.order.len());
        let mut batch_stats = Vec::with_capacity(plan.batches.len());
        let new_encoder = || {
            device.create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("meshlight frame"),
            })
        };
        let mut encoder = new_encoder();
        let mut shared = std::mem::take(&mut self.shared);
        shared.unplanned.clear();
        shared.opened = 0;
        let ts = self.timestamps.as_ref().filter(|_| mode != TimingMode::Off);
        let mut recorder = FrameRecord {
            gpu: &self.gpu,
            graph,
            physical: &physical,
            history_valid: &history_valid,
            frame_data,
            frame,
            fill: self.fill.get_or_insert_with(|| Fill::new(device)),
            programs: &mut self.programs,
            views: &mut self.views,
            readbacks: &mut self.readbacks,
        };
        let mut at = 0;
        let mut failed = None;
        'batches: for (b, batch) in plan.batches.iter().enumerate() {
            let batched = batching && batch.compute;
            let label = batch.label(b);
            let batch_stamps = ts.filter(|_| mode == TimingMode::Frame);
            if batched {
                shared.begin_batch(
                    label.clone(),
                    batch_stamps.map(|t| BatchStamps {
                        query_set: t.query_set.clone(),
                        begin: Some(2 * b as u32),
                        end: 2 * b as u32 + 1,
                    }),
                );
            } else if let Some(t) = batch_stamps {
                t.write(&mut encoder, 2 * b as u32);
            }
            for &p in &batch.passes {
                let node = &graph.passes[p];
                let t0 = Instant::now();
                let pass_stamps = ts.filter(|_| mode == TimingMode::Passes);
                if batched {
                    shared.enter(&mut encoder, &node.name);
                    if let Some(t) = pass_stamps {
                        shared
                            .get(&mut encoder)
                            .write_timestamp(&t.query_set, 2 * at);
                    }
                } else if let Some(t) = pass_stamps {
                    t.write(&mut encoder, 2 * at);
                }
                let splits_before = shared.unplanned.len();
                let recorded = recorder.record(p, &mut encoder, &mut shared, batched);
                if batched {
                    if let Some(t) = pass_stamps {
                        shared
                            .get(&mut encoder)
                            .write_timestamp(&t.query_set, 2 * at + 1);
                    }
                    shared.leave();
                } else if let Some(t) = pass_stamps {
                    t.write(&mut encoder, 2 * at + 1);
                }
                let split = shared.unplanned.get(splits_before).cloned();
                let recorded = match (recorded, split) {
                    (Err(e), _) => Err(e),
                    (Ok(()), Some(u)) if self.checked => Err(GraphError::Record {
                        pass: u.pass,
                        message: format!(
                            "called {} inside a compute batch, which ended the batch's compute pass; declare it in setup with SetupContext::needs_encoder",
                            u.what
                        ),
                    }),
                    (Ok(()), _) => Ok(()),
                };
                if let Err(e) = recorded {
                    failed = Some(e);
                    break 'batches;
                }
                timings.push(PassTiming {
                    name: node.name.clone(),
                    batch: b,
                    gpu_us: None,
                    cpu_record_us: t0.elapsed().as_secs_f64() * 1e6,
                });
                at += 1;
            }
            if batched {
                shared.end_batch();
            } else if let Some(t) = batch_stamps {
                t.write(&mut encoder, 2 * b as u32 + 1);
            }
            batch_stats.push(BatchStats {
                label,
                passes: batch
                    .passes
                    .iter()
                    .map(|&p| plan.passes[p].name.clone())
                    .collect(),
                gpu_us: None,
            });
            if !self.one_command_buffer && b + 1 < plan.batches.len() {
                let done = std::mem::replace(&mut encoder, new_encoder());
                command_buffers.push(done.finish());
            }
        }
        shared.end_batch();
        let unplanned_splits = shared.unplanned.len() as u32;
        let compute_passes = shared.opened;
        self.shared = shared;
        if let Some(ts) = self
            .timestamps
            .as_mut()
            .filter(|_| units > 0 && failed.is_none())
        {
            let names = match mode {
                TimingMode::Frame => batch_stats.iter().map(|b| b.label.clone()).collect(),
                _ => plan
                    .order
                    .iter()
                    .map(|&p| plan.passes[p].name.clone())
                    .collect(),
            };
            ts.resolve(device, &mut encoder, frame, mode, names);
        }
        let finish_start = Instant::now();
        command_buffers.push(encoder.finish());
        let cpu_finish_us = finish_start.elapsed().as_secs_f64() * 1e6;
        let invalid = pollster::block_on(frame_scope.pop());
        if let Some(e) = failed {
            self.readbacks.abandon();
            return Err(e);
        }
        if let Some(e) = invalid {
            self.readbacks.abandon();
            if let Some(ts) = &mut self.timestamps {
                ts.abandon(frame);
            }
            let named = if self.checked {
                self.name_failing_pass(graph, &physical, &history_valid, frame_data)
            } else {
                None
            };
            return Err(named.unwrap_or(GraphError::FrameValidation {
                when: "while recording the frame",
                message: e.to_string(),
            }));
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
            return Err(GraphError::FrameValidation {
                when: "at submit",
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
            .filter(|_| units > 0)
            .map_or(0, |t| t.in_flight())
            .max(self.readbacks.in_flight()) as u32;
        self.frame += 1;
        let stats = FrameStats {
            frame,
            passes: timings,
            timing: mode,
            batches: batch_stats,
            compute_passes,
            unplanned_splits,
            cpu_frame_us: frame_start.elapsed().as_secs_f64() * 1e6,
            cpu_submit_us,
            cpu_finish_us,
            gpu_total_us: None,
            gpu_frame_us: None,
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

    /// Records the frame again, unbatched, each pass into an encoder of its own inside an
    /// error scope, and submits nothing: the first pass whose commands fail validation is
    /// the one to name. Only after a frame failed, so the good path pays nothing for it.
    fn name_failing_pass(
        &mut self,
        graph: &CompiledGraph,
        physical: &[Option<Physical>],
        history_valid: &[bool],
        frame_data: &FrameData,
    ) -> Option<GraphError> {
        let plan = &graph.plan;
        let device = &self.gpu.device;
        self.programs.uniforms.begin_frame();
        let mut recorder = FrameRecord {
            gpu: &self.gpu,
            graph,
            physical,
            history_valid,
            frame_data,
            frame: self.frame,
            fill: self.fill.get_or_insert_with(|| Fill::new(device)),
            programs: &mut self.programs,
            views: &mut self.views,
            readbacks: &mut self.readbacks,
        };
        let mut shared = SharedPass::default();
        let mut found = None;
        for &p in &plan.order {
            let node = &graph.passes[p];
            let scope = device.push_error_scope(wgpu::ErrorFilter::Validation);
            let mut encoder = device.create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some(&node.name),
            });
            let recorded = recorder.record(p, &mut encoder, &mut shared, false);
            drop(encoder.finish());
            let invalid = pollster::block_on(scope.pop());
            if let Some(e) = invalid {
                found = Some(GraphError::Validation {
                    pass: node.name.clone(),
                    message: e.to_string(),
                });
                break;
            }
            if recorded.is_err() {
                break;
            }
        }
        self.readbacks.abandon();
        found
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

/// What the passes of one frame record against: the frame's resources and inputs, and
/// the executor's caches, lent to one pass at a time by [`FrameRecord::record`].
struct FrameRecord<'f> {
    gpu: &'f GpuContext,
    graph: &'f CompiledGraph,
    physical: &'f [Option<Physical>],
    history_valid: &'f [bool],
    frame_data: &'f FrameData,
    frame: u64,
    fill: &'f Fill,
    programs: &'f mut Programs,
    views: &'f mut ViewCache,
    readbacks: &'f mut Readbacks,
}

impl FrameRecord<'_> {
    /// Records pass `p` into `encoder`: into `shared`'s compute pass when `batched`.
    fn record(
        &mut self,
        p: usize,
        encoder: &mut wgpu::CommandEncoder,
        shared: &mut SharedPass,
        batched: bool,
    ) -> Result<()> {
        // A pass skipped on this adapter has nothing to record.
        if self.graph.plan.passes[p].skipped.is_some() {
            return Ok(());
        }
        let node = &self.graph.passes[p];
        let mut ctx = RecordContext {
            device: &self.gpu.device,
            queue: &self.gpu.queue,
            features: self.gpu.features,
            encoder,
            name: &node.name,
            contract: &node.contract,
            stage_slots: &node.stage_slots,
            declared: &self.graph.setups[p].programs,
            pass_index: p,
            plan: &self.graph.plan,
            physical: self.physical,
            programs: self.programs,
            views: self.views,
            readbacks: self.readbacks,
            frame_data: self.frame_data,
            frame_index: self.frame,
            history_valid: self.history_valid,
            shared,
            batched,
            fill: self.fill,
            graph_id: self.graph.id,
        };
        node.pass.record(&mut ctx)
    }
}
