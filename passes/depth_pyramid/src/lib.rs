//! Stage `depth_pyramid`: a conservative min-depth mip chain of the visibility target,
//! for occlusion culling.
//!
//! Culling asks "is everything in this screen rectangle nearer than the object?". One
//! texel answering for a whole rectangle has to hold the *farthest* depth under it, and
//! with reverse-Z (1 near, 0 at infinity) the farthest depth is the *minimum*. A pixel
//! nothing was drawn to has the cleared value 0 (infinitely far), so it counts as 0: an
//! empty pixel never hides anything behind it. Taking the min (never an average, never
//! the max) is what makes the pyramid conservative: an object is only culled where every
//! pixel under its rectangle is nearer than it.
//!
//! The pyramid is built in compute straight from the 64-bit visibility values
//! (`depth_bits << 32 | payload`), so a frame needs no fixed-function depth buffer.
//!
//! # Contract
//!
//! | slot | access | holds | |
//! |------|--------|-------|---|
//! | `visibility` | storage read | u64 | `width × height` visibility values (a u64 buffer or an `R64Uint` texture); the depth is the high word's f32 |
//! | `pyramid` | storage write | `R32Float`, mips | the levels below; declare it with [`texture_desc`]`(width, height)` |
//! | `counter` | storage read-write (optional) | u32 | `single_pass`'s arrival counter: a 4-byte buffer that persists across frames, zeroed once (see below) |
//!
//! # Parameters
//!
//! | parameter | values | |
//! |---|---|---|
//! | `width`, `height` | 1 ..= 16,384 | the visibility target's size |
//!
//! # The footprint rule
//!
//! For a `W × H` source, level `L` (`L = 0, 1, …`) is `ceil(W / 2^(L+1)) × ceil(H /
//! 2^(L+1))` texels, and texel `(x, y)` of it holds the minimum depth over the source
//! pixels `[x·2^(L+1), (x+1)·2^(L+1)) × [y·2^(L+1), (y+1)·2^(L+1))` clipped to the image.
//! Levels go down to 1 × 1: `1 + ceil(log2(max(ceil(W/2), ceil(H/2))))` of them
//! ([`pyramid_extent`]). Equivalently, level `L + 1` texel `(x, y)` is the min of the
//! level-`L` texels `2x..2x+1 × 2y..2y+1` that exist. Rounding up means odd sizes lose
//! nothing: the last texel of a row of an odd level covers the one leftover texel below
//! it. An occlusion test reads level `L` where one texel spans `2^(L+1)` pixels, and the
//! texels under a pixel rectangle clamped to the image are always inside the level.
//! `meshlight_shaders::cpu::occlusion::DepthPyramid` builds the same levels on the CPU:
//! the tests compare with it bit for bit, and the culling references test against it.
//!
//! The texture is padded so wgpu's rounded-down mips hold the rounded-up levels
//! ([`PyramidExtent::texture_size`]): read level `L` only inside
//! [`PyramidExtent::level_size`]`(L)`; the padding is never written.
//!
//! # Implementations
//!
//! - `single_pass` (`auto` takes it): one dispatch of one workgroup per 128 × 128 tile.
//!   Each reduces its tile through levels 0 to 6 in registers and workgroup memory and
//!   writes them; the last workgroup to finish (a global atomic counter) reduces all the
//!   tiles' results through the remaining levels and sets the counter back to 0 (over
//!   the smallest 32-, 64- or 128-tile square covering the grid, so the lone workgroup
//!   that ends the pass loads no more than it must). No
//!   workgroup waits on another, so it needs no forward-progress guarantee and runs on
//!   every adapter, lavapipe included. It binds a view of all 14 possible levels:
//!   adapters need 14 storage textures per stage (every desktop Vulkan driver has far
//!   more; wgpu's default limits say 4, so plans made without an adapter do not check it,
//!   and record does).
//! - `two_pass`: the tiles in one dispatch, the levels above them in a second dispatch of
//!   one workgroup (none when one tile covers the image). Seven storage textures per
//!   dispatch, and no counter; for comparison, and for adapters with fewer than 14.
//!
//! ## How the single pass hands the tile results over
//!
//! Each workgroup stores its tile's result with an atomic store, passes
//! `storageBarrier()`, and only then counts itself in with `atomicAdd`; the workgroup
//! that counts last passes `storageBarrier()` again and reads the results with
//! `atomicLoad`. Texels other workgroups wrote to the texture are never read.
//! WGSL's memory model on its own does not order this: its atomics are relaxed and its
//! barriers are scoped to the workgroup. What orders it is how every backend lowers
//! `storageBarrier()`: with device scope (naga emits SPIR-V `OpControlBarrier` with
//! `Device` memory scope and acquire-release on uniform memory, MSL
//! `threadgroup_barrier(mem_flags::mem_device)`, HLSL
//! `DeviceMemoryBarrierWithGroupSync()`), which makes the store-barrier-count and
//! count-barrier-load pairs a release and an acquire at device scope; the results
//! themselves are atomics, so no incoherent cache can hold a stale copy. That holds on
//! every adapter meshlight runs on (Vulkan). An adapter or translation layer that lowered
//! `storageBarrier()` to a workgroup-scope barrier would break it; `two_pass` depends on
//! nothing of the kind (the dispatch boundary orders its steps).
//!
//! ## The counter
//!
//! The counter has to read 0 when the dispatch starts. Bound to the `counter` slot (an
//! imported 4-byte buffer, zeroed at creation), it persists and the last workgroup's reset
//! is all it needs. Unbound, the pass uses a scratch word, and since the graph pools
//! scratch memory with other transients it clears that word before each dispatch (a
//! buffer fill). Images of one tile (128 × 128 or less) use no counter at all.
//!
//! The pass builds one bind group itself (per-level views of the pyramid, [`mips`]): the
//! graph binds one view per slot, and a storage texture binding holds one mip.

