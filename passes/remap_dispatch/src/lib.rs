//! Stage `remap_dispatch`: a workgroup count written on the GPU becomes a 2-D indirect
//! dispatch under the per-dimension limit.
//!
//! Culling writes how many clusters go to the software rasteriser, one workgroup each;
//! past 65,535 of them a 1-D indirect dispatch would exceed the API's per-dimension
//! limit. One thread here folds the count into x × y, x as wide as allowed. The count
//! stays in its buffer: the rasteriser reads it, computes its linear workgroup index
//! `y * x_size + x`, and the surplus of the last row returns at once.
//!
//! # Contract
//!
//! | slot    | access                 | holds | |
//! |---------|------------------------|-------|---|
//! | `count` | storage read           | u32   | the workgroup count at word `count_word` |
//! | `args`  | storage write          | DispatchIndirectArgs | `[x, y, 1]`, for `dispatch_workgroups_indirect` |
//!
//! # Definitions the tests pin down
//!
//! With `m` the per-dimension limit and `n` the count: `x = min(n, m)`, `y = ceil(n / x)`
//! (0 when `n = 0`, so nothing runs), capped at `m`: counts above `m²` (more than
//! 4.29 × 10⁹ at the API limit, far past the 2²⁵ clusters a visibility id can name) lose
//! their last rows. [`cpu_remap`] is the reference.

#![warn(missing_docs)]

use meshlight_graph::prelude::*;

/// The stage name pipelines use.
pub const STAGE: &str = "remap_dispatch";

/// The stage's WGSL (`remap.wgsl`) with its uniform block, public so the shader tests
/// compose and validate every entry point.
pub const SHADER: PassShader =
    pass_shader!("remap_dispatch::remap", "remap.wgsl", params: GpuParams);

/// The slots every implementation of `remap_dispatch` shares.
pub fn contract() -> StageContract {
    StageContract {
        stage: STAGE,
        slots: vec![
            Slot::read(
                "count",
                Element::U32,
                "the workgroup count, at word `count_word`, written by an earlier pass",
            ),
            Slot::buffer(
                "args",
                Access::StorageWrite,
                Element::DISPATCH_ARGS,
                "[x, y, 1] with x, y under the per-dimension limit and x·y ≥ the count",
            ),
        ],
    }
}

/// The dispatch arguments for `count` workgroups under a per-dimension limit of
/// `max_per_dimension` (the reference the GPU test compares with).
pub fn cpu_remap(count: u32, max_per_dimension: u32) -> [u32; 3] {
    meshlight_shaders::cpu::dispatch::fold_dispatch(count, max_per_dimension)
}

/// The one implementation: a single-thread dispatch.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct RemapDispatch {
    /// Word of the `count` slot holding the count.
    pub count_word: u32,
    /// A per-dimension limit below the adapter's (tests use small ones); `None` uses the
    /// adapter's `max_compute_workgroups_per_dimension`.
    pub max_per_dimension: Option<u32>,
}

uniform_block! {
    /// The uniform of remap.wgsl, which imports the struct from this declaration.
    struct GpuParams as "Params" in "remap_dispatch::params" {
        /// Word of `count` that holds the workgroup count.
        count_word: u32,
        /// The adapter's limit on workgroups per dimension (or a smaller test value).
        max_per_dimension: u32,
        pad_a: u32,
        pad_b: u32,
    }
}

const PARAM_KEYS: [&str; 2] = ["count_word", "max_per_dimension"];

impl RemapDispatch {
    /// Reads `count_word` and `max_per_dimension` (0 or absent: the adapter's limit).
    pub fn from_params(params: &Params) -> Result<Self> {
        params.only(&PARAM_KEYS)?;
        let max = params.u32("max_per_dimension", 0)?;
        Ok(Self {
            count_word: params.u32("count_word", 0)?,
            max_per_dimension: (max > 0).then_some(max),
        })
    }
}

impl Pass for RemapDispatch {
    fn implementation(&self) -> Implementation {
        Implementation::new("single_thread", contract())
    }
    fn setup(&self, ctx: &mut SetupContext) -> Result<()> {
        ctx.check_max_per_dimension(self.max_per_dimension)?;
        ctx.min_bytes("count", (self.count_word as u64 + 1) * 4);
        ctx.min_bytes("args", 12);
        let layout = BindingLayout::from_shader("remap_dispatch");
        ctx.program(
            "remap",
            ProgramDesc::compute(&SHADER, "remap").layout(layout),
        );
        Ok(())
    }
    fn record(&self, ctx: &mut RecordContext<'_>) -> Result<()> {
        let params = GpuParams {
            count_word: self.count_word,
            max_per_dimension: ctx.max_per_dimension(self.max_per_dimension),
            ..GpuParams::default()
        };
        ctx.dispatch_compute(
            "remap",
            &[("params", bytemuck::bytes_of(&params))],
            Workgroups::Direct([1, 1, 1]),
        )
    }
}

/// Registers `remap_dispatch` for pipeline files.
pub fn register(registry: &mut Registry) {
    registry.register(STAGE, "single_thread", RemapDispatch::from_params);
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_reference_covers_every_workgroup_under_the_limit() {
        for m in [1u32, 2, 7, 65_535] {
            for n in [0u32, 1, 2, m - 1, m, m + 1, 2 * m + 3, 1 << 25] {
                let [x, y, z] = cpu_remap(n, m);
                assert!(x <= m && y <= m && z == 1, "{n} under {m}: {x}×{y}");
                let covered = x as u64 * y as u64;
                if (n as u64) <= m as u64 * m as u64 {
                    assert!(covered >= n as u64, "{n} under {m}: {x}×{y}");
                    assert!(covered < n as u64 + x as u64 || n == 0, "{n}: a spare row");
                }
            }
        }
        assert_eq!(cpu_remap(0, 65_535), [0, 0, 1]);
        assert_eq!(cpu_remap(u32::MAX, 65_535), [65_535, 65_535, 1]);
    }
}
