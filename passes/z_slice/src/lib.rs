//! Stage `z_slice`, implementation `compute`: the first stage of light clustering. Per
//! clusterable object, the range of depth slices of the froxel grid its bounds touch, as
//! one instance per (object, slice) for the count and populate stages.
//!
//! A froxel test is cheap but there are `W × H × D` froxels; slicing in depth first
//! means the later stages only walk, or draw one screen quad for, the slices an object
//! can touch. Each object reserves all its slices with one atomic in workgroup memory and
//! each workgroup its objects' with one global atomic (likewise the count words), so an
//! object's slices are contiguous in the list and a million objects do not serialise on
//! one word; past the capacity they are counted, never written.
//!
//! # Contract
//!
//! | slot                  | access             | holds   | |
//! |-----------------------|--------------------|---------|---|
//! | `objects`             | storage read       | ClusterableObject | `object_count[0]` of them are valid |
//! | `object_count`        | storage read       | u32     | `[0]`: objects in the list |
//! | `slice_instances`     | storage write      | SliceInstance | `(object, slice)` pairs; capacity = its length (or `capacity`) |
//! | `slice_counts`        | cleared read-write | u32 × 8 | the words below |
//! | `slice_draw_args`     | storage write      | DrawIndirectArgs | `[quad_vertices, instances written, 0, 0]` for the raster draws |
//! | `slice_dispatch_args` | storage write      | DispatchIndirectArgs | a workgroup per 64 instances written, `[x, y, 1]`, for the compute implementations |
//! | `cluster_grid`        | storage write      | ClusterGrid | the grid of this frame, for the later stages |
//! | `cluster_counts`      | storage write      | u32     | zeroed, every word: count_raster counts into it |
//!
//! `cluster_counts` is zeroed here, by the dispatch that resets the counters, rather than
//! by a dispatch of count_raster's own: that was one more dependent step of the frame.
//!
//! `slice_counts`: `[0]` instances requested (may exceed the capacity), `[1]` the
//! capacity, `[2]` invalid objects skipped, `[3]` objects culled (range 0, outside the
//! frustum, wholly nearer than the near plane), `[4 + kind]` objects of each
//! `ClusterableKind` given slices. Overflow = `max(0, [0] − [1])`. Frame input `view`
//! (`meshlight_shaders::cpu::layout::View`).
//!
//! | param               | default | |
//! |---------------------|---------|---|
//! | `width`             | 16      | tile columns of the grid |
//! | `height`            | 9       | tile rows of the grid |
//! | `depth`             | 24      | depth slices |
//! | `first_slice_end`   | 5.0     | view-space distance where slice 0 ends; every nearer depth is in slice 0 (Bevy's `first_slice_depth`) |
//! | `far`               | 1000.0  | where the last slice ends; farther depths are in it |
//! | `capacity`          | 0 (all of `slice_instances`) | instances the list may hold |
//! | `quad_vertices`     | 4       | vertices per instance in the draw arguments: 4 (triangle strip) or 6 (list) |
//! | `max_per_dimension` | 0 (the adapter's) | workgroup limit per dimension of the dispatches this pass sizes; objects past `64 × limit²` are not visited, nor instances past `limit²` in the dispatch arguments; `prepare` zeroes `cluster_counts` with at most `limit` workgroups, each lane looping over every `64 × limit`-th word |
//!
//! # Definitions the tests pin down
//!
//! - The grid ([`ZSlice::grid`]): `ClusterGrid::new(dims, viewport, n, far)` with
//!   `n = first_slice_end^(D/(D−1)) / far^(1/(D−1))` (f64, then f32; `first_slice_end`
//!   when `D = 1`), so `z_slice_start(1) = first_slice_end` and slices `1..D` are spaced
//!   exponentially up to `far` (to f32 rounding). It is written to `cluster_grid`.
//! - Invalid (counted in `[2]`): a NaN or infinite position component, a NaN or negative
//!   range (by its bits; `-0.0` is range 0), a kind ≥ 4, a spot or decal direction that
//!   is not finite or has squared length < 1e-12, a spot with a non-finite cos or sin.
//! - Range 0 is culled. Ranges above 1e30 (infinity) are 1e30.
//! - Bounds, all in view space, `c` the position, `r` the range: point light — sphere
//!   `(c, r)`; spot light — the spherical sector of radius `r` around the normalised
//!   view-space direction with the given half-angle (the sphere ∩ cone that
//!   `clusterable_intersects_cluster` tests); probe — the world-axis-aligned cube of
//!   half-extent `r`; decal — the cube of half-extent `r` with one axis along its
//!   direction, bounded by the cylinder of radius `r√2` and half-length `r` around that
//!   axis, since the layout holds no rotation about it. Probes and decals enclose the
//!   sphere `(c, r)`, so later stages that test the sphere find a subset of these slices.
//! - Culled (counted in `[3]`) when `sphere_in_frustum(view, c, bound)` fails (bound `r`
//!   for lights, `r√3` for boxes) or the bounds' far depth is below `view.near`.
//! - Slices `z_slice_of_depth(near depth) ..= max(z_slice_of_depth(far depth), first)`:
//!   a light containing the camera starts at slice 0, one past `far` ends at `D − 1`.
//! - [`cpu::cpu_z_slice`] is the reference, mirroring the WGSL's f32 operations in order.
//!   The GPU tests compare the (object, slice) sets exactly, allowing only objects whose
//!   deciding value lies within a relative 1e-5 of a threshold
//!   ([`cpu::Extent::closeness`]); they count such pairs and assert a small bound.

