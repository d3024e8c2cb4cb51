//! GPU timestamp pairs, one per timed unit (a batch in `frame` mode, a pass in `passes`
//! mode), resolved every frame into a ring of map-read buffers and read frames later, so
//! timing never makes the CPU wait for the GPU.

use crate::record::ring::MapRing;
use crate::record::shared::{BatchStamps, SharedPass};
use serde::Serialize;
use std::collections::HashMap;

/// The environment variable that sets an executor's timing mode (`off`, `frame`, `passes`).
pub const TIMING_ENV: &str = "MESHLIGHT_TIMING";

/// What an executor times on the GPU.
///
/// A timestamp written at a compute-pass boundary is a bottom-of-pipe stamp after an
/// in-band query reset, so every pair serialises the GPU around it: `frame` pays that once
/// per batch, `passes` once per pass (about 7–9 µs of GPU time per pass on an H200), which
/// is why per-pass profiles come only from `passes` and frame times from `frame`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum TimingMode {
    /// No timestamps.
    Off,
    /// One pair per batch: the frame's GPU time and each batch's (the default).
    #[default]
    Frame,
    /// One pair per pass, for profiling. Where the adapter has
    /// `TIMESTAMP_QUERY_INSIDE_PASSES` the stamps go inside the batch's shared compute
    /// pass (`Executor::stamp_inside_passes`); elsewhere every pass gets a compute pass of
    /// its own with stamps around it.
    Passes,
}

impl TimingMode {
    /// `off`, `frame` or `passes` (the values of the timing environment variable).
    pub fn parse(s: &str) -> Option<Self> {
        match s.trim().to_ascii_lowercase().as_str() {
            "off" | "none" | "0" => Some(Self::Off),
            "frame" | "batch" | "batches" => Some(Self::Frame),
            "passes" | "pass" => Some(Self::Passes),
            _ => None,
        }
    }
    /// The mode's name, as [`crate::TIMING_ENV`] accepts it.
    pub fn name(self) -> &'static str {
        match self {
            Self::Off => "off",
            Self::Frame => "frame",
            Self::Passes => "passes",
        }
    }
    /// `MESHLIGHT_TIMING` when set to a known mode, else `frame`.
    pub fn from_env() -> Self {
        std::env::var(TIMING_ENV)
            .ok()
            .and_then(|s| Self::parse(&s))
            .unwrap_or_default()
    }
}

/// GPU time of each timed unit of one frame.
#[derive(Clone, Debug, Serialize)]
pub struct GpuTimings {
    /// The frame these timings belong to.
    pub frame: u64,
    /// The mode that produced these figures.
    pub mode: TimingMode,
    /// (unit, µs) in execution order: batches (`batch 2 (compute ×5)`, `batch 3 (encoder)`)
    /// in `frame` mode, pass names in `passes` mode.
    pub passes: Vec<(String, f64)>,
    /// Sum of the units' times.
    pub total_us: f64,
    /// From the first unit's start to the last one's end: the frame's GPU time, gaps
    /// between units included.
    pub frame_us: f64,
    /// Per pass, when its timestamps were written, in µs after the frame's first one: the
    /// span of a run of passes, gaps included, is `end of the last − start of the first`.
    pub intervals: Vec<[f64; 2]>,
}

pub(crate) struct Timestamps {
    pub query_set: wgpu::QuerySet,
    resolve: wgpu::Buffer,
    ring: MapRing,
    capacity: u32,
    /// True when timestamps may be written between passes on the encoder itself.
    inside_encoders: bool,
    /// Unit names and mode of frames whose timestamps are in flight.
    pending: HashMap<u64, (TimingMode, Vec<String>)>,
}

