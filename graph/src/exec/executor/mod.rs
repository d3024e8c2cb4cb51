//! Runs compiled graphs frame after frame: allocates pooled resources, swaps history,
//! records the plan's batches into one command encoder (each compute batch into one
//! shared compute pass), submits one command buffer, and reports timings per batch or
//! per pass. Nothing here waits for the GPU: timestamps and readbacks come back through
//! rings of map-read buffers frames later.
//!
//! One frame is four steps, each in a module of its own: the graph's programs built for
//! the device once (`exec::prepare`), the frame's resources (`resources`: pool, imports,
//! history), the batch loop (`batches`) under a frame timer (`exec::timing`), and the
//! submit with its statistics (here).

mod batches;
mod resources;
mod stats;

pub use resources::Imports;
pub use stats::{BatchStats, FrameStats, PassTiming};

use crate::compile::CompiledGraph;
use crate::error::{GraphError, Result};
use crate::exec::context::GpuContext;
use crate::exec::timing::{FrameTimer, GpuTimings, Timestamps, TimingMode};
use crate::record::fill::Fill;
use crate::record::frame::FrameData;
use crate::record::physical::{Physical, PhysicalPool};
use crate::record::programs::Programs;
use crate::record::readback::{Readback, Readbacks};
use crate::record::shared::SharedPass;
use crate::record::views::ViewCache;
use crate::resource::ResourceKind;
use batches::FrameRecord;
use resources::{FrameResources, HistoryEntry};
use std::collections::{HashMap, VecDeque};
use std::time::Instant;

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

