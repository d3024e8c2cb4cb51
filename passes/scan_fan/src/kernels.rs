//! What the implementations share: the shader, its typed defs, the level layout of the
//! fan buffer, scratch declarations, and the recording of a list of dispatches.

use crate::{ScanOptions, Subgroups, TileAccess};
use meshlight_graph::prelude::*;

/// The kernels (`scan.wgsl`) and the tile layouts they run on, one module each.
///
/// The kernels (reduce, scan-and-add, the walk, the look-back) are the same whatever the
/// tile layout; only how a lane reads, scans and writes its part of a tile differs. So
/// `scan.wgsl` holds the kernels once and imports the layout, `scan_fan::vector_tile` when
/// the vector width `WIDTH` is given ([`VectorDefs`]) and `scan_fan::staged_tile` without
/// it ([`ScanDefs`]); both build on `scan_fan::common` (parameters, bindings, the
/// Hillis–Steele scan), which takes the parameters' struct from `scan_fan::params`, the
/// module of the `GpuParams` block every dispatch uploads. A `WIDTH` def rather than two
/// entry files keeps every kernel in one place, and the layout modules keep the hot loops
/// of each layout whole and unchanged.
pub const SHADER: PassShader = pass_shader!(
    "scan_fan::scan",
    "scan.wgsl",
    params: GpuParams,
    modules: [
        ("scan_fan::common", "common.wgsl"),
        ("scan_fan::staged_tile", "staged_tile.wgsl"),
        ("scan_fan::vector_tile", "vector_tile.wgsl"),
    ]
);

/// The kernels of `tile_access = "vector"`: [`SHADER`] under a name of its own, so
/// pipelines and dumps tell the layouts apart, composed with [`VectorDefs`]. The same
/// entry points, bindings 0–7 and parameters, plus 16-byte views of the input, output and
/// fan (bindings 8–10) through which a lane moves its words of the tile.
pub const VECTOR_SHADER: PassShader = PassShader {
    name: "scan_fan::scan_vec4",
    ..SHADER
};

/// Kernel entry points in `scan.wgsl`.
pub(crate) mod entry {
    pub const REDUCE: &str = "reduce";
    pub const SCAN_ADD: &str = "scan_add";
    pub const WALK: &str = "walk";
    pub const DISPATCH_ARGS: &str = "dispatch_args";
    pub const LOOKBACK: &str = "lookback";
}

/// Mirrors the WGSL `FLAG_*` constants (`common.wgsl`).
pub(crate) mod flag {
    pub const INCLUSIVE: u32 = 1;
    pub const CARRY: u32 = 2;
    pub const TOTAL: u32 = 4;
    pub const ONE_GROUP_AT_LEAST: u32 = 8;
    pub const TILE_COUNTER: u32 = 32;
}

/// The API's cap on workgroups per dispatch dimension; larger grids are split into rows.
pub(crate) const MAX_GROUPS_PER_DIM: u32 = 65_535;

shader_defs! {
    /// The variant of `scan.wgsl` with tiles of single elements (staged or direct).
    #[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
    pub struct ScanDefs {
        /// Elements each lane scans serially.
        pub items_per_thread: u32 => "ITEMS",
        /// Subgroup scans.
        pub subgroups: bool => "SUBGROUPS",
        /// The element count comes from the `count` slot.
        pub gpu_count: bool => "GPU_COUNT",
        /// Each lane loads and stores its own run of the tile, not staged through
        /// workgroup memory.
        pub direct: bool => "DIRECT",
    }
}

/// The variant of `scan.wgsl` with vector tiles (`WIDTH` given).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct VectorDefs {
    /// Elements each lane scans (`ITEMS`): `items_per_thread / 4` words of 4 (fewer than
    /// 4: one word of that many, read element by element).
    pub items_per_thread: u32,
    /// Subgroup scans (`SUBGROUPS`).
    pub subgroups: bool,
    /// The element count comes from the `count` slot (`GPU_COUNT`).
    pub gpu_count: bool,
}

impl VectorDefs {
    /// Elements per word (`WIDTH`).
    pub fn width(&self) -> u32 {
        self.items_per_thread.min(4)
    }
}

