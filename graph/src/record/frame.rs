//! Per-frame inputs: what changes every frame (the view, the instance count) without the
//! graph being rebuilt or recompiled.

use std::collections::HashMap;

/// Named byte blocks a frame hands its passes; a pass declares the ones it reads with
/// `SetupContext::frame_input` and reads them with `RecordContext::frame_bytes`.
#[derive(Clone, Debug, Default)]
pub struct FrameData {
    entries: HashMap<String, Vec<u8>>,
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
}
