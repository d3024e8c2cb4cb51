//! Runs compiled graphs frame after frame: allocates pooled resources, swaps history,
//! records each live pass into its own labelled encoder inside an error scope, submits
//! once, and reports per-pass timings.

use crate::compile::CompiledGraph;
use crate::error::{GraphError, Result};
use crate::exec::context::GpuContext;
use crate::exec::physical::{self, Physical, PhysicalPool};
use crate::exec::programs::Programs;
use crate::exec::record::RecordContext;
use crate::exec::timing::Timestamps;
use crate::resource::{ImportedUsage, ResourceDesc, ResourceKind};
use serde::Serialize;
use std::collections::HashMap;
use std::time::Instant;

/// Caller-owned resources for one frame, by resource name.
#[derive(Default)]
pub struct Imports {
    entries: HashMap<String, Physical>,
}

impl Imports {
    pub fn new() -> Self {
        Self::default()
    }
    pub fn buffer(mut self, name: &str, buffer: &wgpu::Buffer) -> Self {
        self.entries.insert(
            name.to_string(),
            Physical::Buffer {
                buffer: buffer.clone(),
                size: buffer.size(),
            },
        );
        self
    }
    pub fn texture(mut self, name: &str, texture: &wgpu::Texture) -> Self {
        let view = texture.create_view(&wgpu::TextureViewDescriptor::default());
        self.entries.insert(
            name.to_string(),
            Physical::Texture {
                texture: texture.clone(),
                view,
            },
        );
        self
    }
}

#[derive(Clone, Debug, Serialize)]
pub struct PassTiming {
    pub name: String,
    /// GPU time between the pass's timestamps, when the adapter has timestamps.
    pub gpu_us: Option<f64>,
    /// CPU time spent in the pass's `record`, including pipeline creation on first use.
    pub cpu_record_us: f64,
}

#[derive(Clone, Debug, Serialize)]
pub struct FrameStats {
    pub frame: u64,
    pub passes: Vec<PassTiming>,
    /// CPU time of the whole frame on the executor's side, excluding the GPU wait.
    pub cpu_frame_us: f64,
    /// The part of `cpu_frame_us` spent in `queue.submit` (mostly driver work).
    pub cpu_submit_us: f64,
    pub gpu_total_us: Option<f64>,
    pub bytes_with_reuse: u64,
    pub bytes_without_reuse: u64,
    /// GPU resources created this frame (zero once a steady graph has warmed up).
    pub allocations: u32,
    pub pipelines_created: u32,
}

pub struct Executor {
    pub gpu: GpuContext,
    pool: PhysicalPool,
    programs: Programs,
    histories: HashMap<String, [Physical; 2]>,
    exported: HashMap<String, Physical>,
    timestamps: Option<Timestamps>,
    frame: u64,
    /// Wait for the GPU and read timestamps every frame (off for CPU-overhead benchmarks).
    pub gpu_timing: bool,
}

impl Executor {
    pub fn new(gpu: GpuContext) -> Self {
        Self {
            gpu,
            pool: PhysicalPool::default(),
            programs: Programs::new(),
            histories: HashMap::new(),
            exported: HashMap::new(),
            timestamps: None,
            frame: 0,
            gpu_timing: true,
        }
    }

    pub fn device(&self) -> &wgpu::Device {
        &self.gpu.device
    }
    pub fn queue(&self) -> &wgpu::Queue {
        &self.gpu.queue
    }

    /// Reads back an exported transient or the current half of a history resource, as left
    /// by the last frame.
    pub fn read_buffer(&self, name: &str) -> Result<Vec<u8>> {
        let physical = self
            .exported
            .get(name)
            .or_else(|| {
                self.histories
                    .get(name)
                    .map(|pair| &pair[((self.frame + 1) % 2) as usize])
            })
            .ok_or_else(|| {
                GraphError::Readback(format!(
                    "`{name}` is neither an exported nor a history resource of the last frame"
                ))
            })?;
        match physical {
            Physical::Buffer { buffer, size } => self.gpu.read_buffer(buffer, 0, *size),
            Physical::Texture { .. } => Err(GraphError::Readback(format!(
                "`{name}` is a texture; copy it to a buffer in a pass"
            ))),
        }
    }

