//! The fill program a batched pass's `RecordContext::clear` dispatches: zeroing a buffer
//! inside the batch's compute pass keeps the batch whole, where `clear_buffer` would end
//! it (a clear is an encoder command).

/// Threads per workgroup of `fill.wgsl`.
const WORKGROUP: u64 = 256;
/// Workgroups per grid dimension the fill uses at most (wgpu's default limit).
const MAX_GROUPS_X: u64 = 65_535;

pub(crate) struct Fill {
    pub pipeline: wgpu::ComputePipeline,
    pub layout: wgpu::BindGroupLayout,
}

impl Fill {
    pub fn new(device: &wgpu::Device) -> Self {
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("meshlight fill"),
            source: wgpu::ShaderSource::Wgsl(include_str!("fill.wgsl").into()),
        });
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("meshlight fill"),
            entries: &[wgpu::BindGroupLayoutEntry {
                binding: 0,
                visibility: wgpu::ShaderStages::COMPUTE,
                ty: wgpu::BindingType::Buffer {
                    ty: wgpu::BufferBindingType::Storage { read_only: false },
                    has_dynamic_offset: false,
                    min_binding_size: None,
                },
                count: None,
            }],
        });
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("meshlight fill"),
            bind_group_layouts: &[Some(&layout)],
            immediate_size: 0,
        });
        let pipeline = device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
            label: Some("meshlight fill"),
            layout: Some(&pipeline_layout),
            module: &module,
            entry_point: Some("fill"),
            compilation_options: Default::default(),
            cache: None,
        });
        Self { pipeline, layout }
    }

    /// The byte ranges one binding each covers: at most `max_binding` bytes, starting at
    /// offsets aligned for storage bindings.
    pub fn chunks(bytes: u64, max_binding: u64, align: u64) -> Vec<(u64, u64)> {
        let step = (max_binding / align * align).max(align);
        (0..bytes.div_ceil(step))
            .map(|i| (i * step, step.min(bytes - i * step)))
            .collect()
    }

    /// The workgroup grid that zeroes `bytes` (a multiple of 4).
    pub fn grid(bytes: u64) -> [u32; 2] {
        let groups = (bytes / 4).div_ceil(WORKGROUP).max(1);
        let x = groups.min(MAX_GROUPS_X);
        [x as u32, groups.div_ceil(x) as u32]
    }
}

#[cfg(test)]
mod tests {
    use super::Fill;

    #[test]
    fn chunks_cover_the_buffer_at_aligned_offsets() {
        assert_eq!(Fill::chunks(1000, 4096, 256), vec![(0, 1000)]);
        assert_eq!(
            Fill::chunks(1000, 300, 256),
            vec![(0, 256), (256, 256), (512, 256), (768, 232)]
        );
    }

    #[test]
    fn grid_has_a_thread_per_word_under_the_dimension_limit() {
        assert_eq!(Fill::grid(4), [1, 1]);
        assert_eq!(Fill::grid(4 * 256 * 65_536), [65_535, 2]);
        let [x, y] = Fill::grid(4 * 256 * 200_000);
        assert!(x as u64 * y as u64 >= 200_000 && x <= 65_535);
    }
}