impl ShaderDefs for VectorDefs {
    fn shader_defs(&self) -> Vec<(&'static str, ShaderDef)> {
        vec![
            ("ITEMS", ShaderDef::UInt(self.items_per_thread)),
            ("WIDTH", ShaderDef::UInt(self.width())),
            ("SUBGROUPS", ShaderDef::Bool(self.subgroups)),
            ("GPU_COUNT", ShaderDef::Bool(self.gpu_count)),
        ]
    }
}

/// The defs of whichever shader a pass runs.
#[derive(Clone, Copy, Debug)]
enum Defs {
    Staged(ScanDefs),
    Vector(VectorDefs),
}

impl ShaderDefs for Defs {
    fn shader_defs(&self) -> Vec<(&'static str, ShaderDef)> {
        match self {
            Defs::Staged(d) => d.shader_defs(),
            Defs::Vector(d) => d.shader_defs(),
        }
    }
}

/// The smallest capacity the vector kernels take: below 16 bytes a buffer cannot be
/// bound as an array of `vec4<u32>`, so smaller scans run the staged kernels.
pub const VECTOR_MIN_COUNT: u32 = 4;

uniform_block! {
    /// The uniform block of every dispatch, which `common.wgsl` imports from this
    /// declaration for all the kernels.
    pub(crate) struct GpuParams as "Params" in "scan_fan::params" {
        /// Elements of level 0 when the count comes from the CPU (unused with GPU_COUNT).
        pub count: u32,
        /// The level this dispatch works on (0 = input/output, l > 0 = fan level l).
        pub level: u32,
        /// Offset in `fan` of this level's values (levels > 0); a multiple of 4.
        pub src_offset: u32,
        /// Offset in `fan` of the next level: `reduce` writes tile totals there, `scan_add`
        /// reads each tile's carry from there.
        pub dst_offset: u32,
        /// FLAG_* bits.
        pub flags: u32,
        /// The most elements level 0 may hold; a GPU count above it is clamped.
        pub capacity: u32,
        /// Levels whose dispatch arguments `dispatch_args` writes (GPU_COUNT only).
        pub indirect_levels: u32,
        pub pad_a: u32,
    }
}

/// Element counts of each level and where the levels above 0 sit in the fan buffer.
///
/// Level 0 is the input; level l + 1 holds one total per tile of level l. The last level
/// fits one tile. Built from the capacity, so with a GPU count every level is big enough.
#[derive(Clone, Debug, PartialEq, Eq)]
pub(crate) struct Levels {
    pub sizes: Vec<u32>,
    /// `offsets[l]`: first word of level l in `fan` (0 for level 0, which is not in it).
    pub offsets: Vec<u32>,
}

impl Levels {
    /// Recursive levels until one tile holds the top (the `scan_fan` scheme).
    pub fn recursive(count: u32, tile: u32) -> Self {
        let mut sizes = vec![count];
        while *sizes.last().expect("level 0") > tile {
            let n = sizes.last().expect("level 0").div_ceil(tile);
            sizes.push(n);
        }
        Self::with_offsets(sizes)
    }

    /// At most one level of tile totals, however many (the `two_step` scheme).
    pub fn single_fan(count: u32, tile: u32) -> Self {
        let sizes = if count > tile {
            vec![count, count.div_ceil(tile)]
        } else {
            vec![count]
        };
        Self::with_offsets(sizes)
    }

    fn with_offsets(sizes: Vec<u32>) -> Self {
        // Every level starts on a 16-byte word, for the vector views.
        let mut offsets = vec![0; sizes.len()];
        for l in 2..sizes.len() {
            offsets[l] = offsets[l - 1] + sizes[l - 1].next_multiple_of(4);
        }
        Self { sizes, offsets }
    }

    pub fn top(&self) -> usize {
        self.sizes.len() - 1
    }

    /// Words of `fan`: every level above 0, each padded to a multiple of 4 (at least 4,
    /// so the buffer exists and has a whole vector word).
    pub fn fan_words(&self) -> u64 {
        self.sizes[1..]
            .iter()
            .map(|&n| (n as u64).next_multiple_of(4))
            .sum::<u64>()
            .max(4)
    }

