//! The batch loop: the plan's batches recorded into the frame's encoder, each compute
//! batch into one shared compute pass, with the timer's stamps around batches or passes.

use super::stats::{BatchStats, PassTiming};
use crate::compile::CompiledGraph;
use crate::error::{GraphError, Result};
use crate::exec::context::GpuContext;
use crate::exec::timing::FrameTimer;
use crate::record::RecordContext;
use crate::record::fill::Fill;
use crate::record::frame::FrameData;
use crate::record::physical::Physical;
use crate::record::programs::Programs;
use crate::record::readback::Readbacks;
use crate::record::shared::SharedPass;
use crate::record::views::ViewCache;
use std::time::Instant;

/// What recording a frame's batches left.
pub(super) struct Recorded {
    /// Finished command buffers (more than none only without one command buffer per
    /// frame).
    pub command_buffers: Vec<wgpu::CommandBuffer>,
    /// The encoder recorded into last, still open for the timestamps' resolve.
    pub encoder: wgpu::CommandEncoder,
    /// Per pass recorded, in order.
    pub passes: Vec<PassTiming>,
    /// Per batch, in order.
    pub batches: Vec<BatchStats>,
    /// The first error a pass reported; recording stopped there.
    pub failed: Option<GraphError>,
}

/// What the passes of one frame record against: the frame's resources and inputs, and
/// the executor's caches, lent to one pass at a time by [`FrameRecord::record`].
pub(super) struct FrameRecord<'f> {
    pub gpu: &'f GpuContext,
    pub graph: &'f CompiledGraph,
    pub physical: &'f [Option<Physical>],
    pub history_valid: &'f [bool],
    pub frame_data: &'f FrameData,
    pub frame: u64,
    pub fill: &'f Fill,
    pub programs: &'f mut Programs,
    pub views: &'f mut ViewCache,
    pub readbacks: &'f mut Readbacks,
}

impl FrameRecord<'_> {
    /// Records pass `p` into `encoder`: into `shared`'s compute pass when `batched`.
    pub(super) fn record(
        &mut self,
        p: usize,
        encoder: &mut wgpu::CommandEncoder,
        shared: &mut SharedPass,
        batched: bool,
    ) -> Result<()> {
        let node = &self.graph.passes[p];
        let mut ctx = RecordContext {
            device: &self.gpu.device,
            queue: &self.gpu.queue,
            features: self.gpu.features,
            encoder,
            name: &node.name,
            inputs: &node.inputs,
            contract: &node.contract,
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

    /// Records every batch of the plan into a new encoder: a compute batch's passes into
    /// one shared compute pass (when `timer.batching`), every other pass on the encoder,
    /// stamps where the timer puts them. With `checked`, a batched pass that took the
    /// encoder is an error; without `one_command_buffer`, each batch ends a command
    /// buffer.
    pub(super) fn record_batches(
        &mut self,
        timer: &FrameTimer<'_>,
        shared: &mut SharedPass,
        checked: bool,
        one_command_buffer: bool,
    ) -> Recorded {
        let graph = self.graph;
        let plan = &graph.plan;
        let device = &self.gpu.device;
        let new_encoder = || {
            device.create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("meshlight frame"),
            })
        };
        let mut encoder = new_encoder();
        let mut command_buffers = Vec::with_capacity(2);
        let mut passes = Vec::with_capacity(plan.order.len());
        let mut batches = Vec::with_capacity(plan.batches.len());
        let mut at = 0;
        let mut failed = None;
        'batches: for (b, batch) in plan.batches.iter().enumerate() {
            let batched = timer.batching && batch.compute;
            let label = batch.label(b);
            if batched {
                shared.begin_batch(label.clone(), timer.shared_batch(b));
            } else {
                timer.batch_edge(&mut encoder, b, false);
            }
            for &p in &batch.passes {
                // A pass skipped on this adapter, or left out of this frame, records
                // nothing and is not timed.
                if plan.passes[p].skipped.is_some() || self.frame_data.skips(&plan.passes[p].name) {
                    continue;
                }
                let node = &graph.passes[p];
                profiling::scope!("meshlight::record", node.name.as_str());
                let t0 = Instant::now();
                if batched {
                    shared.enter(&mut encoder, &node.name);
                }
                timer.pass_edge(&mut encoder, shared, batched, at, false);
                let splits_before = shared.unplanned.len();
                let recorded = self.record(p, &mut encoder, shared, batched);
                timer.pass_edge(&mut encoder, shared, batched, at, true);
                if batched {
                    shared.leave();
                }
                let split = shared.unplanned.get(splits_before).cloned();
                let recorded = match (recorded, split) {
                    (Err(e), _) => Err(e),
                    (Ok(()), Some(u)) if checked => Err(GraphError::Record {
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
                passes.push(PassTiming {
                    name: node.name.clone(),
                    batch: b,
                    gpu_us: None,
                    cpu_record_us: t0.elapsed().as_secs_f64() * 1e6,
                });
                at += 1;
            }
            if batched {
                shared.end_batch();
            } else {
                timer.batch_edge(&mut encoder, b, true);
            }
            batches.push(BatchStats {
                label,
                passes: batch
                    .passes
                    .iter()
                    .filter(|&&p| {
                        plan.passes[p].skipped.is_none()
                            && !self.frame_data.skips(&plan.passes[p].name)
                    })
                    .map(|&p| plan.passes[p].name.clone())
                    .collect(),
                gpu_us: None,
            });
            if !one_command_buffer && b + 1 < plan.batches.len() {
                let done = std::mem::replace(&mut encoder, new_encoder());
                command_buffers.push(done.finish());
            }
        }
        shared.end_batch();
        Recorded {
            command_buffers,
            encoder,
            passes,
            batches,
            failed,
        }
    }
}