#![warn(missing_docs)]

pub mod cpu;
pub mod scenes;
pub mod testbed;

pub use cpu::{Extent, Outcome, SliceInstance, ZSliceResult, cpu_z_slice};

use meshlight_gpu_scene::view::frame_view;
use meshlight_graph::prelude::*;
use meshlight_shaders::LocalModule;
use meshlight_shaders::cpu::layout::{ClusterGrid, ClusterableObject};

/// The stage name pipelines use.
pub const STAGE: &str = "z_slice";
/// The implementation name pipelines use.
pub const IMPLEMENTATION: &str = "compute";
/// The frame input holding the `View`.
pub const VIEW_INPUT: &str = "view";
/// Threads per object workgroup.
pub const WORKGROUP_SIZE: u32 = 64;

/// `meshlight::light::ClusterableObject`.
pub const CLUSTERABLE_OBJECT: Element =
    Element::named("ClusterableObject", size_of::<ClusterableObject>() as u32);
/// `meshlight::light::ClusterGrid`.
pub const CLUSTER_GRID: Element = Element::named("ClusterGrid", size_of::<ClusterGrid>() as u32);
/// [`SliceInstance`]: `(object, slice)`.
pub const SLICE_INSTANCE: Element =
    Element::named("SliceInstance", size_of::<SliceInstance>() as u32);

/// The WGSL of the list's entries, `SliceInstance` ([`cpu::SliceInstance`] is its
/// mirror), imported by this stage's shader and by the walk count_raster and populate
/// share: one definition of the layout every reader of the list agrees on.
pub const INSTANCE_MODULE: LocalModule = LocalModule {
    name: "z_slice::instance",
    source: include_str!("instance.wgsl"),
    file_path: concat!(env!("CARGO_PKG_NAME"), "/instance.wgsl"),
};

/// The stage's WGSL (`z_slice.wgsl`) with the instance module and its uniform block,
/// public so the shader tests compose and validate every entry point.
pub const SHADER: PassShader = PassShader {
    modules: &[INSTANCE_MODULE, GpuParams::MODULE],
    ..pass_shader!("z_slice::z_slice", "z_slice.wgsl")
};

/// The slots every implementation of `z_slice` shares.
pub fn contract() -> StageContract {
    let write = |name, element, doc| Slot::buffer(name, Access::StorageWrite, element, doc);
    StageContract {
        stage: STAGE,
        slots: vec![
            Slot::read("objects", CLUSTERABLE_OBJECT, "lights, probes and decals"),
            Slot::read(
                "object_count",
                Element::U32,
                "[0]: valid entries of `objects`",
            ),
            write(
                "slice_instances",
                SLICE_INSTANCE,
                "(object, slice) pairs, each object's slices together",
            ),
            Slot::buffer(
                "slice_counts",
                Access::ClearedReadWrite,
                Element::U32,
                "requested, capacity, invalid, culled, visible per kind",
            ),
            write(
                "slice_draw_args",
                Element::DRAW_ARGS,
                "[quad vertices, instances, 0, 0]",
            ),
            write(
                "slice_dispatch_args",
                Element::DISPATCH_ARGS,
                "a workgroup per 64 instances",
            ),
            write("cluster_grid", CLUSTER_GRID, "the grid of this frame"),
            write(
                "cluster_counts",
                Element::U32,
                "zeroed for count_raster to count into",
            ),
        ],
    }
}

