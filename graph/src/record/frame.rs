//! Per-frame inputs: what changes every frame (the view, the instance count) without the
//! graph being rebuilt or recompiled.

use std::collections::{HashMap, HashSet};

/// Named byte blocks a frame hands its passes; a pass declares the ones it reads with
/// `SetupContext::frame_input` and reads them with `RecordContext::frame_bytes`.
#[derive(Clone, Debug, Default)]
pub struct FrameData {
    entries: HashMap<String, Vec<u8>>,
    skipped: HashSet<String>,
}

impl FrameData {
    /// No frame inputs.
    pub fn new() -> Self {
        Self::default()
    }
    /// Sets `name` to `bytes`, reusing the block's allocation from an earlier frame.
    pub fn set(&mut self, name: &str, bytes: &[u8]) -> &mut Self {
        match self.entries.get_mut(name) {
            Some(v) => {
                v.clear();
                v.extend_from_slice(bytes);
            }
            None => {
                self.entries.insert(name.to_string(), bytes.to_vec());
            }
        }
        self
    }
    /// Sets `name` to one little-endian `u32` (a count, a frame index).
    pub fn set_u32(&mut self, name: &str, value: u32) -> &mut Self {
        self.set(name, &value.to_le_bytes())
    }
    /// Builder form of [`FrameData::set`].
    pub fn with(mut self, name: &str, bytes: &[u8]) -> Self {
        self.set(name, bytes);
        self
    }
    /// The bytes set for `name`, or `None` when this frame does not supply it.
    pub fn get(&self, name: &str) -> Option<&[u8]> {
        self.entries.get(name).map(Vec::as_slice)
    }
    /// Leaves the pass `name` out of this frame: it records nothing and is not timed, so
    /// what it writes keeps what it held. For work a caller knows is still valid (a
    /// shadow cascade whose view and scene did not change, drawn into a buffer the caller
    /// owns); the passes reading its output must not depend on a transient it would
    /// have written this frame. A name that is no pass of the graph is an error when the
    /// frame runs.
    pub fn skip(&mut self, name: &str) -> &mut Self {
        self.skipped.insert(name.to_string());
        self
    }
    /// Whether the pass `name` is left out of this frame.
    pub fn skips(&self, name: &str) -> bool {
        self.skipped.contains(name)
    }
    /// The passes left out of this frame.
    pub fn skipped(&self) -> impl Iterator<Item = &str> {
        self.skipped.iter().map(String::as_str)
    }
}
