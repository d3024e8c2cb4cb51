//! Implementation `two_step`: reduce each tile into the fan, one workgroup walks the whole
//! fan in order, then each tile is scanned with its carry.
//!
//! The middle step is the simple scheme: no recursion, but one workgroup does work
//! proportional to the number of tiles while the rest of the GPU idles. It is here to be
//! measured against `scan_fan`, and as the obviously-correct variant.

use crate::ScanOptions;
use crate::kernels::{self, Grid, Scheme, Step, entry, flag};

kernels::scan_implementation!(
    /// The sequential-fan scan (implementation `two_step` of stage `scan_fan`).
    TwoStep,
    "two_step",
    ScanOptions::new
);

impl Scheme for TwoStep {
    fn steps(&self, gpu_count: bool) -> Vec<Step> {
        let o = &self.options;
        let levels = self.levels();
        let inclusive = if o.inclusive { flag::INCLUSIVE } else { 0 };
        if levels.top() == 0 {
            let params = levels.params(o, 0, flag::TOTAL | inclusive);
            return vec![Step::once(entry::SCAN_ADD, params)];
        }
        let tiles = Grid::tiles(&levels, 0, o.tile(), gpu_count);
        let mut steps = Vec::with_capacity(4);
        if gpu_count {
            steps.push(Step::once(entry::DISPATCH_ARGS, levels.params(o, 0, 0)));
        }
        steps.push(Step {
            entry: entry::REDUCE,
            params: levels.params(o, 0, 0),
            grid: tiles,
        });
        steps.push(Step::once(entry::WALK, levels.params(o, 1, 0)));
        steps.push(Step {
            entry: entry::SCAN_ADD,
            params: levels.params(o, 0, flag::CARRY | inclusive),
            grid: tiles,
        });
        steps
    }
}
