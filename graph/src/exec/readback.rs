//! Asynchronous readback of buffers the graph declared with `GraphBuilder::readback`.

use crate::exec::ring::MapRing;
use std::collections::{HashMap, VecDeque};

/// Bytes copied from the GPU in frame `frame`.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Readback {
    pub frame: u64,
    pub bytes: Vec<u8>,
}

struct Channel {
    ring: MapRing,
    latency: u32,
    ready: VecDeque<Readback>,
}

#[derive(Default)]
pub(crate) struct Readbacks {
    channels: HashMap<String, Channel>,
}

impl Readbacks {
    /// Records the copy of `range` of `source` for frame `frame` into `name`'s ring.
    pub fn record(
        &mut self,
        device: &wgpu::Device,
        encoder: &mut wgpu::CommandEncoder,
        name: &str,
        latency: u32,
        source: &wgpu::Buffer,
        range: std::ops::Range<u64>,
        frame: u64,
    ) -> Result<(), String> {
        let len = range.end.saturating_sub(range.start);
        if range.start % wgpu::COPY_BUFFER_ALIGNMENT != 0 || len % wgpu::COPY_BUFFER_ALIGNMENT != 0
        {
            return Err(format!(
                "readback `{name}`: range {range:?} must start and end on a multiple of 4 bytes"
            ));
        }
        if range.end > source.size() {
            return Err(format!(
                "readback `{name}`: range {range:?} runs past the buffer's {} bytes",
                source.size()
            ));
        }
        let channel = self
            .channels
            .entry(name.to_string())
            .or_insert_with(|| Channel {
                ring: MapRing::new("meshlight readback"),
                latency,
                ready: VecDeque::new(),
            });
        channel.latency = latency;
        if let Some(dst) = channel.ring.acquire(device, len, frame) {
            encoder.copy_buffer_to_buffer(source, range.start, dst, 0, len);
        }
        Ok(())
    }

    pub fn submitted(&mut self) {
        for c in self.channels.values_mut() {
            c.ring.submitted();
        }
    }

    pub fn abandon(&mut self) {
        for c in self.channels.values_mut() {
            c.ring.abandon();
        }
    }

    /// Moves finished copies old enough to be taken (frame + latency <= `next_frame`) into
    /// the ready queues.
    pub fn collect(&mut self, next_frame: u64) {
        for c in self.channels.values_mut() {
            let up_to = next_frame.checked_sub(c.latency as u64);
            if let Some(up_to) = up_to {
                for (frame, bytes) in c.ring.take_ready(up_to) {
                    c.ready.push_back(Readback { frame, bytes });
                }
            }
        }
    }

    pub fn take(&mut self, name: &str) -> Option<Readback> {
        self.channels.get_mut(name)?.ready.pop_front()
    }

    pub fn known(&self, name: &str) -> bool {
        self.channels.contains_key(name)
    }

    /// Copies dropped because the GPU was more frames behind than the ring holds.
    pub fn dropped(&self) -> u64 {
        self.channels.values().map(|c| c.ring.dropped).sum()
    }

    pub fn in_flight(&self) -> usize {
        self.channels
            .values()
            .map(|c| c.ring.in_flight())
            .max()
            .unwrap_or(0)
    }
}