/// Runs compiled graphs frame after frame on one device: allocates and pools the physical
/// resources, caches programs and bind groups, times and reads back.
///
/// A frame that copies a caller's texture into a buffer the graph owns, on the first
/// adapter found (lavapipe where there is no GPU: `scripts/ensure-vulkan.sh` installs it):
///
/// ```
/// use meshlight_graph::synthetic::CopyTextureToBuffer;
/// use meshlight_graph::*;
/// use wgpu::util::DeviceExt;
///
/// # fn main() -> Result<()> {
/// // A row of 64 RGBA8 texels is 256 bytes, the alignment texture copies want.
/// let (width, height) = (64, 2);
/// let format = wgpu::TextureFormat::Rgba8Unorm;
/// let usage = wgpu::TextureUsages::COPY_SRC | wgpu::TextureUsages::COPY_DST;
///
/// let mut g = GraphBuilder::new();
/// g.import_texture("picture", TextureDesc::d2(format, width, height), usage);
/// let copy = g.create_buffer("copy", BufferDesc::array(Element::U32, (width * height) as u64));
/// g.export(copy);
/// let pass = CopyTextureToBuffer { format, width, height };
/// let bind = Bindings::new().bind_named("texture", "picture").bind("buffer", copy);
/// g.add_pass("copy", pass, bind)?;
///
/// let gpu = GpuContext::with_available(wgpu::Features::empty())?;
/// let compiled = g.compile(&CompileOptions::for_gpu(&gpu))?;
/// let mut executor = Executor::new(gpu);
/// let texels: Vec<u8> = (0..width * height * 4).map(|i| i as u8).collect();
/// let picture = executor.device().create_texture_with_data(
///     executor.queue(),
///     &wgpu::TextureDescriptor {
///         label: Some("picture"),
///         size: wgpu::Extent3d { width, height, depth_or_array_layers: 1 },
///         mip_level_count: 1,
///         sample_count: 1,
///         dimension: wgpu::TextureDimension::D2,
///         format,
///         usage,
///         view_formats: &[],
///     },
///     wgpu::util::TextureDataOrder::LayerMajor,
///     &texels,
/// );
/// executor.execute(&compiled, &Imports::new().texture("picture", &picture))?;
/// // Waits for the GPU: for tests and tools; frames read back through the graph.
/// assert_eq!(executor.read_buffer("copy")?, texels);
/// # Ok(())
/// # }
/// ```
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

    /// Turns checked mode on or off, whatever the build profile and [`CHECKED_ENV`] say:
    /// checked, a frame that fails validation is recorded again pass by pass to name
    /// the failing pass (on by default in debug builds, where the cost does not matter).
    pub fn set_checked(&mut self, on: bool) {
        self.checked = on;
    }

    /// Whether checked mode is on (see [`Self::set_checked`]).
    pub fn checked(&self) -> bool {
        self.checked
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

    /// Whether readback `name` has run in some frame, so [`Self::take_readback`] knows it.
    /// A readback whose pass every frame so far left out has not.
    pub fn readback_has_run(&self, name: &str) -> bool {
        self.readbacks.known(name)
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

    /// Builds every program `graph`'s passes declared (shader modules, bind-group
    /// layouts, pipelines) on this executor's device, so that a shader that does not
    /// match its slots, or a pipeline the device refuses, is an error naming the pass
    /// before any frame. The first frame of a graph prepares it when this was not
    /// called; a second call for the same graph does nothing.
    pub fn prepare(&mut self, graph: &CompiledGraph) -> Result<()> {
        crate::exec::prepare::prepare(&mut self.programs, &self.gpu, graph)
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
        profiling::scope!("meshlight::execute_frame");
        let frame_start = Instant::now();
        let plan = &graph.plan;
        self.check_inputs(graph, frame_data)?;
        self.poll()?;
        let frame = self.frame;
        self.pool.begin_frame(frame);
        self.programs.begin_frame(frame);
        self.views.begin_frame(frame);
        let pipelines_before = self.programs.pipelines_created;
        let bind_groups_before = self.programs.bind_groups_created;
        self.prepare(graph)?;
        let resources = self.resolve_resources(graph, imports)?;
        let (mode, batching) = self.start_timer(graph);

        let frame_scope = self
            .gpu
            .device
            .push_error_scope(wgpu::ErrorFilter::Validation);
        let mut shared = std::mem::take(&mut self.shared);
        shared.unplanned.clear();
        shared.opened = 0;
        let timer = FrameTimer::new(mode, batching, self.timestamps.as_ref());
        let device = &self.gpu.device;
        let mut recorder = FrameRecord {
            gpu: &self.gpu,
            graph,
            physical: &resources.physical,
            history_valid: &resources.history_valid,
            frame_data,
            frame,
            fill: self.fill.get_or_insert_with(|| Fill::new(device)),
            programs: &mut self.programs,
            views: &mut self.views,
            readbacks: &mut self.readbacks,
        };
        let recorded = {
            profiling::scope!("meshlight::record batches");
            recorder.record_batches(&timer, &mut shared, self.checked, self.one_command_buffer)
        };
        let unplanned_splits = shared.unplanned.len() as u32;
        let compute_passes = shared.opened;
        self.shared = shared;
        let batches::Recorded {
            mut command_buffers,
            mut encoder,
            passes,
            batches,
            failed,
        } = recorded;
        let timed = mode != TimingMode::Off;
        if let Some(ts) = self
            .timestamps
            .as_mut()
            .filter(|_| timed && failed.is_none())
        {
            let names = match mode {
                TimingMode::Frame => batches.iter().map(|b| b.label.clone()).collect(),
                // The passes recorded, in order: skipped ones have no stamps.
                _ => passes.iter().map(|p| p.name.clone()).collect(),
            };
            ts.resolve(&self.gpu.device, &mut encoder, frame, mode, names);
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
                self.name_failing_pass(graph, &resources, frame_data)
            } else {
                None
            };
            return Err(named.unwrap_or(GraphError::FrameValidation {
                when: "while recording the frame",
                message: e.to_string(),
            }));
        }
        let cpu_submit_us = self.submit(frame, command_buffers)?;
        self.keep_exported(graph, &resources);
        let frames_in_flight = self
            .timestamps
            .as_ref()
            .filter(|_| timed)
            .map_or(0, |t| t.in_flight())
            .max(self.readbacks.in_flight()) as u32;
        self.frame += 1;
        let stats = FrameStats {
            frame,
            passes,
            timing: mode,
            batches,
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

    /// The device has the plan's features, and the frame carries every input a pass
    /// declared.
    fn check_inputs(&self, graph: &CompiledGraph, frame_data: &FrameData) -> Result<()> {
        let plan = &graph.plan;
        let missing = plan.enabled_features - self.gpu.features;
        if !missing.is_empty() {
            return Err(GraphError::DeviceLacksFeatures {
                features: crate::names::feature_names(missing),
                instead: "open the device with the plan's `enabled_features` (GpuAdapter::open)"
                    .into(),
            });
        }
        if let Some(unknown) = frame_data.skipped().find(|n| plan.pass_index(n).is_none()) {
            return Err(GraphError::Setting {
                setting: "FrameData::skip".into(),
                message: format!(
                    "the frame leaves out a pass `{unknown}`, which the graph does not have; name one of its passes"
                ),
            });
        }
        for &p in &plan.order {
            if frame_data.skips(&plan.passes[p].name) {
                continue;
            }
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
        Ok(())
    }

    /// The frame's timing mode and whether its batches share compute passes under it;
    /// makes room for its timestamps.
    fn start_timer(&mut self, graph: &CompiledGraph) -> (TimingMode, bool) {
        let plan = &graph.plan;
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
        (mode, batching)
    }

    /// Writes the frame's uniforms and submits its command buffers; returns the CPU time
    /// of the submit. A validation error at submit abandons the frame's readbacks and
    /// timestamps.
    fn submit(&mut self, frame: u64, command_buffers: Vec<wgpu::CommandBuffer>) -> Result<f64> {
        profiling::scope!("meshlight::submit");
        self.programs.uniforms.flush(&self.gpu.queue);
        let scope = self
            .gpu
            .device
            .push_error_scope(wgpu::ErrorFilter::Validation);
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
        Ok(cpu_submit_us)
    }

    /// Keeps this frame's exported transients readable until the next frame.
    fn keep_exported(&mut self, graph: &CompiledGraph, resources: &FrameResources) {
        self.exported.clear();
        for (r, res) in graph.plan.resources.iter().enumerate() {
            if res.info.kind == ResourceKind::Exported
                && let Some(ph) = &resources.physical[r]
            {
                self.exported.insert(res.info.name.clone(), ph.clone());
            }
        }
    }

    /// Records the frame again, unbatched, each pass into an encoder of its own inside an
    /// error scope, and submits nothing: the first pass whose commands fail validation is
    /// the one to name. Only after a frame failed, so the good path pays nothing for it.
    fn name_failing_pass(
        &mut self,
        graph: &CompiledGraph,
        resources: &FrameResources,
        frame_data: &FrameData,
    ) -> Option<GraphError> {
        let plan = &graph.plan;
        let device = &self.gpu.device;
        self.programs.uniforms.begin_frame();
        let mut recorder = FrameRecord {
            gpu: &self.gpu,
            graph,
            physical: &resources.physical,
            history_valid: &resources.history_valid,
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
}