    /// The uniform block for a dispatch on `level`.
    pub fn params(&self, options: &ScanOptions, level: usize, flags: u32) -> GpuParams {
        GpuParams {
            count: options.count,
            level: level as u32,
            src_offset: self.offsets[level],
            dst_offset: self.offsets.get(level + 1).copied().unwrap_or(0),
            flags,
            capacity: options.count,
            indirect_levels: self.top() as u32,
            ..GpuParams::default()
        }
    }
}

/// Splits `groups` workgroups into a grid no wider than the per-dimension cap. The kernels
/// skip the surplus of the last row. Mirrors `dispatch_args` in `scan.wgsl`.
pub(crate) fn grid(groups: u32) -> [u32; 2] {
    let rows = groups.div_ceil(MAX_GROUPS_PER_DIM).max(1);
    [groups.div_ceil(rows), rows]
}

/// How a dispatch gets its workgroup count.
#[derive(Clone, Copy, Debug)]
pub(crate) enum Grid {
    /// Known on the CPU.
    Direct([u32; 2]),
    /// The tile grid of `level`, computed on the GPU by `dispatch_args`.
    Indirect { level: usize },
}

impl Grid {
    /// The tile grid of `level` of `levels`: direct when the count is known on the CPU.
    pub fn tiles(levels: &Levels, level: usize, tile: u32, gpu_count: bool) -> Self {
        if gpu_count {
            Grid::Indirect { level }
        } else {
            Grid::Direct(grid(levels.sizes[level].div_ceil(tile)))
        }
    }
    pub const ONE: Grid = Grid::Direct([1, 1]);
}

/// One dispatch of `scan.wgsl`.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Step {
    pub entry: &'static str,
    pub params: GpuParams,
    pub grid: Grid,
}

impl Step {
    /// `entry` run by one workgroup.
    pub fn once(entry: &'static str, params: GpuParams) -> Self {
        Self {
            entry,
            params,
            grid: Grid::ONE,
        }
    }
}

/// An implementation's options; written by [`scan_implementation!`].
pub(crate) trait Configured {
    fn options(&self) -> &ScanOptions;
}

/// What tells the implementations apart: the levels, the dispatches, the tile state.
/// Everything else, the constructors and the [`meshlight_graph::Pass`] impl, they share
/// ([`scan_implementation!`]).
pub(crate) trait Scheme: Configured {
    /// Level 0 and, past one tile, one level of tile totals (the default).
    fn levels(&self) -> Levels {
        Levels::single_fan(self.options().count, self.options().tile())
    }
    /// The dispatches, in order.
    fn steps(&self, gpu_count: bool) -> Vec<Step>;
    /// Words of the single-pass scan's tile state; `None` without one.
    fn state_words(&self) -> Option<u64> {
        None
    }
    /// True when the tile state must be cleared before the steps.
    fn clears_state(&self, _gpu_count: bool) -> bool {
        false
    }
}

/// `Pass::setup` of every implementation.
pub(crate) fn setup_scheme(ctx: &mut SetupContext, scheme: &impl Scheme) -> Result<()> {
    let steps = scheme.steps(gpu_count(ctx));
    setup(
        ctx,
        scheme.options(),
        &scheme.levels(),
        &steps,
        scheme.state_words(),
    )
}

/// `Pass::record` of every implementation.
pub(crate) fn record_scheme(ctx: &mut RecordContext<'_>, scheme: &impl Scheme) -> Result<()> {
    let gpu_count = ctx.is_bound("count");
    record(
        ctx,
        &scheme.steps(gpu_count),
        scheme.clears_state(gpu_count),
    )
}

