//! One GPU timestamp pair per pass, resolved and read back after the frame.

pub(crate) struct Timestamps {
    pub query_set: wgpu::QuerySet,
    resolve: wgpu::Buffer,
    readback: wgpu::Buffer,
    capacity: u32,
    /// True when timestamps may be written between passes on the encoder itself.
    inside_encoders: bool,
}

impl Timestamps {
    pub fn new(device: &wgpu::Device, passes: u32, inside_encoders: bool) -> Self {
        let capacity = (passes * 2).max(2);
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
            readback: device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("meshlight timestamp readback"),
                size: bytes,
                usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            }),
            capacity,
            inside_encoders,
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

    pub fn resolve(&self, encoder: &mut wgpu::CommandEncoder, count: u32) {
        if count == 0 {
            return;
        }
        encoder.resolve_query_set(&self.query_set, 0..count, &self.resolve, 0);
        encoder.copy_buffer_to_buffer(&self.resolve, 0, &self.readback, 0, count as u64 * 8);
    }

    pub fn readback(&self) -> &wgpu::Buffer {
        &self.readback
    }
}
