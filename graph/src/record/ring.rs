//! A ring of map-read buffers: results copied on the GPU in frame k are read on the CPU
//! frames later, once the GPU is done, without the CPU ever waiting for it.

use std::sync::Arc;
use std::sync::atomic::{AtomicU8, Ordering};

/// The most buffers a ring grows to. When the GPU is so far behind that every one is
/// still in flight, the frame's copy is dropped (and counted) rather than waited for.
pub(crate) const MAX_SLOTS: usize = 8;

const PENDING: u8 = 0;
const MAPPED: u8 = 1;
const FAILED: u8 = 2;

enum State {
    Free,
    /// A copy into it was recorded for `frame`; not yet submitted.
    Recorded {
        frame: u64,
        bytes: u64,
    },
    /// Submitted and `map_async` called.
    Mapping {
        frame: u64,
        bytes: u64,
        flag: Arc<AtomicU8>,
    },
}

struct Slot {
    buffer: wgpu::Buffer,
    state: State,
}

pub(crate) struct MapRing {
    label: &'static str,
    slots: Vec<Slot>,
    /// Copies dropped because every buffer was in flight.
    pub dropped: u64,
}

impl MapRing {
    pub fn new(label: &'static str) -> Self {
        Self {
            label,
            slots: Vec::new(),
            dropped: 0,
        }
    }

    /// Slots whose copies are submitted but not yet read.
    pub fn in_flight(&self) -> usize {
        self.slots
            .iter()
            .filter(|s| !matches!(s.state, State::Free))
            .count()
    }

    /// A free buffer of at least `bytes` for frame `frame`'s copy, or `None` when all
    /// [`MAX_SLOTS`] are in flight.
    pub fn acquire(
        &mut self,
        device: &wgpu::Device,
        bytes: u64,
        frame: u64,
    ) -> Option<&wgpu::Buffer> {
        let free = self
            .slots
            .iter()
            .position(|s| matches!(s.state, State::Free) && s.buffer.size() >= bytes);
        let i = match free {
            Some(i) => i,
            None => {
                // A free buffer that is too small is replaced; otherwise the ring grows.
                if let Some(i) = self
                    .slots
                    .iter()
                    .position(|s| matches!(s.state, State::Free))
                {
                    self.slots.remove(i);
                }
                if self.slots.len() >= MAX_SLOTS {
                    self.dropped += 1;
                    return None;
                }
                self.slots.push(Slot {
                    buffer: device.create_buffer(&wgpu::BufferDescriptor {
                        label: Some(self.label),
                        size: bytes.max(8).next_multiple_of(wgpu::COPY_BUFFER_ALIGNMENT),
                        usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
                        mapped_at_creation: false,
                    }),
                    state: State::Free,
                });
                self.slots.len() - 1
            }
        };
        self.slots[i].state = State::Recorded { frame, bytes };
        Some(&self.slots[i].buffer)
    }

    /// Forgets copies recorded for a frame that was not submitted (a recording error).
    pub fn abandon(&mut self) {
        for s in &mut self.slots {
            if matches!(s.state, State::Recorded { .. }) {
                s.state = State::Free;
            }
        }
    }

    /// Called after the frame's submit: asks for every recorded copy to be mapped.
    pub fn submitted(&mut self) {
        for s in &mut self.slots {
            if let State::Recorded { frame, bytes } = s.state {
                let flag = Arc::new(AtomicU8::new(PENDING));
                let f = flag.clone();
                s.buffer
                    .slice(
                        ..bytes
                            .next_multiple_of(wgpu::COPY_BUFFER_ALIGNMENT)
                            .min(s.buffer.size()),
                    )
                    .map_async(wgpu::MapMode::Read, move |r| {
                        f.store(if r.is_ok() { MAPPED } else { FAILED }, Ordering::Release);
                    });
                s.state = State::Mapping { frame, bytes, flag };
            }
        }
    }

    /// Mapped results of frames `<= up_to`, oldest first; their buffers return to the ring.
    /// Never waits: a copy the GPU has not finished stays for a later call.
    pub fn take_ready(&mut self, up_to: u64) -> Vec<(u64, Vec<u8>)> {
        let mut out = Vec::new();
        for s in &mut self.slots {
            let State::Mapping { frame, bytes, flag } = &s.state else {
                continue;
            };
            if *frame > up_to {
                continue;
            }
            match flag.load(Ordering::Acquire) {
                MAPPED => {
                    // Only the copied bytes were mapped: a buffer reused from a larger
                    // copy is longer than that, and its whole range is not mapped.
                    let mapped = bytes
                        .next_multiple_of(wgpu::COPY_BUFFER_ALIGNMENT)
                        .min(s.buffer.size());
                    let data = s
                        .buffer
                        .get_mapped_range(..mapped)
                        .map(|m| m[..*bytes as usize].to_vec());
                    s.buffer.unmap();
                    if let Ok(data) = data {
                        out.push((*frame, data));
                    }
                    s.state = State::Free;
                }
                FAILED => s.state = State::Free,
                _ => {}
            }
        }
        out.sort_by_key(|(f, _)| *f);
        out
    }
}
