//! Implementation `scan_fan`: reduce each tile into the fan, scan the fan recursively, then
//! scan each tile with its carry.
//!
//! The fan of 2^28 elements in tiles of 2048 is 131,072 totals, one more level makes 64, so
//! every level runs wide across the GPU; nothing is walked by a single workgroup.

use crate::kernels::{self, Grid, Levels, Step, entry, flag};
use crate::{ScanOptions, contract};
use meshlight_graph::{Pass, RecordContext, Result, SetupContext, StageContract};

/// Counts of at most this many tiles, known on the CPU, are scanned by one workgroup
/// walking the tiles in order (one dispatch), not by the fan.
pub const WALK_TILES: u32 = 4;

/// The multi-level fan scan (the default implementation of stage `scan_fan`).
#[derive(Clone, Debug)]
pub struct ScanFan {
    pub options: ScanOptions,
}

impl ScanFan {
    /// An exclusive scan of `count` elements (or at most `count`, with a GPU count).
    pub fn new(count: u32) -> Self {
        Self::with_options(ScanOptions::new(count))
    }
    pub fn with_options(options: ScanOptions) -> Self {
        Self { options }
    }
    pub fn inclusive(mut self, inclusive: bool) -> Self {
        self.options.inclusive = inclusive;
        self
    }

    fn levels(&self) -> Levels {
        Levels::recursive(self.options.count, self.options.tile())
    }

    /// The dispatches, in order. With one tile this is a single `scan_add`.
    fn steps(&self, gpu_count: bool) -> Vec<Step> {
        let o = &self.options;
        let levels = self.levels();
        let top = levels.top();
        let inclusive_at = |level: usize| {
            if level == 0 && o.inclusive {
                flag::INCLUSIVE
            } else {
                0
            }
        };
        if !gpu_count && top > 0 && levels.sizes[1] <= WALK_TILES {
            // A few tiles: one workgroup scans them in order, one dispatch instead of
            // three (a third of the time at 4,096 elements on the H100).
            return vec![Step {
                entry: entry::WALK,
                params: levels.params(o, 0, flag::TOTAL | inclusive_at(0)),
                grid: Grid::ONE,
            }];
        }
        let mut steps = Vec::with_capacity(2 * top + 2);
        if gpu_count && top > 0 {
            steps.push(Step {
                entry: entry::DISPATCH_ARGS,
                params: levels.params(o, 0, 0),
                grid: Grid::ONE,
            });
        }
        for level in 0..top {
            let grid = Grid::tiles(&levels, level, o.tile(), gpu_count);
            steps.push(Step {
                entry: entry::REDUCE,
                params: levels.params(o, level, 0),
                grid,
            });
        }
        steps.push(Step {
            entry: entry::SCAN_ADD,
            params: levels.params(o, top, flag::TOTAL | inclusive_at(top)),
            grid: Grid::ONE,
        });
        for level in (0..top).rev() {
            let grid = Grid::tiles(&levels, level, o.tile(), gpu_count);
            steps.push(Step {
                entry: entry::SCAN_ADD,
                params: levels.params(o, level, flag::CARRY | inclusive_at(level)),
                grid,
            });
        }
        steps
    }
}

impl Pass for ScanFan {
    fn contract(&self) -> StageContract {
        contract()
    }
    fn implementation(&self) -> &'static str {
        "scan_fan"
    }
    fn setup(&self, ctx: &mut SetupContext) -> Result<()> {
        let steps = self.steps(kernels::gpu_count(ctx));
        kernels::setup(ctx, &self.options, &self.levels(), &steps, None)
    }
    fn record(&self, ctx: &mut RecordContext<'_>) -> Result<()> {
        kernels::record(ctx, &self.steps(ctx.is_bound("count")), false)
    }
}