impl Timestamps {
    pub fn new(device: &wgpu::Device, units: u32, inside_encoders: bool) -> Self {
        let capacity = (units * 2).max(2);
        let bytes = capacity as u64 * 8;
        Self {
            query_set: device.create_query_set(&wgpu::QuerySetDescriptor {
                label: Some("meshlight pass timestamps"),
                ty: wgpu::QueryType::Timestamp,
                count: capacity,
            }),
            resolve: device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("meshlight timestamp resolve"),
                size: bytes,
                usage: wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC,
                mapped_at_creation: false,
            }),
            ring: MapRing::new("meshlight timestamp readback"),
            capacity,
            inside_encoders,
            pending: HashMap::new(),
        }
    }

    pub fn capacity(&self) -> u32 {
        self.capacity
    }

    /// Writes timestamp `index`. Without encoder-level timestamps an empty compute pass
    /// carries the write, which every timestamp-capable adapter supports.
    pub fn write(&self, encoder: &mut wgpu::CommandEncoder, index: u32) {
        if self.inside_encoders {
            encoder.write_timestamp(&self.query_set, index);
        } else {
            encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("timestamp"),
                timestamp_writes: Some(wgpu::ComputePassTimestampWrites {
                    query_set: &self.query_set,
                    beginning_of_pass_write_index: Some(index),
                    end_of_pass_write_index: None,
                }),
            });
        }
    }

    /// Resolves this frame's timestamps and copies them into a ring buffer. When every
    /// ring buffer is still in flight the frame's timings are dropped, not waited for.
    pub fn resolve(
        &mut self,
        device: &wgpu::Device,
        encoder: &mut wgpu::CommandEncoder,
        frame: u64,
        mode: TimingMode,
        passes: Vec<String>,
    ) {
        let count = passes.len() as u32 * 2;
        if count == 0 {
            return;
        }
        let bytes = count as u64 * 8;
        encoder.resolve_query_set(&self.query_set, 0..count, &self.resolve, 0);
        if let Some(dst) = self.ring.acquire(device, bytes, frame) {
            encoder.copy_buffer_to_buffer(&self.resolve, 0, dst, 0, bytes);
            self.pending.insert(frame, (mode, passes));
        }
    }

    pub fn submitted(&mut self) {
        self.ring.submitted();
    }
    pub fn abandon(&mut self, frame: u64) {
        self.ring.abandon();
        self.pending.remove(&frame);
    }
    pub fn in_flight(&self) -> usize {
        self.ring.in_flight()
    }
    pub fn dropped(&self) -> u64 {
        self.ring.dropped
    }

    /// Timings of every frame whose timestamps the GPU has finished, oldest first.
    pub fn harvest(&mut self, period_ns: f64) -> Vec<GpuTimings> {
        self.ring
            .take_ready(u64::MAX)
            .into_iter()
            .filter_map(|(frame, bytes)| {
                let (mode, names) = self.pending.remove(&frame)?;
                // Mapped bytes carry no alignment guarantee for u64: copy rather than cast.
                let ticks: Vec<u64> = bytemuck::pod_collect_to_vec(&bytes);
                let passes: Vec<(String, f64)> = names
                    .into_iter()
                    .enumerate()
                    .map(|(i, name)| {
                        let us = ticks[2 * i + 1].saturating_sub(ticks[2 * i]) as f64 * period_ns
                            / 1000.0;
                        (name, us)
                    })
                    .collect();
                let total_us = passes.iter().map(|(_, us)| us).sum();
                let origin = ticks.first().copied().unwrap_or(0);
                let at = |t: u64| t.saturating_sub(origin) as f64 * period_ns / 1000.0;
                let intervals: Vec<[f64; 2]> = (0..passes.len())
                    .map(|i| [at(ticks[2 * i]), at(ticks[2 * i + 1])])
                    .collect();
                let frame_us = intervals.last().map_or(0.0, |l| l[1]);
                Some(GpuTimings {
                    frame,
                    mode,
                    passes,
                    total_us,
                    frame_us,
                    intervals,
                })
            })
            .collect()
    }
}

/// How one frame is timed: the mode in effect, whether batches share compute passes under
/// it, and the timestamps it writes. Made by the executor per frame; the batch loop asks
/// it where to stamp.
pub(crate) struct FrameTimer<'t> {
    /// The mode in effect (`off` where timing is switched off or the adapter has no
    /// timestamps).
    pub mode: TimingMode,
    /// Consecutive compute passes share a compute pass: per-pass stamps split every
    /// batch unless they can go inside the shared pass.
    pub batching: bool,
    /// The query set, when the frame is timed.
    stamps: Option<&'t Timestamps>,
}

impl<'t> FrameTimer<'t> {
    /// A timer for `mode` over `stamps`; `batching` as the executor decided it.
    pub fn new(mode: TimingMode, batching: bool, stamps: Option<&'t Timestamps>) -> Self {
        Self {
            mode,
            batching,
            stamps: stamps.filter(|_| mode != TimingMode::Off),
        }
    }

    /// The stamps a batch's shared compute pass writes at its two ends (`frame` mode).
    pub fn shared_batch(&self, b: usize) -> Option<BatchStamps> {
        self.batch_stamps().map(|t| BatchStamps {
            query_set: t.query_set.clone(),
            begin: Some(2 * b as u32),
            end: 2 * b as u32 + 1,
        })
    }

    /// Writes the stamp opening (or, with `end`, closing) batch `b` when it is recorded
    /// on the encoder (`frame` mode).
    pub fn batch_edge(&self, encoder: &mut wgpu::CommandEncoder, b: usize, end: bool) {
        if let Some(t) = self.batch_stamps() {
            t.write(encoder, 2 * b as u32 + u32::from(end));
        }
    }

    /// Writes the stamp opening (or closing) the pass at position `at` of the order
    /// (`passes` mode): inside the batch's shared compute pass when it is batched.
    pub fn pass_edge(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        shared: &mut SharedPass,
        batched: bool,
        at: u32,
        end: bool,
    ) {
        let Some(t) = self.stamps.filter(|_| self.mode == TimingMode::Passes) else {
            return;
        };
        let index = 2 * at + u32::from(end);
        if batched {
            shared.get(encoder).write_timestamp(&t.query_set, index);
        } else {
            t.write(encoder, index);
        }
    }

    fn batch_stamps(&self) -> Option<&'t Timestamps> {
        self.stamps.filter(|_| self.mode == TimingMode::Frame)
    }
}