#![warn(missing_docs)]

pub mod extent;
pub mod mips;

pub use extent::{
    BLOCK_LEVELS, FORMAT, MAX_LEVELS, MAX_SIDE, PyramidExtent, TILE, pyramid_extent, texture_desc,
    tile_grid,
};

use meshlight_graph::prelude::*;
use mips::MipViews;

/// The stage name pipelines use.
pub const STAGE: &str = "depth_pyramid";
/// The slot of the 64-bit visibility target.
pub const VISIBILITY: &str = "visibility";
/// The slot of the pyramid texture.
pub const PYRAMID: &str = "pyramid";
/// The optional slot of `single_pass`'s persistent arrival counter.
pub const COUNTER: &str = "counter";
/// The implementations and the method each runs, best first (the order `auto` tries them
/// in).
pub const IMPLEMENTATIONS: [(&str, Method); 2] = [
    ("single_pass", Method::SinglePass),
    ("two_pass", Method::TwoPass),
];

/// The stage's WGSL (`pyramid.wgsl`) with its uniform block, public so the shader tests
/// compose and validate every entry point.
pub const SHADER: PassShader = pass_shader!("depth_pyramid", "pyramid.wgsl", params: ShaderParams);

/// Scratch: one u32 per tile, its level-6 texel's depth bits.
const TILE_RESULTS: &str = "tile_results";
/// Scratch: the arrival counter when the `counter` slot is unbound.
const ARRIVALS: &str = "arrivals";

/// The slots every implementation of `depth_pyramid` shares.
pub fn contract() -> StageContract {
    StageContract {
        stage: STAGE,
        slots: vec![
            Slot::visibility64(
                VISIBILITY,
                Access::StorageRead,
                "width × height visibility values (u64 buffer or r64uint texture); depth in the high word, 0 = empty",
            ),
            Slot::texture(
                PYRAMID,
                Access::StorageWrite,
                Some(FORMAT),
                "min depth over each texel's footprint, every level; declared with depth_pyramid::texture_desc",
            ),
            Slot::buffer(
                COUNTER,
                Access::StorageReadWrite,
                Element::U32,
                "single_pass's arrival counter, 0 between dispatches: a persistent, zeroed 4-byte buffer saves the per-frame clear",
            )
            .optional(),
        ],
    }
}