/// The froxel grid's shape, as the params give it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GridSettings {
    /// Tile columns, tile rows, depth slices.
    pub dims: [u32; 3],
    /// View-space distance where slice 0 ends; every nearer depth is in slice 0.
    pub first_slice_end: f32,
    /// Where the last slice ends; farther depths are in it.
    pub far: f32,
}

impl Default for GridSettings {
    /// About Bevy's defaults for a 16:9 view: 16 × 9 × 24, slice 0 up to 5 m.
    fn default() -> Self {
        Self {
            dims: [16, 9, 24],
            first_slice_end: 5.0,
            far: 1000.0,
        }
    }
}

impl GridSettings {
    fn check(&self) -> Result<()> {
        for (key, d) in ["width", "height", "depth"].iter().zip(self.dims) {
            if d == 0 {
                return Err(GraphError::parameter(format!(
                    "`{key}` = 0: the cluster grid needs at least one cluster along each axis"
                )));
            }
        }
        let [w, h, d] = self.dims.map(u64::from);
        if w * h * d > u64::from(u32::MAX) {
            return Err(GraphError::parameter(format!(
                "a grid of `width` × `height` × `depth` = {w} × {h} × {d} clusters does not fit in 32 bits; make it smaller"
            )));
        }
        let (first, far) = (self.first_slice_end, self.far);
        if !(first.is_finite() && first > 0.0) {
            return Err(GraphError::parameter(format!(
                "`first_slice_end` = {first} must be a finite distance > 0"
            )));
        }
        if !(far.is_finite() && far > first) {
            return Err(GraphError::parameter(format!(
                "`far` = {far} must be finite and beyond `first_slice_end` = {first}"
            )));
        }
        Ok(())
    }
}

/// The `compute` implementation.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ZSlice {
    /// The froxel grid's shape, which the later stages read from `cluster_grid`.
    pub grid: GridSettings,
    /// List entries; `None`: as many as `slice_instances` holds.
    pub capacity: Option<u32>,
    /// 4 (triangle strip) or 6 (triangle list).
    pub quad_vertices: u32,
    /// A per-dimension limit below the adapter's (tests use small ones); `None`: the
    /// adapter's `max_compute_workgroups_per_dimension`.
    pub max_per_dimension: Option<u32>,
}

impl Default for ZSlice {
    fn default() -> Self {
        Self {
            grid: GridSettings::default(),
            capacity: None,
            quad_vertices: 4,
            max_per_dimension: None,
        }
    }
}

uniform_block! {
    /// The uniform of z_slice.wgsl, which imports the struct from this declaration.
    struct GpuParams as "Params" in "z_slice::params" {
        /// Instances the list may hold; clamped to the bound list's length.
        capacity: u32,
        /// The per-dimension workgroup limit every dispatch this pass sizes must stay under.
        max_per_dimension: u32,
        /// Vertices of one quad in the draw arguments: 4 (strip) or 6 (list).
        quad_vertices: u32,
        pad_a: u32,
    }
}

const PARAM_KEYS: [&str; 8] = [
    "width",
    "height",
    "depth",
    "first_slice_end",
    "far",
    "capacity",
    "quad_vertices",
    "max_per_dimension",
];

impl ZSlice {
    /// Reads the params of the table in the crate docs.
    pub fn from_params(params: &Params) -> Result<Self> {
        params.only(&PARAM_KEYS)?;
        let defaults = GridSettings::default();
        let nonzero = |v: u32| (v > 0).then_some(v);
        let pass = Self {
            grid: GridSettings {
                dims: [
                    params.u32("width", defaults.dims[0])?,
                    params.u32("height", defaults.dims[1])?,
                    params.u32("depth", defaults.dims[2])?,
                ],
                first_slice_end: params.f32("first_slice_end", defaults.first_slice_end)?,
                far: params.f32("far", defaults.far)?,
            },
            capacity: nonzero(params.u32("capacity", 0)?),
            quad_vertices: params.u32("quad_vertices", 4)?,
            max_per_dimension: nonzero(params.u32("max_per_dimension", 0)?),
        };
        pass.check()?;
        Ok(pass)
    }

    fn check(&self) -> Result<()> {
        self.grid.check()?;
        if !matches!(self.quad_vertices, 4 | 6) {
            return Err(GraphError::parameter(format!(
                "`quad_vertices` = {} must be 4 (triangle strip) or 6 (triangle list)",
                self.quad_vertices
            )));
        }
        Ok(())
    }

