//! Stage `count_raster`: per froxel and per object kind, how many clusterable objects
//! touch it — the counts light clustering's prefix sum turns into list offsets.
//!
//! Each (object, slice) instance `z_slice` wrote covers a rectangle of tiles
//! (`meshlight::froxel::froxel_rect`: the screen bounds of the object's box cut to the
//! slice's depths); every froxel of it is tested exactly with `object_touches_froxel`
//! (sphere–box for point lights, sphere–box and cone–sphere for spot lights, oriented box
//! against the froxel box for probes and decals, all in view space) and counted with an
//! atomic. The rectangle only bounds the work: which froxels count is the test's answer.
//!
//! # Contract
//!
//! | slot                  | access             | holds | |
//! |-----------------------|--------------------|-------|---|
//! | `objects`             | storage read       | ClusterableObject | what `slice_instances` refers to |
//! | `slice_instances`     | storage read       | SliceInstance | z_slice's `(object, slice)` list |
//! | `slice_counts`        | storage read       | u32 | z_slice's words: `[0]` requested, `[1]` capacity |
//! | `slice_draw_args`     | indirect           | DrawIndirectArgs | z_slice's draw (the `raster` implementation draws it) |
//! | `slice_dispatch_args` | indirect           | DispatchIndirectArgs | z_slice's dispatch, for a walk sized on the GPU (the `compute` implementation here dispatches directly: [`walk_grid`]) |
//! | `cluster_grid`        | storage read       | ClusterGrid | the grid z_slice published |
//! | `cluster_counts`      | storage read-write | u32 | `[froxel × 4 + kind]`, froxels in `cluster_index` order; zeroed on entry (z_slice's `prepare` zeroes it) |
//!
//! Frame input `view`. Both argument slots are in the contract, so a pipeline binds both
//! and swapping the implementation stays one line.
//!
//! # Implementations
//!
//! [`CountRaster`], whose [`Walk`] is one of:
//!
//! - `raster`: one instanced indirect draw of a quad per instance on a
//!   `width × height` viewport (one pixel per tile, `width` and `height` equal to the
//!   grid's), colour writes off; the fragment shader tests and counts. Where every unit
//!   of the GPU rasterises, the rasteriser does the rectangle walk for free.
//! - `compute`: a direct dispatch of at most [`WALK_GROUPS`] workgroups;
//!   each workgroup of 64 lanes takes its share of the instances (at most 64) a round
//!   and shares its lanes out over
//!   all their tiles (a prefix sum of the tile counts in
//!   workgroup memory, a binary search per tile), a froxel per lane. No fixed-function
//!   work: the fast path where few units run graphics (the H100/H200 have two).
//!
//! Both count exactly the pairs [`cpu::cpu_count`] counts, except pairs whose deciding
//! value lies within a hair of its threshold (`meshlight_shaders::cpu::froxel::Decision`),
//! where the GPU's rounding may go the other way.

#![warn(missing_docs)]

pub mod cpu;
pub mod testbed;

use meshlight_gpu_scene::view::frame_view;
use meshlight_graph::prelude::*;
use meshlight_pass_z_slice::{
    CLUSTER_GRID, CLUSTERABLE_OBJECT, INSTANCE_MODULE, SLICE_INSTANCE, check_tiles,
    declare_tile_target, workgroup_grid,
};
use meshlight_shaders::LocalModule;

/// The stage name pipelines use.
pub const STAGE: &str = "count_raster";
/// The frame input holding the `View`.
pub const VIEW_INPUT: &str = "view";
/// Counts per froxel: one per `ClusterableKind`.
pub const KINDS: u32 = 4;
/// The entry points of both implementations; the walk itself is the `count_raster::walk`
/// module ([`WALK_MODULES`]).
pub const SHADER: PassShader = PassShader {
    modules: &[
        INSTANCE_MODULE,
        ListParams::MODULE,
        LocalModule {
            name: "count_raster::walk",
            source: include_str!("walk.wgsl"),
            file_path: concat!(env!("CARGO_PKG_NAME"), "/walk.wgsl"),
        },
    ],
    ..pass_shader!("count_raster::count", "count.wgsl")
};