/// How the levels above the tiles are reached.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Method {
    /// One dispatch; the last workgroup to finish reduces the tiles' results.
    SinglePass,
    /// A dispatch for the tiles, one of one workgroup for the levels above them.
    TwoPass,
}

impl Method {
    /// The implementation name pipelines use for this method.
    pub fn name(self) -> &'static str {
        match self {
            Method::SinglePass => "single_pass",
            Method::TwoPass => "two_pass",
        }
    }
    /// Level views one program binds.
    fn level_bindings(self) -> u32 {
        match self {
            Method::SinglePass => MAX_LEVELS,
            Method::TwoPass => BLOCK_LEVELS,
        }
    }
}

/// The pyramid of a `width × height` visibility target (implementations `single_pass`
/// and `two_pass`, told apart by [`DepthPyramid::method`]).
#[derive(Clone, Debug)]
pub struct DepthPyramid {
    /// The visibility target's width in pixels; the pyramid's size follows from it.
    pub width: u32,
    /// The visibility target's height in pixels.
    pub height: u32,
    /// How the levels above the first tiles are reached: one dispatch or two.
    pub method: Method,
    mips: MipViews,
}

/// The params a pipeline file may give; any other key is an error.
pub const KEYS: [&str; 2] = ["width", "height"];

impl DepthPyramid {
    /// A pass for a `width × height` target built by `method`; nothing is checked until
    /// setup ([`Self::validate`]).
    pub fn new(width: u32, height: u32, method: Method) -> Self {
        Self {
            width,
            height,
            method,
            mips: MipViews::default(),
        }
    }
    /// [`Self::new`] with `single_pass`, what `auto` takes.
    pub fn single_pass(width: u32, height: u32) -> Self {
        Self::new(width, height, Method::SinglePass)
    }
    /// [`Self::new`] with `two_pass`, for adapters that bind fewer than 14 storage textures.
    pub fn two_pass(width: u32, height: u32) -> Self {
        Self::new(width, height, Method::TwoPass)
    }

    /// Reads `width` and `height` (required, 1 to 16,384).
    pub fn from_params(params: &Params, method: Method) -> Result<Self> {
        params.only(&KEYS)?;
        let pass = Self::new(params.u32("width", 0)?, params.u32("height", 0)?, method);
        pass.validate()?;
        Ok(pass)
    }

    /// Refuses a size of 0 or past [`MAX_SIDE`], naming the params to change.
    pub fn validate(&self) -> Result<()> {
        let [w, h] =
            Params::positive_size(self.width, self.height, "the visibility target's size")?;
        if w > MAX_SIDE || h > MAX_SIDE {
            return Err(GraphError::parameter(format!(
                "`width` × `height` = {w} × {h}: the pyramid takes sides up to {MAX_SIDE}; render at a smaller size"
            )));
        }
        Ok(())
    }

    /// Level 0's size and the level count of this pass's pyramid, for sizing the texture.
    pub fn extent(&self) -> PyramidExtent {
        pyramid_extent(self.width, self.height)
    }

    fn tiles(&self) -> [u32; 2] {
        tile_grid(self.width, self.height)
    }

    /// The uniform of a dispatch whose group 1 starts at `level_base`.
    fn params(&self, level_base: u32) -> ShaderParams {
        ShaderParams {
            size: [self.width, self.height],
            tiles: self.tiles(),
            levels: self.extent().mip_levels,
            level_base,
            ..ShaderParams::default()
        }
    }

    /// Whether levels above the tiles exist: more than one tile.
    fn has_top(&self) -> bool {
        self.extent().mip_levels > BLOCK_LEVELS
    }