    /// The grid over a viewport of `viewport` pixels (see the crate docs).
    pub fn grid(&self, viewport: [u32; 2]) -> ClusterGrid {
        let GridSettings {
            dims,
            first_slice_end,
            far,
        } = self.grid;
        let near = if dims[2] > 1 {
            let d = f64::from(dims[2]);
            ((d * f64::from(first_slice_end).ln() - f64::from(far).ln()) / (d - 1.0)).exp() as f32
        } else {
            first_slice_end
        };
        ClusterGrid::new(dims, viewport, near, far)
    }
}

impl Pass for ZSlice {
    fn implementation(&self) -> Implementation {
        Implementation::new(IMPLEMENTATION, contract())
    }
    fn setup(&self, ctx: &mut SetupContext) -> Result<()> {
        self.check()?;
        ctx.check_max_per_dimension(self.max_per_dimension)?;
        ctx.min_bytes("object_count", 4);
        ctx.min_bytes("slice_counts", 4 * cpu::COUNT_WORDS as u64);
        ctx.min_bytes("slice_draw_args", 16);
        ctx.min_bytes("slice_dispatch_args", 12);
        ctx.min_bytes("cluster_grid", size_of::<ClusterGrid>() as u64);
        ctx.frame_input(VIEW_INPUT);
        ctx.scratch_buffer(
            "arrivals",
            BufferDesc::array(Element::U32, 1),
            &[Access::StorageReadWrite],
        );
        // Both programs are an entry point of the shader, laid out as it binds.
        for (entry, layout) in [("prepare", "z_slice::prepare"), ("slice", "z_slice::slice")] {
            let layout = BindingLayout::from_shader(layout);
            ctx.program(entry, ProgramDesc::compute(&SHADER, entry).layout(layout));
        }
        Ok(())
    }
    fn record(&self, ctx: &mut RecordContext<'_>) -> Result<()> {
        let view = frame_view(ctx, VIEW_INPUT, None)?;
        let [w, h] = view.viewport_size;
        let grid = self.grid([w as u32, h as u32]);
        let max_per_dimension = ctx.max_per_dimension(self.max_per_dimension);
        let params = GpuParams {
            capacity: self.capacity.unwrap_or(u32::MAX),
            max_per_dimension,
            quad_vertices: self.quad_vertices,
            ..GpuParams::default()
        };
        // A workgroup per 64 objects the bound list holds: `object_count[0]` may be fewer,
        // and those workgroups' lanes find no object, which costs less than the extra
        // dependent step (and wgpu's argument check) an indirect dispatch sized on the GPU
        // would.
        let (_, object_bytes) = ctx.buffer("objects")?;
        let objects = object_bytes / u64::from(CLUSTERABLE_OBJECT.size);
        let groups = workgroup_grid(
            objects.div_ceil(u64::from(WORKGROUP_SIZE)),
            max_per_dimension,
        );
        // `prepare`: a lane per word of `cluster_counts` (grid-stride past the limit).
        let (_, count_bytes) = ctx.buffer("cluster_counts")?;
        let prepare_groups = (count_bytes / 4)
            .div_ceil(u64::from(WORKGROUP_SIZE))
            .clamp(1, u64::from(max_per_dimension)) as u32;
        let (view, grid, params) = (
            bytemuck::bytes_of(&view),
            bytemuck::bytes_of(&grid),
            bytemuck::bytes_of(&params),
        );
        // Two dispatches: the counters are reset (and the froxel counts zeroed) before any
        // object counts; the arguments are written by the last workgroup of the second,
        // once every object has counted.
        ctx.dispatch_compute(
            "prepare",
            &[("grid", grid), ("params", params)],
            Workgroups::Direct([prepare_groups, 1, 1]),
        )?;
        ctx.dispatch_compute(
            "slice",
            &[("view", view), ("grid", grid), ("params", params)],
            Workgroups::Direct([groups[0], groups[1], 1]),
        )
    }
}

/// `groups` workgroups as a direct dispatch `[x, y]` under `max_per_dimension` each way
/// (as the WGSL's `fold_dispatch` folds them): past `max_per_dimension²` the rest are not
/// dispatched. Always at least one workgroup, so a stage whose last workgroup writes
/// results runs even for an empty list. The compute walks of count_raster and populate
/// size their dispatches with it too.
pub fn workgroup_grid(groups: u64, max_per_dimension: u32) -> [u32; 2] {
    let max = u64::from(max_per_dimension.max(1));
    let x = groups.clamp(1, max);
    [x as u32, groups.div_ceil(x).clamp(1, max) as u32]
}

/// Checks a tile grid read from a pipeline file by a stage that walks froxels: at least
/// one tile each way.
pub fn check_tiles(width: u32, height: u32) -> Result<()> {
    if width == 0 || height == 0 {
        return Err(GraphError::parameter(format!(
            "`width` × `height` = {width} × {height}: the grid needs at least one tile each way; set both to z_slice's"
        )));
    }
    Ok(())
}

