//! Implementation `decoupled_lookback`: one dispatch, each tile read once and written once
//! (8 bytes per element against the fan scan's 12), after Merrill and Garland's
//! single-pass scan with decoupled look-back.
//!
//! # Forward progress
//!
//! A workgroup waits for earlier tiles to publish their totals, so on its own the scheme
//! relies on those earlier workgroups running while it waits. Two things take that away:
//!
//! - Tiles come from a counter in the order workgroups start, not from the workgroup id,
//!   so a workgroup only ever waits on one that has already started.
//! - The wait is bounded: after 1,024 looks at a silent predecessor the waiting workgroup
//!   reduces that tile's input itself and goes on. A scheduler that starves the
//!   predecessor makes the scan slower, never wrong or hung.
//!
//! Where it is fast:
//!
//! - NVIDIA (Vulkan): resident workgroups run independently and a started one runs to
//!   completion, so predecessors publish within microseconds and the fallback is rare.
//! - lavapipe (llvmpipe): each worker thread runs one workgroup to its end before taking
//!   the next, so a started predecessor owns a thread and does finish. Yet an unbounded
//!   spin there gave a few tiles a carry of 0 with two worker threads (never with one):
//!   the loop ended without its predecessor's total, as gallivm's loop limiter (65,535
//!   iterations) would end it. So the wait is bounded and every loop here stays short; the
//!   tests run it there with the default worker threads.
//! - Elsewhere (mobile GPUs, some integrated ones) workgroups may be run in turn; the
//!   scan stays correct but falls back often and is slower than `scan_fan`.
//!
//! So nothing chooses this implementation for the user: a pipeline names it.
//!
//! # Tiles and what limits the speed
//!
//! With vector tiles (the default) a workgroup holds its whole tile in registers while it
//! looks back, so its tile is big: 8,192 elements (32 per lane) by default, which halves
//! the look-backs per byte against 4,096 and was the fastest measured (docs/BENCHMARKS.md).
//! A scan of one tile whose count is known on the CPU takes tile 0 without the counter and
//! waits on nothing, so its state is not even cleared: one dispatch.
//!
//! On the H100 the single pass reaches 0.71× of a compute copy at 2^26 elements, not the
//! copy's speed: each workgroup spends part of its life with no loads in flight (taking a
//! tile from the counter, then waiting for its predecessors), and its register footprint
//! limits how many others can cover for it. Tried and slower there: a wider look-back (4
//! or 8 predecessors per lane and round trip), parking the tile in workgroup memory or
//! reading it again after the look-back (both to free registers), and taking the next tile
//! and loading it before the current one's look-back (the prefetched tile then publishes
//! late and the look-backs chain).

use crate::ScanOptions;
use crate::kernels::{self, Grid, Scheme, Step, entry, flag};

kernels::scan_implementation!(
    /// The single-pass scan (implementation `decoupled_lookback` of stage `scan_fan`).
    DecoupledLookback,
    "decoupled_lookback",
    ScanOptions::for_lookback
);

impl DecoupledLookback {
    /// Tiles at capacity, at least one so an empty scan still writes its total.
    fn tiles(&self) -> u32 {
        self.options.count.div_ceil(self.options.tile()).max(1)
    }

    /// True when tiles may wait on each other: more than one tile, or a count from the GPU.
    fn waits(&self, gpu_count: bool) -> bool {
        gpu_count || self.tiles() > 1
    }
}

/// Only level 0 is scanned; the level above (the default levels) sizes the tile grid of
/// `dispatch_args`.
impl Scheme for DecoupledLookback {
    fn steps(&self, gpu_count: bool) -> Vec<Step> {
        let o = &self.options;
        let levels = self.levels();
        let inclusive = if o.inclusive { flag::INCLUSIVE } else { 0 };
        let counter = if self.waits(gpu_count) {
            flag::TILE_COUNTER
        } else {
            0
        };
        let mut args = levels.params(o, 0, flag::ONE_GROUP_AT_LEAST);
        // `dispatch_args` writes only the level-0 grid.
        args.indirect_levels = 1;
        let mut steps = Vec::with_capacity(2);
        let grid = if gpu_count {
            steps.push(Step::once(entry::DISPATCH_ARGS, args));
            Grid::Indirect { level: 0 }
        } else {
            Grid::Direct(kernels::grid(self.tiles()))
        };
        steps.push(Step {
            entry: entry::LOOKBACK,
            params: levels.params(o, 0, inclusive | counter),
            grid,
        });
        steps
    }

    /// The tile counter, then two words per tile.
    fn state_words(&self) -> Option<u64> {
        Some(1 + 2 * self.tiles() as u64)
    }

    /// With one tile and a count known here, the kernel takes tile 0 and waits on
    /// nothing: no state to clear.
    fn clears_state(&self, gpu_count: bool) -> bool {
        self.waits(gpu_count)
    }
}