    /// Errors when what is bound does not fit the params: the pyramid must be exactly
    /// [`texture_desc`], a visibility texture at least `width × height`, and the device
    /// must bind as many storage textures as the program has level views.
    fn check_bound(&self, ctx: &RecordContext<'_>) -> Result<()> {
        let record = |message: String| GraphError::Record {
            pass: ctx.pass_name().to_string(),
            message,
        };
        let want = texture_desc(self.width, self.height);
        match ctx.desc(PYRAMID)? {
            ResourceDesc::Texture(t) if *t == want => {}
            other => {
                return Err(record(format!(
                    "the resource bound to `{PYRAMID}` is {other:?}; declare it with \
                     depth_pyramid::texture_desc({}, {}) = {want:?} (padded so every level fits)",
                    self.width, self.height
                )));
            }
        }
        if let Some(range) = ctx.range(PYRAMID)?
            && range.resolve(&want) != want.full_range()
        {
            return Err(record(format!(
                "`{PYRAMID}` is bound to {} of its texture; bind the whole texture, the pass writes every level",
                range.label()
            )));
        }
        if let ResourceDesc::Texture(t) = ctx.desc(VISIBILITY)?
            && (t.width < self.width || t.height < self.height)
        {
            return Err(record(format!(
                "the `{VISIBILITY}` texture is {} × {}, smaller than the params' {} × {}; set `width` and `height` to the visibility target's size",
                t.width, t.height, self.width, self.height
            )));
        }
        let views = self.method.level_bindings();
        let max = ctx.device().limits().max_storage_textures_per_shader_stage;
        if views > max {
            return Err(GraphError::LimitExceeded {
                what: format!("pass `{}` ({})", ctx.pass_name(), self.method.name()),
                limit: "max_storage_textures_per_shader_stage",
                value: views as u64,
                max: max as u64,
                unit: "storage textures",
                hint: format!(
                    "implementation `two_pass` binds {BLOCK_LEVELS} per dispatch; name it in the pipeline"
                ),
            });
        }
        Ok(())
    }
}

uniform_block! {
    /// The uniform of pyramid.wgsl, which imports the struct (`Params`) from this
    /// declaration.
    struct ShaderParams as "Params" in "depth_pyramid::params" {
        /// Visibility target size in pixels.
        size: [u32; 2],
        /// Tiles of 128 × 128 pixels covering it: the workgroup grid of the first step.
        tiles: [u32; 2],
        /// Levels of the pyramid (its mip count).
        levels: u32,
        /// The level bound at group 1, binding 0: 0, or 7 for two_pass's top dispatch.
        level_base: u32,
        pad_a: u32,
        pad_b: u32,
    }
}

shader_defs! {
    /// The variant of pyramid.wgsl a program runs.
    #[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
    pub struct PyramidDefs {
        /// The arrival counter and all 14 level views (else 7).
        pub single_pass: bool => "SINGLE_PASS",
        /// The visibility target is an R64Uint texture.
        pub texture: bool => "VIS_TEXTURE",
    }
}

/// Group 1: `views` write-only views of the pyramid's levels (built by [`mips`]). Named
/// here: the shader's `mip0`, `mip1`, … are each one level of the one `pyramid` slot.
fn levels_layout(views: u32) -> BindingLayout {
    (0..views).fold(BindingLayout::compute("depth_pyramid_levels"), |l, b| {
        l.slot(b, PYRAMID)
    })
}

