//! Stage `populate`: the last stage of light clustering. Writes each froxel's object
//! lists where the prefix sum of `count_raster`'s counts placed them.
//!
//! It walks the same (object, slice) instances, rectangles and froxel test as
//! `count_raster` (`meshlight::froxel`), and claims a place in each (froxel, kind) list
//! by taking one from its count with an atomic: the count is the cursor, so no cursor
//! buffer needs zeroing in a step of its own, and the place follows from what is left and
//! what was counted (the difference of neighbouring offsets). A list never receives more entries than it was counted, places
//! past the capacity are claimed and not written, and a last step lowers each count to
//! the entries really written, so whatever the GPU does, no list spills into another, no
//! entry is written out of bounds, and no unwritten place is ever read as an entry.
//!
//! # Contract
//!
//! | slot                  | access             | holds | |
//! |-----------------------|--------------------|-------|---|
//! | `objects`             | storage read       | ClusterableObject | what `slice_instances` refers to |
//! | `slice_instances`     | storage read       | SliceInstance | z_slice's `(object, slice)` list |
//! | `slice_counts`        | storage read       | u32 | z_slice's words: `[0]` requested, `[1]` capacity |
//! | `slice_draw_args`     | indirect           | DrawIndirectArgs | z_slice's draw (`raster`) |
//! | `slice_dispatch_args` | indirect           | DispatchIndirectArgs | z_slice's dispatch, for a walk sized on the GPU (`compute` dispatches directly: count_raster's `walk_grid`) |
//! | `cluster_grid`        | storage read       | ClusterGrid | the grid z_slice published |
//! | `cluster_offsets`     | storage read       | u32 | `[froxel × 4 + kind]`: where that list starts (exclusive prefix sum of the counts) |
//! | `cluster_counts`      | storage read-write | u32 | in: count_raster's counts; out: the entries each list holds |
//! | `list_total`          | storage read       | u32 | `[0]`: the prefix sum's total, the entries all lists need |
//! | `cluster_objects`     | storage write      | u32 | the lists back to back: indices into `objects` |
//! | `list_counts`         | storage write      | u32 × 2 | `[0]` entries needed, `[1]` the capacity |
//!
//! Frame input `view`. A froxel's lists: kind `k` holds `cluster_counts[f × 4 + k]`
//! entries from `cluster_objects[cluster_offsets[f × 4 + k]]`, kinds in
//! `ClusterableKind` order (point lights, spot lights, probes, decals). **Order within a
//! list is unspecified** (the atomics decide it); lists compare as sets.
//!
//! Overflow: when `list_counts[0] > list_counts[1]` the lists that end past the capacity
//! are cut short (their counts say so); the caller reads `list_counts` back and grows
//! `cluster_objects`.
//!
//! | param      | default | |
//! |------------|---------|---|
//! | `capacity` | 0 (all of `cluster_objects`) | entries the lists may hold |
//! | `width`, `height` | 16, 9 | the grid's tiles (z_slice's): `raster`'s viewport, one pixel each; `compute` checks and ignores them |
//!
//! # Implementations
//!
//! [`Populate`], whose [`Walk`] is `raster` (an instanced indirect draw of a quad per instance, the fragment
//! shader writes) or `compute` (a direct dispatch whose workgroups share
//! their lanes out over the tiles of their share of the instances, at most 64, a round),
//! as in `count_raster`; pair each with the same implementation of that stage, so both
//! stages decide every pair with the same code. That code is one source: count_raster's
//! walk module ([`meshlight_pass_count_raster::WALK_MODULES`]), which this stage's shader
//! imports with `POPULATE` defined, and both record it through
//! [`meshlight_pass_count_raster::Walk`].

#![warn(missing_docs)]

pub mod cpu;

use meshlight_graph::prelude::*;
use meshlight_pass_count_raster::{ListParams, Walk, WalkShader};
use meshlight_pass_z_slice::CLUSTER_GRID;

/// The stage name pipelines use.
pub const STAGE: &str = "populate";
/// The frame input holding the `View`.
pub const VIEW_INPUT: &str = "view";
/// Threads per workgroup of `settle`.
const WORKGROUP: u32 = 64;

/// The walk's entry points and `settle`; the walk is count_raster's
/// ([`meshlight_pass_count_raster::WALK_MODULES`], which include the module of the
/// [`ListParams`] block this stage uploads), run here with `POPULATE` defined.
pub const SHADER: PassShader = PassShader {
    modules: meshlight_pass_count_raster::WALK_MODULES,
    ..pass_shader!("populate::populate", "populate.wgsl")
};