    pub fn execute(&mut self, graph: &CompiledGraph, imports: &Imports) -> Result<FrameStats> {
        let frame_start = Instant::now();
        let plan = &graph.plan;
        let missing = plan.enabled_features - self.gpu.features;
        if !missing.is_empty() {
            return Err(GraphError::MissingFeature {
                pass: "(graph)".into(),
                stage: "(device)".into(),
                features: missing
                    .iter_names()
                    .map(|(n, _)| n)
                    .collect::<Vec<_>>()
                    .join(", "),
            });
        }
        self.pool.begin_frame();
        self.programs.uniforms.begin_frame();
        if self.programs.bind_groups.len() > 4096 {
            self.programs.bind_groups.clear();
        }
        let pipelines_before = self.programs.pipelines_created;
        let physical = self.resolve_resources(graph, imports)?;

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
        for (i, &p) in plan.order.iter().enumerate() {
            let node = &graph.passes[p];
            let t0 = Instant::now();
            let scope = device.push_error_scope(wgpu::ErrorFilter::Validation);
            let mut encoder = device.create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some(&node.name),
            });
            let ts = if timing {
                self.timestamps.as_ref()
            } else {
                None
            };
            if let Some(ts) = ts {
                ts.write(&mut encoder, 2 * i as u32);
            }
            let mut ctx = RecordContext {
                device,
                queue: &self.gpu.queue,
                features: self.gpu.features,
                encoder: &mut encoder,
                node,
                pass_index: p,
                plan,
                physical: &physical,
                programs: &mut self.programs,
            };
            let recorded = node.pass.record(&mut ctx);
            if let Some(ts) = ts {
                ts.write(&mut encoder, 2 * i as u32 + 1);
            }
            let cb = encoder.finish();
            if let Some(e) = pollster::block_on(scope.pop()) {
                return Err(GraphError::Validation {
                    pass: node.name.clone(),
                    message: e.to_string(),
                });
            }
            recorded?;
            command_buffers.push(cb);
            timings.push(PassTiming {
                name: node.name.clone(),
                gpu_us: None,
                cpu_record_us: t0.elapsed().as_secs_f64() * 1e6,
            });
        }

        let queries = plan.order.len() as u32 * 2;
        if let Some(ts) = self.timestamps.as_ref().filter(|_| timing) {
            let mut enc = device.create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("meshlight timestamps"),
            });
            ts.resolve(&mut enc, queries);
            command_buffers.push(enc.finish());
        }
        self.programs.uniforms.flush(&self.gpu.queue);
        let scope = device.push_error_scope(wgpu::ErrorFilter::Validation);
        let submit_start = Instant::now();
        self.gpu.queue.submit(command_buffers);
        let cpu_submit_us = submit_start.elapsed().as_secs_f64() * 1e6;
        if let Some(e) = pollster::block_on(scope.pop()) {
            return Err(GraphError::Validation {
                pass: "(submit)".into(),
                message: e.to_string(),
            });
        }
        let cpu_frame_us = frame_start.elapsed().as_secs_f64() * 1e6;

        let mut gpu_total_us = None;
        if let Some(ts) = self.timestamps.as_ref().filter(|_| timing && queries > 0) {
            let bytes = self.gpu.map_and_read(ts.readback())?;
            // Mapped bytes carry no alignment guarantee for u64: copy rather than cast.
            let ticks: Vec<u64> = bytemuck::pod_collect_to_vec(&bytes[..queries as usize * 8]);
            let period_ns = self.gpu.queue.get_timestamp_period() as f64;
            let mut total = 0.0;
            for (i, t) in timings.iter_mut().enumerate() {
                let us = ticks[2 * i + 1].saturating_sub(ticks[2 * i]) as f64 * period_ns / 1000.0;
                t.gpu_us = Some(us);
                total += us;
            }
            gpu_total_us = Some(total);
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
        self.frame += 1;
        Ok(FrameStats {
            frame: self.frame - 1,
            passes: timings,
            cpu_frame_us,
            cpu_submit_us,
            gpu_total_us,
            bytes_with_reuse: plan.bytes_with_reuse,
            bytes_without_reuse: plan.bytes_without_reuse,
            allocations: self.pool.allocations,
            pipelines_created: self.programs.pipelines_created - pipelines_before,
        })
    }

    fn resolve_resources(
        &mut self,
        graph: &CompiledGraph,
        imports: &Imports,
    ) -> Result<Vec<Option<Physical>>> {
        let plan = &graph.plan;
        let mut physical: Vec<Option<Physical>> = vec![None; plan.resources.len()];
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
        let parity = (self.frame % 2) as usize;
        for (r, res) in plan.resources.iter().enumerate() {
            match &res.info.kind {
                ResourceKind::Imported { usage } => {
                    let Some(ph) = imports.entries.get(&res.info.name) else {
                        if res.lifetime.is_none() {
                            continue;
                        }
                        return Err(GraphError::MissingImport {
                            resource: res.info.name.clone(),
                        });
                    };
                    check_import(&res.info.name, &res.info.desc, *usage, ph)?;
                    physical[r] = Some(ph.clone());
                }
                ResourceKind::History { prev } => {
                    let pair = self.history_pair(
                        &res.info.name,
                        &res.info.desc,
                        res.buffer_usage,
                        res.texture_usage,
                    );
                    physical[r] = Some(pair[parity].clone());
                    physical[prev.index()] = Some(pair[1 - parity].clone());
                }
                _ => {}
            }
        }
        Ok(physical)
    }

    fn history_pair(
        &mut self,
        name: &str,
        desc: &ResourceDesc,
        bu: wgpu::BufferUsages,
        tu: wgpu::TextureUsages,
    ) -> [Physical; 2] {
        let device = &self.gpu.device;
        self.histories
            .entry(name.to_string())
            .or_insert_with(|| {
                [
                    physical::create(device, &format!("{name} (history a)"), desc, bu, tu),
                    physical::create(device, &format!("{name} (history b)"), desc, bu, tu),
                ]
            })
            .clone()
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
            {
                return mismatch(format!(
                    "declared {:?} {}x{}, the texture is {:?} {}x{}",
                    t.format,
                    t.width,
                    t.height,
                    texture.format(),
                    texture.width(),
                    texture.height()
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
