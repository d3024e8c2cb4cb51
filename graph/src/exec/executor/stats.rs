//! What one executed frame cost and did, as the executor reports it.

use crate::exec::timing::{GpuTimings, TimingMode};
use serde::Serialize;

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
