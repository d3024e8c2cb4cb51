//! What a still render waits for: the frame it submitted finished on the GPU, and that
//! frame's counters back.

use crate::graph::{Executor, FrameStats, GraphError, Result};

/// Waits for every submitted frame; the statistics are those of frame `submitted`.
pub fn finish(executor: &mut Executor, submitted: u64) -> Result<FrameStats> {
    executor
        .finish()?
        .ok_or_else(|| GraphError::Readback(format!("frame {submitted} left no statistics")))
}

/// The counters of frame `submitted` from the newest ones taken back (`frame` names the
/// frame they belong to); after [`finish`] they must be there.
pub fn counters_of<C: Copy>(
    latest: Option<C>,
    frame: impl Fn(&C) -> u64,
    submitted: u64,
) -> Result<C> {
    latest.filter(|c| frame(c) == submitted).ok_or_else(|| {
        GraphError::Readback(format!(
            "frame {submitted}'s counters did not come back after the GPU finished it"
        ))
    })
}