/// The walk over z_slice's instances and their froxels (`walk.wgsl`, after z_slice's
/// [`INSTANCE_MODULE`] and [`ListParams`]'s module, which it imports), for this stage and
/// for `populate`, whose shader imports it too and defines `POPULATE` to claim list places
/// where this stage counts.
///
/// Both stages must decide every (object, froxel) pair alike, or populate's lists would
/// not match the counts its offsets were built from; one source for the walk makes that
/// hold by construction. It lives here, in the first of the two stages, which populate
/// already depends on for the instance slots ([`instance_slots`]) and the walk's grid
/// ([`walk_grid`]). Only the entry points stay in each stage's shader (`count.wgsl`,
/// populate's `populate.wgsl`), a call each, so pipelines and dumps still name them per
/// stage. A stage's shader picks its work with a `#define` rather than a def given from
/// Rust: a stage never runs the other's variant, so the choice belongs to the shader, not
/// to the pipeline.
pub const WALK_MODULES: &[LocalModule] = SHADER.modules;

uniform_block! {
    /// The uniform of the walk's `POPULATE` section, which `populate` fills and binds at 10.
    ///
    /// populate owns the upload, yet the block is declared here, beside the walk that
    /// imports it: naga_oil resolves every import a module uses, in whichever `#ifdef`
    /// branch, when the module is added, so `walk.wgsl` may only import modules this
    /// stage's own shader lists, and this crate cannot name populate's.
    pub struct ListParams as "ListParams" in "count_raster::list_params" {
        /// Entries the list may hold; clamped to the bound list's length.
        pub capacity: u32,
        /// Pads the block to one 16-byte row, as a uniform's size must be.
        pub pad_a: u32,
        /// See `pad_a`.
        pub pad_b: u32,
        /// See `pad_a`.
        pub pad_c: u32,
    }
}

/// The slots through which a walking stage reads z_slice's instances: `count_raster`'s,
/// and `populate`'s, which walks the same instances.
pub fn instance_slots() -> Vec<Slot> {
    vec![
        Slot::read("objects", CLUSTERABLE_OBJECT, "lights, probes and decals"),
        Slot::read(
            "slice_instances",
            SLICE_INSTANCE,
            "z_slice's (object, slice) list",
        ),
        Slot::read("slice_counts", Element::U32, "[0] requested, [1] capacity"),
        Slot::buffer(
            "slice_draw_args",
            Access::Indirect,
            Element::DRAW_ARGS,
            "a quad per instance (raster)",
        ),
        Slot::buffer(
            "slice_dispatch_args",
            Access::Indirect,
            Element::DISPATCH_ARGS,
            "a workgroup per 64 instances (compute)",
        ),
        Slot::read("cluster_grid", CLUSTER_GRID, "the grid z_slice published"),
    ]
}

/// The slots every implementation of `count_raster` shares.
pub fn contract() -> StageContract {
    let mut slots = instance_slots();
    slots.push(Slot::buffer(
        "cluster_counts",
        Access::StorageReadWrite,
        Element::U32,
        "[froxel × 4 + kind]: objects touching it (zeroed by z_slice)",
    ));
    StageContract {
        stage: STAGE,
        slots,
    }
}

fn setup_common(ctx: &mut SetupContext) {
    ctx.min_bytes("slice_counts", 8);
    ctx.min_bytes("cluster_grid", CLUSTER_GRID.size as u64);
    ctx.frame_input(VIEW_INPUT);
}

/// The walk of this stage's implementations.
const COUNT_WALK: WalkShader = WalkShader {
    shader: &SHADER,
    program: "count",
    vertex: "count_vs",
    fragment: "count_fs",
    compute: "count_cs",
    raster_layout: "count_raster::raster",
    compute_layout: "count_raster::compute",
};