/// Declares an implementation `$ty { options }` named `$name` whose `new(count)` takes
/// `$defaults(count)`: the struct, its constructors and its `Pass` impl, around the
/// [`Scheme`] the module implements for it.
macro_rules! scan_implementation {
    ($(#[$doc:meta])* $ty:ident, $name:literal, $defaults:path) => {
        $(#[$doc])*
        #[derive(Clone, Debug)]
        pub struct $ty {
            /// What the scan is configured with; swapping implementations keeps it.
            pub options: $crate::ScanOptions,
        }

        impl $ty {
            #[doc = concat!(
                "An exclusive scan of `count` elements (or at most `count`, with a GPU ",
                "count), with the options of `",
                stringify!($defaults),
                "`."
            )]
            pub fn new(count: u32) -> Self {
                Self::with_options($defaults(count))
            }
            /// The implementation with `options` as given, for a caller that sets each field.
            pub fn with_options(options: $crate::ScanOptions) -> Self {
                Self { options }
            }
            /// Inclusive sums instead of exclusive ones.
            pub fn inclusive(mut self, inclusive: bool) -> Self {
                self.options.inclusive = inclusive;
                self
            }
        }

        impl $crate::kernels::Configured for $ty {
            fn options(&self) -> &$crate::ScanOptions {
                &self.options
            }
        }

        impl meshlight_graph::Pass for $ty {
            fn implementation(&self) -> meshlight_graph::Implementation {
                meshlight_graph::Implementation::new($name, $crate::contract())
            }
            fn setup(&self, ctx: &mut meshlight_graph::SetupContext) -> meshlight_graph::Result<()> {
                $crate::kernels::setup_scheme(ctx, self)
            }
            fn record(
                &self,
                ctx: &mut meshlight_graph::RecordContext<'_>,
            ) -> meshlight_graph::Result<()> {
                $crate::kernels::record_scheme(ctx, self)
            }
        }
    };
}
pub(crate) use scan_implementation;

/// Setup shared by the implementations: validation, the variant, the scratch buffers,
/// and one program per kernel the steps use, with the layout the bound slots give.
/// `state_words`, for the single-pass scan, sizes its tile-state buffer.
pub(crate) fn setup(
    ctx: &mut SetupContext,
    options: &ScanOptions,
    levels: &Levels,
    steps: &[Step],
    state_words: Option<u64>,
) -> Result<()> {
    options.validate()?;
    ctx.optional_features(wgpu::Features::SUBGROUP);
    let gpu_count = gpu_count(ctx);
    let subgroups = options.subgroups == Subgroups::Auto && ctx.has(wgpu::Features::SUBGROUP);
    let vector = uses_vector_kernels(options);
    let (shader, defs) = if vector {
        let defs = VectorDefs {
            items_per_thread: options.items_per_thread,
            subgroups,
            gpu_count,
        };
        (&VECTOR_SHADER, Defs::Vector(defs))
    } else {
        let defs = ScanDefs {
            items_per_thread: options.items_per_thread,
            subgroups,
            gpu_count,
            direct: options.tile_access == TileAccess::Direct,
        };
        (&SHADER, Defs::Staged(defs))
    };
    ctx.shader_defs(&defs);
    ctx.scratch_buffer(
        "fan",
        BufferDesc::array(Element::U32, levels.fan_words()),
        &[Access::StorageReadWrite],
    );
    ctx.scratch_buffer(
        "args",
        BufferDesc::array(Element::DISPATCH_ARGS, levels.top().max(1) as u64),
        &[Access::StorageReadWrite, Access::Indirect],
    );
    ctx.scratch_buffer(
        "total",
        BufferDesc::array(Element::U32, 1),
        &[Access::StorageReadWrite],
    );
    if let Some(words) = state_words {
        ctx.scratch_buffer(
            "state",
            BufferDesc::array(Element::U32, words),
            &[Access::StorageReadWrite],
        );
    }
    let bytes = options.count as u64 * 4;
    ctx.min_bytes("input", bytes);
    ctx.min_bytes("output", bytes);
    ctx.min_bytes("total", 4);
    ctx.min_bytes("count", 4);
    let scan = scan_layout(gpu_count, vector);
    for step in steps {
        let layout = scan.clone();
        ctx.program(
            step.entry,
            ProgramDesc::compute(shader, step.entry)
                .defs(&defs)
                .layout(layout),
        );
        if let Grid::Direct([x, y]) = step.grid {
            ctx.dispatch(step.entry, [x, y, 1]);
        }
    }
    Ok(())
}

/// True when `options` run the vector tiles: vector tile access and a capacity of at
/// least [`VECTOR_MIN_COUNT`] elements.
pub(crate) fn uses_vector_kernels(options: &ScanOptions) -> bool {
    options.tile_access == TileAccess::Vector && options.count >= VECTOR_MIN_COUNT
}