impl Pass for DepthPyramid {
    fn implementation(&self) -> Implementation {
        Implementation::new(self.method.name(), contract())
    }
    fn setup(&self, ctx: &mut SetupContext) -> Result<()> {
        self.validate()?;
        let texture = ctx.is_texture(VISIBILITY);
        if texture {
            ctx.require_features(
                wgpu::Features::SHADER_INT64 | wgpu::Features::TEXTURE_INT64_ATOMIC,
            );
        } else {
            ctx.min_bytes(VISIBILITY, self.width as u64 * self.height as u64 * 8);
        }
        let [tx, ty] = self.tiles();
        ctx.scratch_buffer(
            TILE_RESULTS,
            BufferDesc::array(Element::U32, tx as u64 * ty as u64),
            &[Access::StorageReadWrite],
        );
        let defs = PyramidDefs {
            single_pass: self.method == Method::SinglePass,
            texture,
        };
        ctx.shader_defs(&defs);
        // Group 0 from the shader; the arrival counter is named here when a `counter`
        // slot is bound (the shader calls it `arrivals`, as the scratch buffer it is
        // otherwise).
        let common = BindingLayout::from_shader("depth_pyramid");
        let levels = levels_layout(self.method.level_bindings());
        match self.method {
            Method::SinglePass => {
                let common = if ctx.is_bound(COUNTER) {
                    ctx.min_bytes(COUNTER, 4);
                    common.slot(3, COUNTER)
                } else {
                    ctx.scratch_buffer(
                        ARRIVALS,
                        BufferDesc::array(Element::U32, 1),
                        &[Access::ClearedReadWrite],
                    );
                    common
                };
                ctx.program(
                    "single_pass",
                    ProgramDesc::compute(&SHADER, "single_pass")
                        .defs(&defs)
                        .layout(common)
                        .layout(levels),
                );
                ctx.dispatch("single_pass", [tx, ty, 1]);
            }
            Method::TwoPass => {
                ctx.program(
                    "tiles",
                    ProgramDesc::compute(&SHADER, "tiles")
                        .defs(&defs)
                        .layout(common.clone())
                        .layout(levels.clone()),
                );
                ctx.dispatch("tiles", [tx, ty, 1]);
                if self.has_top() {
                    ctx.program(
                        "top",
                        ProgramDesc::compute(&SHADER, "top")
                            .defs(&defs)
                            .layout(common)
                            .layout(levels),
                    );
                }
            }
        }
        Ok(())
    }
    fn record(&self, ctx: &mut RecordContext<'_>) -> Result<()> {
        self.check_bound(ctx)?;
        let [tx, ty] = self.tiles();
        let mut dispatches = Vec::with_capacity(2);
        match self.method {
            Method::SinglePass => {
                let program = ctx.compute("single_pass")?;
                dispatches.push(self.dispatch(ctx, program, 0, [tx, ty])?);
                if self.has_top() && !ctx.is_bound(COUNTER) {
                    // Pooled scratch may hold another pass's data: start the count at 0.
                    // A fill dispatch inside the batch, not a clear command.
                    ctx.clear_scratch(ARRIVALS)?;
                }
            }
            Method::TwoPass => {
                let program = ctx.compute("tiles")?;
                dispatches.push(self.dispatch(ctx, program, 0, [tx, ty])?);
                if self.has_top() {
                    let program = ctx.compute("top")?;
                    dispatches.push(self.dispatch(ctx, program, BLOCK_LEVELS, [1, 1])?);
                }
            }
        }
        let mut pass = ctx.compute_pass();
        for d in &dispatches {
            pass.set_pipeline(&d.program.pipeline);
            pass.set_bind_group(0, &d.common, &[]);
            pass.set_bind_group(1, &d.levels, &[]);
            pass.dispatch_workgroups(d.grid[0], d.grid[1], 1);
        }
        Ok(())
    }
}

/// One dispatch, ready to encode.
struct Dispatch {
    program: std::sync::Arc<ComputeProgram>,
    common: wgpu::BindGroup,
    levels: wgpu::BindGroup,
    grid: [u32; 2],
}

impl DepthPyramid {
    fn dispatch(
        &self,
        ctx: &mut RecordContext<'_>,
        program: std::sync::Arc<ComputeProgram>,
        level_base: u32,
        grid: [u32; 2],
    ) -> Result<Dispatch> {
        let params = self.params(level_base);
        let common = ctx.bind_group(&program, 0, &[("params", bytemuck::bytes_of(&params))])?;
        let levels =
            self.mips
                .bind_group(ctx, &program, level_base, self.method.level_bindings())?;
        Ok(Dispatch {
            program,
            common,
            levels,
            grid,
        })
    }
}

/// Registers `depth_pyramid` (implementations `single_pass`, `two_pass` and `auto`) for
/// pipeline files.
pub fn register(registry: &mut Registry) {
    registry.register_best_first(STAGE, &IMPLEMENTATIONS, DepthPyramid::from_params);
}