/// The grid's tiles a walking stage's params give: `width` and `height`, default 16 × 9
/// (z_slice's), at least one each way.
pub fn tiles_param(params: &Params) -> Result<[u32; 2]> {
    let tiles = [params.u32("width", 16)?, params.u32("height", 9)?];
    check_tiles(tiles[0], tiles[1])?;
    Ok(tiles)
}

/// The stage's pass. Its two implementations differ only in how they walk (a [`Walk`]),
/// so one type serves both and names itself after its walk, as `sw_raster` picks its
/// target by a field.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct CountRaster {
    /// How this pass walks: its implementation (`raster` or `compute`).
    pub walk: Walk,
}

impl Pass for CountRaster {
    fn implementation(&self) -> Implementation {
        Implementation::new(self.walk.implementation(), contract())
    }
    fn setup(&self, ctx: &mut SetupContext) -> Result<()> {
        setup_common(ctx);
        self.walk.setup(ctx, &COUNT_WALK)
    }
    fn record(&self, ctx: &mut RecordContext<'_>) -> Result<()> {
        self.walk.record(ctx, &COUNT_WALK, &[])
    }
}

/// A walking stage's program: its shader, entry points and layout labels.
#[derive(Clone, Copy, Debug)]
pub struct WalkShader {
    /// The stage's WGSL, holding every entry point below.
    pub shader: &'static PassShader,
    /// The program's name in the pass.
    pub program: &'static str,
    /// `raster`'s vertex entry point: the corner of the instance's tile rectangle.
    pub vertex: &'static str,
    /// `raster`'s fragment entry point: tests and counts (or places) the pixel's froxel.
    pub fragment: &'static str,
    /// `compute`'s entry point.
    pub compute: &'static str,
    /// Label of the `raster` bind-group layout, as dumps and GPU captures show it.
    pub raster_layout: &'static str,
    /// Label of the `compute` bind-group layout.
    pub compute_layout: &'static str,
}

/// How a stage walks the instances' froxels, the part of its `raster` and `compute`
/// implementations this stage and `populate` share: both set up and record the walk of
/// `walk.wgsl` alike, only their shaders and extra uniforms differ.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Walk {
    /// One instanced indirect draw of a quad per instance on a `width × height` viewport.
    Raster {
        /// Viewport columns: the grid's tiles across, one pixel each.
        width: u32,
        /// Viewport rows: the grid's tiles down.
        height: u32,
    },
    /// A direct dispatch of at most this many workgroups ([`walk_grid`]).
    Compute(u32),
}

/// The raster walk's scratch target.
const TARGET: &str = "target";

impl Walk {
    /// The walk a walking stage's params ask for: `raster` on the `width × height` tiles
    /// ([`tiles_param`]), or `compute` with [`WALK_GROUPS`]. `compute` accepts and checks
    /// the tiles too, so a file swaps implementations by changing one line.
    pub fn from_params(params: &Params, compute: bool) -> Result<Self> {
        let [width, height] = tiles_param(params)?;
        Ok(if compute {
            Walk::Compute(WALK_GROUPS)
        } else {
            Walk::Raster { width, height }
        })
    }