/// For implementations that walk froxels by drawing one pixel per tile: refuses a grid
/// past the adapter's viewport and declares the scratch target `name` they draw into
/// (write-masked: the drawing is only a way to visit the tiles).
pub fn declare_tile_target(
    ctx: &mut SetupContext,
    name: &str,
    width: u32,
    height: u32,
) -> Result<()> {
    let limit = ctx.limits().max_texture_dimension_2d;
    if width > limit || height > limit {
        return Err(GraphError::parameter(format!(
            "a {width} × {height} grid is past the adapter's {limit}-pixel viewport; use the `compute` implementation or fewer tiles"
        )));
    }
    ctx.scratch_texture(
        name,
        TextureDesc::d2(wgpu::TextureFormat::R8Unorm, width, height),
        &[Access::RenderTarget],
    );
    Ok(())
}

/// Registers `z_slice` (implementation `compute`) for pipeline files.
pub fn register(registry: &mut Registry) {
    registry.register(STAGE, IMPLEMENTATION, ZSlice::from_params);
}

#[cfg(test)]
mod tests {
    use super::*;
    use meshlight_shaders::cpu::light::{z_slice_of_depth, z_slice_start};
    use meshlight_testing::shader_variants::wgsl_constant;

    /// Reads the pass from `params`, a pipeline file's `params = { … }` contents.
    fn pipeline(params: &str) -> Result<()> {
        let table = params.replace(", ", "\n").parse().expect("toml");
        ZSlice::from_params(&Params::new(table)).map(drop)
    }

    #[test]
    fn params_parse_and_bad_ones_name_what_to_change() {
        meshlight_testing::assert_params(
            pipeline,
            &[
                "",
                "width = 32, height = 18, depth = 32",
                "first_slice_end = 2, far = 500.5",
                "capacity = 100, quad_vertices = 6, max_per_dimension = 7",
                "depth = 1",
            ],
            &[
                ("widht = 16", "widht"),
                ("width = 0", "width"),
                ("height = 0", "height"),
                ("depth = 0", "depth"),
                ("width = 65536, height = 65536, depth = 2", "width"),
                ("first_slice_end = 0", "first_slice_end"),
                ("first_slice_end = nan", "first_slice_end"),
                ("far = 4.0", "far"),
                ("far = inf", "far"),
                ("far = \"x\"", "far"),
                ("quad_vertices = 3", "quad_vertices"),
                ("capacity = 1.5", "capacity"),
            ],
        );
    }

    #[test]
    fn slice_zero_ends_at_first_slice_end_and_the_last_at_far() {
        for (dims, first, far) in [
            ([16, 9, 24], 5.0f32, 1000.0f32),
            ([8, 8, 2], 1.0, 100.0),
            ([4, 4, 1], 2.0, 50.0),
        ] {
            let pass = ZSlice {
                grid: GridSettings {
                    dims,
                    first_slice_end: first,
                    far,
                },
                ..ZSlice::default()
            };
            let grid = pass.grid([1280, 720]);
            let d = dims[2];
            if d > 1 {
                let end = z_slice_start(&grid, 1);
                assert!((end - first).abs() / first < 1e-5, "{end} vs {first}");
                assert_eq!(z_slice_of_depth(&grid, first * 0.999), 0);
                assert_eq!(z_slice_of_depth(&grid, first * 1.001), 1);
                let before_far = z_slice_start(&grid, d - 1);
                assert!(before_far < far && before_far >= first * 0.99999);
            }
            assert_eq!(z_slice_of_depth(&grid, 1e-3), 0);
            assert_eq!(z_slice_of_depth(&grid, far * 0.999), d - 1);
            assert_eq!(z_slice_of_depth(&grid, far * 10.0), d - 1);
            let tiles = [1280u32.div_ceil(dims[0]), 720u32.div_ceil(dims[1])];
            assert_eq!(grid.tile_size, tiles.map(|t| t as f32));
        }
    }

    #[test]
    fn the_wgsl_constants_are_the_reference_s() {
        let value = |name| wgsl_constant::<f32>(&SHADER, name);
        assert_eq!(value("SQRT_2").to_bits(), cpu::SQRT_2.to_bits());
        assert_eq!(value("SQRT_3").to_bits(), cpu::SQRT_3.to_bits());
        assert_eq!(value("RANGE_LIMIT").to_bits(), cpu::RANGE_LIMIT.to_bits());
    }
}