/// The slots every implementation of `populate` shares.
pub fn contract() -> StageContract {
    let mut slots = meshlight_pass_count_raster::instance_slots();
    slots.extend([
        Slot::read("cluster_offsets", Element::U32, "where each list starts"),
        Slot::buffer(
            "cluster_counts",
            Access::StorageReadWrite,
            Element::U32,
            "in: counted; out: entries each list holds",
        ),
        Slot::read("list_total", Element::U32, "[0]: entries needed"),
        Slot::buffer(
            "cluster_objects",
            Access::StorageWrite,
            Element::U32,
            "the lists: object indices",
        ),
        Slot::buffer(
            "list_counts",
            Access::StorageWrite,
            Element::U32,
            "[0] needed, [1] capacity",
        ),
    ]);
    StageContract {
        stage: STAGE,
        slots,
    }
}

/// The walk of this stage's implementations: count_raster's, claiming list places.
const POPULATE_WALK: WalkShader = WalkShader {
    shader: &SHADER,
    program: "populate",
    vertex: "populate_vs",
    fragment: "populate_fs",
    compute: "populate_cs",
    raster_layout: "populate::raster",
    compute_layout: "populate::compute",
};

/// The stage's pass: its walk, then the compute step after it. Its two implementations
/// differ only in how they walk (count_raster's [`Walk`]), so one type serves both and
/// names itself after its walk.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Populate {
    /// How this pass walks: its implementation, the same as count_raster's.
    pub walk: Walk,
    /// Entries the lists may hold; `None`: all of `cluster_objects`.
    pub capacity: Option<u32>,
}

impl Populate {
    /// The walk's and `settle`'s uniform, whose block count_raster declares beside the
    /// walk that imports it.
    fn params(&self) -> ListParams {
        ListParams {
            capacity: self.capacity.unwrap_or(u32::MAX),
            ..ListParams::default()
        }
    }
}

impl Pass for Populate {
    fn implementation(&self) -> Implementation {
        Implementation::new(self.walk.implementation(), contract())
    }
    fn setup(&self, ctx: &mut SetupContext) -> Result<()> {
        ctx.min_bytes("slice_counts", 8);
        ctx.min_bytes("cluster_grid", CLUSTER_GRID.size as u64);
        ctx.min_bytes("list_total", 4);
        ctx.min_bytes("list_counts", 8);
        ctx.frame_input(VIEW_INPUT);
        let settle = BindingLayout::from_shader("populate::settle");
        ctx.program(
            "settle",
            ProgramDesc::compute(&SHADER, "settle").layout(settle),
        );
        self.walk.setup(ctx, &POPULATE_WALK)
    }

    /// The walk, then `settle`: every count set to the entries written, and the needed
    /// and available entries published.
    fn record(&self, ctx: &mut RecordContext<'_>) -> Result<()> {
        let params = self.params();
        let params = bytemuck::bytes_of(&params);
        self.walk
            .record(ctx, &POPULATE_WALK, &[("list_params", params)])?;
        // A thread per list (grid-stride past the limit).
        let (_, bytes) = ctx.buffer("cluster_counts")?;
        let limit = ctx.device().limits().max_compute_workgroups_per_dimension;
        let groups = ((bytes / 4) as u32).div_ceil(WORKGROUP).clamp(1, limit);
        ctx.dispatch_compute(
            "settle",
            &[("list_params", params)],
            Workgroups::Direct([groups, 1, 1]),
        )
    }
}

/// The implementation that walks as `walk`.
pub fn pass(walk: Walk, capacity: Option<u32>) -> Box<dyn Pass> {
    Box::new(Populate { walk, capacity })
}

fn build(params: &Params, compute: bool) -> Result<Box<dyn Pass>> {
    params.only(&["width", "height", "capacity"])?;
    let capacity = Some(params.u32("capacity", 0)?).filter(|&c| c > 0);
    Ok(pass(Walk::from_params(params, compute)?, capacity))
}

/// Registers `populate` (implementations `raster` and `compute`) for pipeline files.
pub fn register(registry: &mut Registry) {
    registry.register(STAGE, "raster", |params| build(params, false));
    registry.register(STAGE, "compute", |params| build(params, true));
}
