//! The compute pass a batch of graph passes shares, and the guard `compute_pass()` hands
//! out. Held as `ComputePass<'static>` (its encoder stays locked while it is open), so
//! it can live across the `record` calls of the batch's passes.

use std::ops::{Deref, DerefMut};

/// What `RecordContext::compute_pass` returns: the batch's shared compute pass, or a
/// pass of its own (unbatched, or a pass recorded on the encoder) that ends when the
/// guard drops. Either way it derefs to [`wgpu::ComputePass`].
pub struct ComputePassGuard<'p> {
    inner: Inner<'p>,
}

// The guard lives on the stack for one pass's recording; boxing the owned pass would
// allocate on every `compute_pass()` of an unbatched pass.
#[allow(clippy::large_enum_variant)]
enum Inner<'p> {
    Own(wgpu::ComputePass<'static>),
    Shared(&'p mut wgpu::ComputePass<'static>),
}

impl<'p> ComputePassGuard<'p> {
    pub(crate) fn own(pass: wgpu::ComputePass<'static>) -> Self {
        Self {
            inner: Inner::Own(pass),
        }
    }
    pub(crate) fn shared(pass: &'p mut wgpu::ComputePass<'static>) -> Self {
        Self {
            inner: Inner::Shared(pass),
        }
    }
    /// True when this is the batch's shared pass.
    pub fn is_shared(&self) -> bool {
        matches!(self.inner, Inner::Shared(_))
    }
}

impl Deref for ComputePassGuard<'_> {
    type Target = wgpu::ComputePass<'static>;
    fn deref(&self) -> &Self::Target {
        match &self.inner {
            Inner::Own(p) => p,
            Inner::Shared(p) => p,
        }
    }
}

impl DerefMut for ComputePassGuard<'_> {
    fn deref_mut(&mut self) -> &mut Self::Target {
        match &mut self.inner {
            Inner::Own(p) => p,
            Inner::Shared(p) => p,
        }
    }
}

/// Timestamps a batch's compute pass writes at its beginning and end (`frame` timing).
pub(crate) struct BatchStamps {
    pub query_set: wgpu::QuerySet,
    /// Taken by the first compute pass the batch opens.
    pub begin: Option<u32>,
    /// Written by every compute pass the batch opens, so the last one's end counts.
    pub end: u32,
}

/// A pass that took the encoder inside a batch, which ended the batch's compute pass.
#[derive(Clone, Debug)]
pub(crate) struct Unplanned {
    pub pass: String,
    pub what: &'static str,
}

/// The batch's compute pass while it is open, and the debug group of the graph pass
/// recording into it.
#[derive(Default)]
pub(crate) struct SharedPass {
    pass: Option<wgpu::ComputePass<'static>>,
    label: String,
    stamps: Option<BatchStamps>,
    group: Option<String>,
    pushed: bool,
    /// Passes that split their batch this frame.
    pub unplanned: Vec<Unplanned>,
    /// Compute passes opened this frame (one per batch unless a pass split one).
    pub opened: u32,
}

impl SharedPass {
    pub fn begin_batch(&mut self, label: String, stamps: Option<BatchStamps>) {
        self.end_batch();
        self.label = label;
        self.stamps = stamps;
    }

    /// Ends the compute pass; its timestamps were given when it was opened.
    pub fn end_batch(&mut self) {
        self.close();
        self.stamps = None;
        self.group = None;
    }

    /// The open compute pass, opened (again) on `encoder` if a split closed it.
    pub fn get(&mut self, encoder: &mut wgpu::CommandEncoder) -> &mut wgpu::ComputePass<'static> {
        if self.pass.is_none() {
            let timestamp_writes = self
                .stamps
                .as_mut()
                .map(|s| wgpu::ComputePassTimestampWrites {
                    query_set: &s.query_set,
                    beginning_of_pass_write_index: s.begin.take(),
                    end_of_pass_write_index: Some(s.end),
                });
            let pass = encoder
                .begin_compute_pass(&wgpu::ComputePassDescriptor {
                    label: Some(&self.label),
                    timestamp_writes,
                })
                .forget_lifetime();
            self.opened += 1;
            self.pushed = false;
            self.pass = Some(pass);
        }
        let pass = self.pass.as_mut().expect("opened above");
        if let (Some(group), false) = (&self.group, self.pushed) {
            pass.push_debug_group(group);
            self.pushed = true;
        }
        pass
    }

    /// A graph pass starts recording into the batch: its name labels a debug group.
    pub fn enter(&mut self, encoder: &mut wgpu::CommandEncoder, name: &str) {
        self.group = Some(name.to_string());
        self.get(encoder);
    }

    /// The graph pass is done: its debug group closes.
    pub fn leave(&mut self) {
        if let (Some(pass), true) = (self.pass.as_mut(), self.pushed) {
            pass.pop_debug_group();
        }
        self.pushed = false;
        self.group = None;
    }

    /// Ends the open compute pass so the encoder can take other commands; the next
    /// `get` opens another. True when one was open.
    pub fn split(&mut self) -> bool {
        let was_open = self.pass.is_some();
        self.close();
        was_open
    }

    fn close(&mut self) {
        if let Some(mut pass) = self.pass.take()
            && self.pushed
        {
            pass.pop_debug_group();
        }
        self.pushed = false;
    }
}
