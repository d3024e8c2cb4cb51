//! Asynchronous readback of buffers the graph declared with `GraphBuilder::readback`.

use crate::record::ring::MapRing;
use std::collections::{HashMap, VecDeque};

/// Bytes copied from the GPU in frame `frame`.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Readback {
    /// The frame the bytes were copied in, earlier than the one that delivered them.
    pub frame: u64,
    /// The bytes of the range asked for.
    pub bytes: Vec<u8>,
}

/// One frame's copy for a readback.
pub(crate) struct ReadbackCopy<'a> {
    pub name: &'a str,
    pub latency: u32,
    pub source: &'a wgpu::Buffer,
    pub range: std::ops::Range<u64>,
    pub frame: u64,
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
    /// Records the copy of `copy.range` of `copy.source` into `copy.name`'s ring.
    pub fn record(
        &mut self,
        device: &wgpu::Device,
        encoder: &mut wgpu::CommandEncoder,
        copy: ReadbackCopy<'_>,
    ) -> Result<(), String> {
        let ReadbackCopy {
            name,
            latency,
            source,
            range,
            frame,
        } = copy;
        let len = range.end.saturating_sub(range.start);
        if !range.start.is_multiple_of(wgpu::COPY_BUFFER_ALIGNMENT)
            || !len.is_multiple_of(wgpu::COPY_BUFFER_ALIGNMENT)
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

    /// Moves finished copies old enough to be taken into the ready queues: with `next_frame`
    /// frames executed, frame k is taken once frame k + latency has run.
    pub fn collect(&mut self, next_frame: u64) {
        for c in self.channels.values_mut() {
            let up_to = next_frame.checked_sub(c.latency as u64 + 1);
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