    /// The implementation this walk is: `raster` or `compute`.
    pub fn implementation(self) -> &'static str {
        match self {
            Walk::Raster { .. } => "raster",
            Walk::Compute(_) => "compute",
        }
    }

    /// Declares the walk's program (and the raster walk's target and draw arguments).
    pub fn setup(self, ctx: &mut SetupContext, shader: &WalkShader) -> Result<()> {
        let program = match self {
            Walk::Raster { width, height } => {
                ctx.min_bytes("slice_draw_args", 16);
                declare_tile_target(ctx, TARGET, width, height)?;
                // The quad's vertices need the instance, object and grid; only the
                // fragment shader visits froxels.
                ProgramDesc::render(shader.shader, shader.vertex)
                    .fragment(shader.fragment)
                    .target(ColorTarget::masked(TARGET))
                    .primitive(Primitive {
                        topology: wgpu::PrimitiveTopology::TriangleStrip,
                        cull_mode: None,
                        ..Primitive::default()
                    })
                    .layout(BindingLayout::from_shader_render(shader.raster_layout))
            }
            Walk::Compute(_) => ProgramDesc::compute(shader.shader, shader.compute)
                .layout(BindingLayout::from_shader(shader.compute_layout)),
        };
        ctx.program(shader.program, program);
        Ok(())
    }

    /// Records the walk with the view and `uniforms` bound.
    pub fn record(
        self,
        ctx: &mut RecordContext<'_>,
        shader: &WalkShader,
        uniforms: &[(&str, &[u8])],
    ) -> Result<()> {
        let view = frame_view(ctx, VIEW_INPUT, None)?;
        let mut bound = vec![("view", bytemuck::bytes_of(&view))];
        bound.extend_from_slice(uniforms);
        match self {
            Walk::Raster { .. } => {
                let program = ctx.render(shader.program)?;
                let group = ctx.bind_group(&*program, 0, &bound)?;
                let (args, _) = ctx.buffer("slice_draw_args")?;
                let mut pass = ctx.render_pass(&[ColorAttachment::new(TARGET)], None)?;
                pass.set_pipeline(&program.pipeline);
                pass.set_bind_group(0, &group, &[]);
                pass.draw_indirect(args, 0);
            }
            Walk::Compute(max_groups) => {
                let [x, y] = walk_grid(ctx, max_groups)?;
                ctx.dispatch_compute(shader.program, &bound, Workgroups::Direct([x, y, 1]))?;
            }
        }
        Ok(())
    }
}

/// Workgroups a compute walk (this stage's and `populate`'s) is dispatched with at most:
/// about as many 64-lane workgroups as an H100 or H200 holds at once (32 on each of its
/// 132 SMs is 4,224), so a long list is walked in rounds by resident workgroups.
pub const WALK_GROUPS: u32 = 2048;

/// The direct grid of a compute walk over the list bound to `slice_instances`: a
/// workgroup per 64 instances the list can hold, at most `max_groups`. Each workgroup
/// takes its share of the instances written a round, shared over the grid or 128
/// workgroups of it, at most 64 (`walk_share` and `walk_rounds` in `meshlight::froxel`):
/// a short list spreads over many workgroups, a long one is walked in rounds. No indirect dispatch: wgpu checks indirect arguments
/// with a dispatch of its own, a dependent step. On the H200 a share of 64 from a
/// 2,048-workgroup grid took the clustering from 0.061 to 0.051 ms at 100,000 lights and
/// 0.179 to 0.164 ms at 1,000,000, but from 0.038 to 0.043 ms at 1,000 lights, where the
/// hundred or so instances then sat in two workgroups; hence the spread for short lists
/// (over at most 128 workgroups: spread a few per workgroup over thousands, the walks
/// of 100,000 lights were slower than 64 a workgroup).
/// (Sharing over a grid sized for the whole capacity, with no cap, spread a long list a
/// few instances per workgroup over tens of thousands: 0.177 against 0.049 ms for count
/// at 1,000,000 lights.)
pub fn walk_grid(ctx: &RecordContext<'_>, max_groups: u32) -> Result<[u32; 2]> {
    let (_, bytes) = ctx.buffer("slice_instances")?;
    let groups = (bytes / u64::from(SLICE_INSTANCE.size))
        .div_ceil(64)
        .min(u64::from(max_groups.max(1)));
    let limit = ctx.device().limits().max_compute_workgroups_per_dimension;
    Ok(workgroup_grid(groups, limit))
}

/// The implementation that walks as `walk`.
pub fn pass(walk: Walk) -> Box<dyn Pass> {
    Box::new(CountRaster { walk })
}

fn build(params: &Params, compute: bool) -> Result<Box<dyn Pass>> {
    params.only(&["width", "height"])?;
    Ok(pass(Walk::from_params(params, compute)?))
}

/// Registers `count_raster` (implementations `raster` and `compute`) for pipeline files.
pub fn register(registry: &mut Registry) {
    registry.register(STAGE, "raster", |params| build(params, false));
    registry.register(STAGE, "compute", |params| build(params, true));
}
