//! A streamed scene's changes (pages installed and evicted: a page's words, its
//! meshlets' offsets, its group's error, nodes' errors) written to the GPU's buffers by
//! one compute dispatch.
//!
//! A frame that installs 50 pages changes about 250 ranges of five buffers. Written
//! with `Queue::write_buffer` (a staging buffer each) or copied from one staging buffer
//! (a copy command each), wgpu's per-range cost came to 0.3–1 ms of the render thread a
//! frame on an NVIDIA H200's host, most of it in the submission's tracking of each copy
//! (1.2 µs a copy). Here the ranges and their words go up in one `write_buffer` into a
//! buffer kept from frame to frame, and `stream_upload.wgsl` scatters them: one
//! dispatch, whatever the number of ranges.

use meshlight_graph::GpuContext;

use crate::streaming::StreamBuffer;

/// Words of the scatter's header per part: buffer, first word there, first word in the
/// source, words.
const PART_WORDS: usize = 4;

/// Most workgroups along one dimension of a dispatch (WebGPU's default limit): more
/// parts go on further rows.
const MAX_GROUPS_X: u32 = 65535;

/// One range of words to write.
pub(crate) struct Part<'a> {
    /// The buffer.
    pub buffer: StreamBuffer,
    /// Its first word written.
    pub first_word: u32,
    /// The words.
    pub words: &'a [u32],
}

/// The scatter's pipeline and its source buffer, kept from frame to frame.
pub(crate) struct StreamUpload {
    pipeline: wgpu::ComputePipeline,
    layout: wgpu::BindGroupLayout,
    source: Option<wgpu::Buffer>,
    /// The words written to `source`, kept so that a frame's packing reuses memory
    /// already mapped (a new one each frame would fault its pages in again).
    packed: Vec<u32>,
    /// Workgroups a row ([`MAX_GROUPS_X`]; fewer in a test of the rows).
    groups_x: u32,
}

impl StreamUpload {
    pub(crate) fn new(gpu: &GpuContext) -> Self {
        let device = &gpu.device;
        let entry = |binding, read_only| wgpu::BindGroupLayoutEntry {
            binding,
            visibility: wgpu::ShaderStages::COMPUTE,
            ty: wgpu::BindingType::Buffer {
                ty: wgpu::BufferBindingType::Storage { read_only },
                has_dynamic_offset: false,
                min_binding_size: None,
            },
            count: None,
        };
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("stream_upload"),
            entries: &[
                entry(0, true),
                entry(1, false),
                entry(2, false),
                entry(3, false),
                entry(4, false),
                entry(5, false),
            ],
        });
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("stream_upload"),
            source: wgpu::ShaderSource::Wgsl(include_str!("stream_upload.wgsl").into()),
        });
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("stream_upload"),
            bind_group_layouts: &[Some(&layout)],
            immediate_size: 0,
        });
        let pipeline = device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
            label: Some("stream_upload"),
            layout: Some(&pipeline_layout),
            module: &module,
            entry_point: Some("scatter"),
            compilation_options: Default::default(),
            cache: None,
        });
        Self {
            pipeline,
            layout,
            source: None,
            packed: Vec::new(),
            groups_x: MAX_GROUPS_X,
        }
    }

    /// Writes `parts` into `targets` (the buffers, in [`StreamBuffer::ALL`]'s order) and
    /// submits the dispatch, which runs before any later submission (the frame that
    /// draws what it installs). Returns the data's bytes.
    pub(crate) fn write(
        &mut self,
        gpu: &GpuContext,
        targets: [&wgpu::Buffer; 5],
        parts: &[Part<'_>],
    ) -> u64 {
        let data_words: usize = parts.iter().map(|p| p.words.len()).sum();
        if data_words == 0 {
            return 0;
        }
        let header = 1 + PART_WORDS * parts.len();
        let mut source = std::mem::take(&mut self.packed);
        source.clear();
        source.push(parts.len() as u32);
        let mut from = header as u32;
        for p in parts {
            source.extend([p.buffer as u32, p.first_word, from, p.words.len() as u32]);
            from += p.words.len() as u32;
        }
        for p in parts {
            source.extend_from_slice(p.words);
        }
        let bytes = (source.len() * 4) as u64;
        // Kept, and grown to twice what is needed when too small.
        if self.source.as_ref().is_none_or(|b| b.size() < bytes) {
            self.source = Some(gpu.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("stream_upload"),
                size: bytes.next_power_of_two().max(1 << 16),
                usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            }));
        }
        let buffer = self.source.as_ref().expect("made above");
        gpu.queue
            .write_buffer(buffer, 0, bytemuck::cast_slice(&source));
        self.packed = source;
        let sources = [buffer];
        let entries: Vec<wgpu::BindGroupEntry<'_>> = (sources.iter().chain(&targets))
            .enumerate()
            .map(|(binding, buffer)| wgpu::BindGroupEntry {
                binding: binding as u32,
                resource: buffer.as_entire_binding(),
            })
            .collect();
        let bind_group = gpu.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("stream_upload"),
            layout: &self.layout,
            entries: &entries,
        });
        let mut encoder = gpu
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor {
                label: Some("stream_upload"),
            });
        {
            let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("stream_upload"),
                timestamp_writes: None,
            });
            pass.set_pipeline(&self.pipeline);
            pass.set_bind_group(0, &bind_group, &[]);
            let n = parts.len() as u32;
            pass.dispatch_workgroups(n.min(self.groups_x), n.div_ceil(self.groups_x), 1);
        }
        gpu.queue.submit([encoder.finish()]);
        (data_words * 4) as u64
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Parts of every size around the workgroup's width, to every buffer, on several
    /// rows of workgroups: each buffer ends up as the same writes made on the CPU.
    #[test]
    fn parts_on_every_row_reach_their_buffers() {
        let gpu = meshlight_testing::gpu();
        let mut upload = StreamUpload::new(&gpu);
        upload.groups_x = 7;
        let usage = wgpu::BufferUsages::STORAGE
            | wgpu::BufferUsages::COPY_SRC
            | wgpu::BufferUsages::COPY_DST;
        let mut want = vec![vec![0u32; 2048]; 5];
        let targets: Vec<wgpu::Buffer> = (0..5)
            .map(|_| gpu.buffer_with_data("target", &[0u8; 8192], usage))
            .collect();
        let words: Vec<Vec<u32>> = (0..50u32)
            .map(|i| (0..1 + (i * 37) % 150).map(|k| i << 16 | k).collect())
            .collect();
        let parts: Vec<Part<'_>> = (words.iter().enumerate())
            .map(|(i, w)| Part {
                buffer: StreamBuffer::ALL[i % 5],
                first_word: (i / 5 * 160) as u32,
                words: w,
            })
            .collect();
        for p in &parts {
            let first = p.first_word as usize;
            want[p.buffer as usize][first..first + p.words.len()].copy_from_slice(p.words);
        }
        let bytes = upload.write(&gpu, std::array::from_fn(|k| &targets[k]), &parts);
        assert_eq!(bytes, words.iter().map(|w| w.len() as u64 * 4).sum::<u64>());
        for (k, target) in targets.iter().enumerate() {
            let got = gpu.read_buffer(target, 0, 8192).unwrap();
            assert!(
                got == bytemuck::cast_slice::<u32, u8>(&want[k]),
                "buffer {k}"
            );
        }
    }
}