/// The bind group of every kernel, from the shader. Named here what a name cannot say:
/// the `count` slot, which the shader calls `gpu_count` (beside its locals named
/// `count`), and, with `vector`, the input, output and fan once more as 16-byte words
/// (`input4`, `output4`, `fan4` at bindings 8–10).
fn scan_layout(gpu_count: bool, vector: bool) -> BindingLayout {
    let layout = BindingLayout::from_shader("scan_fan");
    let layout = if gpu_count {
        layout.slot(5, "count")
    } else {
        layout
    };
    if vector {
        layout
            .slot(8, "input")
            .slot(9, "output")
            .scratch(10, "fan", Access::StorageReadWrite)
    } else {
        layout
    }
}

/// A step with its pipeline and bind group resolved, ready to encode.
struct Encoded {
    program: std::sync::Arc<meshlight_graph::ComputeProgram>,
    bind_group: wgpu::BindGroup,
    grid: Grid,
}

/// True when the element count comes from the `count` slot.
pub(crate) fn gpu_count(ctx: &SetupContext) -> bool {
    ctx.is_bound("count")
}

/// Encodes `steps` in order in one compute pass; wgpu orders the storage writes of one
/// dispatch before the reads of the next. With `clear_state`, the single-pass scan's tile
/// counter and flags are zeroed first (the graph's fill, a dispatch in the same compute
/// pass), so every frame starts from tile 0.
pub(crate) fn record(ctx: &mut RecordContext<'_>, steps: &[Step], clear_state: bool) -> Result<()> {
    if clear_state {
        ctx.clear_scratch("state")?;
    }
    let mut encoded = Vec::with_capacity(steps.len());
    for step in steps {
        let program = ctx.compute(step.entry)?;
        let bind_group =
            ctx.bind_group(&program, 0, &[("params", bytemuck::bytes_of(&step.params))])?;
        encoded.push(Encoded {
            program,
            bind_group,
            grid: step.grid,
        });
    }
    let args_buffer = if ctx.is_bound("count") {
        Some(ctx.scratch("args")?.0)
    } else {
        None
    };
    let mut pass = ctx.compute_pass();
    for e in &encoded {
        pass.set_pipeline(&e.program.pipeline);
        pass.set_bind_group(0, &e.bind_group, &[]);
        match (e.grid, args_buffer) {
            (Grid::Direct([x, y]), _) => pass.dispatch_workgroups(x, y, 1),
            (Grid::Indirect { level }, Some(buffer)) => {
                pass.dispatch_workgroups_indirect(buffer, level as u64 * 12)
            }
            (Grid::Indirect { .. }, None) => {
                unreachable!("indirect steps are planned only with a GPU count")
            }
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn grids_stay_under_the_dimension_cap_and_cover_every_tile() {
        for groups in [0, 1, 65_535, 65_536, 65_537, 1 << 20, 1 << 23] {
            let [x, y] = grid(groups);
            assert!(
                x <= MAX_GROUPS_PER_DIM && y <= MAX_GROUPS_PER_DIM,
                "{groups}: {x}×{y}"
            );
            assert!(x as u64 * y as u64 >= groups as u64, "{groups}: {x}×{y}");
            assert!(
                (x as u64 * y as u64) < groups as u64 + y as u64 || groups == 0,
                "{groups}: {x}×{y} wastes a row"
            );
        }
    }

    #[test]
    fn levels_recurse_until_one_tile_and_pack_the_fan() {
        let l = Levels::recursive(1 << 28, 256);
        assert_eq!(l.sizes, [1 << 28, 1 << 20, 1 << 12, 16]);
        assert_eq!(l.offsets, [0, 0, 1 << 20, (1 << 20) + (1 << 12)]);
        assert_eq!(l.fan_words(), (1 << 20) + (1 << 12) + 16);
        assert_eq!(Levels::recursive(256, 256).sizes, [256]);
        assert_eq!(Levels::recursive(257, 256).sizes, [257, 2]);
        assert_eq!(Levels::single_fan(1 << 28, 256).sizes, [1 << 28, 1 << 20]);
    }
}
