//! Implementation `two_step`: reduce each tile into the fan, one workgroup walks the whole
//! fan in order, then each tile is scanned with its carry.
//!
//! The middle step is the simple scheme: no recursion, but one workgroup does work
//! proportional to the number of tiles while the rest of the GPU idles. It is here to be
//! measured against `scan_fan`, and as the obviously-correct variant.

use crate::kernels::{self, Grid, Levels, Step, entry, flag};
use crate::{ScanOptions, contract};
use meshlight_graph::{Pass, RecordContext, Result, SetupContext, StageContract};

/// The sequential-fan scan (implementation `two_step` of stage `scan_fan`).
#[derive(Clone, Debug)]
pub struct TwoStep {
    pub options: ScanOptions,
}

impl TwoStep {
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
        Levels::single_fan(self.options.count, self.options.tile())
    }

    fn steps(&self, gpu_count: bool) -> Vec<Step> {
        let o = &self.options;
        let levels = self.levels();
        let inclusive = if o.inclusive { flag::INCLUSIVE } else { 0 };
        if levels.top() == 0 {
            return vec![Step {
                entry: entry::SCAN_ADD,
                params: levels.params(o, 0, flag::TOTAL | inclusive),
                grid: Grid::ONE,
            }];
        }
        let tiles = Grid::tiles(&levels, 0, o.tile(), gpu_count);
        let mut steps = Vec::with_capacity(4);
        if gpu_count {
            steps.push(Step {
                entry: entry::DISPATCH_ARGS,
                params: levels.params(o, 0, 0),
                grid: Grid::ONE,
            });
        }
        steps.push(Step {
            entry: entry::REDUCE,
            params: levels.params(o, 0, 0),
            grid: tiles,
        });
        steps.push(Step {
            entry: entry::WALK,
            params: levels.params(o, 1, 0),
            grid: Grid::ONE,
        });
        steps.push(Step {
            entry: entry::SCAN_ADD,
            params: levels.params(o, 0, flag::CARRY | inclusive),
            grid: tiles,
        });
        steps
    }
}

impl Pass for TwoStep {
    fn contract(&self) -> StageContract {
        contract()
    }
    fn implementation(&self) -> &'static str {
        "two_step"
    }
    fn setup(&self, ctx: &mut SetupContext) -> Result<()> {
        let steps = self.steps(kernels::gpu_count(ctx));
        kernels::setup(ctx, &self.options, &self.levels(), &steps, None)
    }
    fn record(&self, ctx: &mut RecordContext<'_>) -> Result<()> {
        kernels::record(ctx, &self.steps(ctx.is_bound("count")), false)
    }
}
