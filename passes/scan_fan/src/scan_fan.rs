//! Implementation `scan_fan`: reduce each tile into the fan, scan the fan recursively, then
//! scan each tile with its carry.
//!
//! The fan of 2^28 elements in tiles of 2048 is 131,072 totals, one more level makes 64, so
//! every level runs wide across the GPU; nothing is walked by a single workgroup.

use crate::ScanOptions;
use crate::kernels::{self, Grid, Levels, Scheme, Step, entry, flag};

/// Counts of at most this many tiles, known on the CPU, are scanned by one workgroup
/// walking the tiles in order (one dispatch), not by the fan.
pub const WALK_TILES: u32 = 4;

kernels::scan_implementation!(
    /// The multi-level fan scan (the default implementation of stage `scan_fan`).
    ScanFan,
    "scan_fan",
    ScanOptions::new
);

impl Scheme for ScanFan {
    /// Recursive levels until one tile holds the top.
    fn levels(&self) -> Levels {
        Levels::recursive(self.options.count, self.options.tile())
    }

    /// With one tile this is a single `scan_add`.
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
            let params = levels.params(o, 0, flag::TOTAL | inclusive_at(0));
            return vec![Step::once(entry::WALK, params)];
        }
        let mut steps = Vec::with_capacity(2 * top + 2);
        if gpu_count && top > 0 {
            steps.push(Step::once(entry::DISPATCH_ARGS, levels.params(o, 0, 0)));
        }
        for level in 0..top {
            let grid = Grid::tiles(&levels, level, o.tile(), gpu_count);
            steps.push(Step {
                entry: entry::REDUCE,
                params: levels.params(o, level, 0),
                grid,
            });
        }
        let params = levels.params(o, top, flag::TOTAL | inclusive_at(top));
        steps.push(Step::once(entry::SCAN_ADD, params));
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
