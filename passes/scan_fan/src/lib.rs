//! Stage `scan_fan`: prefix sum of u32 counts into offsets, plus their total.
//!
//! Light clustering counts objects per cluster on the GPU; turning those counts into the
//! start offset of each cluster's list is a prefix sum. It is also the first pass crate, so
//! it shows the shape every pass crate follows: the contract here, one module per
//! implementation, the WGSL beside them, a CPU reference, GPU tests against it, and a
//! benchmark.
//!
//! # Contract
//!
//! | slot     | access        | holds | |
//! |----------|---------------|-------|---|
//! | `input`  | storage read  | u32   | the counts, `count` of them |
//! | `output` | storage write | u32   | `output[i]` = sum of `input[..i]` (exclusive) or `input[..=i]` (inclusive) |
//! | `total`  | storage write | u32   | optional: `total[0]` = sum of all counted inputs |
//! | `count`  | storage read  | u32   | optional: `count[0]` = elements to scan, written by an earlier pass |
//!
//! # Definitions the tests pin down
//!
//! - Sums are u32 and wrap modulo 2^32, exactly like [`cpu_scan`]; counts near `u32::MAX`
//!   wrap rather than saturate or fail.
//! - With the `count` slot bound, the element count is `min(count[0], capacity)` where the
//!   capacity is the pass's `count` parameter; the dispatches are indirect. Elements of
//!   `output` at or past the element count are never written, whichever way the count
//!   comes, so a caller's contents there survive.
//! - An empty scan writes only `total[0] = 0`.
//!
//! # Implementations
//!
//! - [`ScanFan`] (`scan_fan`, the default): per tile a reduction into a fan buffer, the fan
//!   scanned recursively (any number of levels), then each tile scanned with its carry.
//! - [`TwoStep`] (`two_step`): the same first and last steps, with one workgroup walking
//!   all tile totals in order in between — simpler, and the comparison for the benchmark.
//! - [`DecoupledLookback`] (`decoupled_lookback`): one dispatch that reads and writes each
//!   element once, each tile finding its carry from its predecessors' published totals.
//!   Its wait on a predecessor is bounded (then it reduces that tile itself), so it is
//!   correct on any adapter, but fast only where workgroups run side by side (NVIDIA; see
//!   its module), so nothing picks it automatically: a pipeline names it.
//!
//! All share this contract and [`ScanOptions`], so swapping them is a one-line change.
//!
//! # Parameters
//!
//! | parameter | values | default | |
//! |---|---|---|---|
//! | `count` | 0 ..= 2^31 | 0 | elements to scan (the capacity, with a GPU count) |
//! | `inclusive` | bool | false | inclusive sums instead of exclusive ones |
//! | `subgroups` | `"auto"`, `"off"` | `"auto"` | subgroup scans where the device has them |
//! | `items_per_thread` | 1, 2, 4, 8, 16; 32 with vector tiles | 8; 32 for `decoupled_lookback` with vector tiles | elements per lane, a tile is 256 × this |
//! | `tile_access` | `"vector"`, `"staged"`, `"direct"` | `"vector"` | how a lane reaches its part of a tile ([`TileAccess`]) |
//!
//! # Tiles
//!
//! With vector tiles (the default, `vector_tile.wgsl`) a lane moves its part of a tile as
//! `items_per_thread / 4` words of 16 bytes (`vec4<u32>`) and keeps them in registers from
//! the load to the store; a subgroup owns a contiguous run of the tile, so every load and
//! store of a row of words is one coalesced stretch. The words are views of the same
//! buffers: the graph binds whole buffers at offset 0, so the vector views are 16-byte
//! aligned, each fan level starts at a multiple of 4 words, and a level's last partial
//! word (`count % 4` elements) is read and written element by element through the `u32`
//! views, so elements past the count are never touched. A capacity under
//! [`VECTOR_MIN_COUNT`] elements (a buffer under 16 bytes, too small for a vector view)
//! runs the staged kernels. On the H100 this took `scan_fan` from 0.30× to 0.64× and the
//! single pass from 0.28× to 0.71× of a compute copy at 2^26 elements (docs/BENCHMARKS.md).
//!
//! # Why reduce-then-scan
//!
//! The textbook order (scan each chunk and write it, scan the chunk totals, then read and
//! rewrite every element to add its chunk's carry) moves 16 bytes per element; the best it
//! can reach is half of copy bandwidth. Here step 1 only reduces each tile to its total
//! (4 bytes read per element) and step 3 does the tile scan and the carry add in one read
//! and one write (8 bytes), 12 bytes in all. Counts of at most [`WALK_TILES`] tiles known on
//! the CPU take one dispatch instead: one workgroup walks the tiles in order.

#![warn(missing_docs)]

use meshlight_graph::prelude::*;

mod cpu;
mod decoupled_lookback;
mod kernels;
mod scan_fan;
mod two_step;

pub use cpu::{cpu_scan, cpu_scan_into};
pub use decoupled_lookback::DecoupledLookback;
pub use kernels::{SHADER, ScanDefs, VECTOR_MIN_COUNT, VECTOR_SHADER, VectorDefs};
pub use scan_fan::{ScanFan, WALK_TILES};
pub use two_step::TwoStep;

/// The stage name pipelines use.
pub const STAGE: &str = "scan_fan";

/// Lanes per workgroup: one Hillis–Steele step per doubling, eight steps for 256 lanes.
pub const WORKGROUP: u32 = 256;

/// The largest element count a pass accepts. Tile offsets are u32 on the GPU, and the
/// last tile must not run past 2^32.
pub const MAX_COUNT: u32 = 1 << 31;

/// The slots every implementation of `scan_fan` shares.
pub fn contract() -> StageContract {
    StageContract {
        stage: STAGE,
        slots: vec![
            Slot::read("input", Element::U32, "counts to scan; at least `count` elements"),
            Slot::buffer(
                "output",
                Access::StorageWrite,
                Element::U32,
                "prefix sums (exclusive unless `inclusive`); elements past the count are left untouched",
            ),
            Slot::buffer("total", Access::StorageWrite, Element::U32, "total[0] = sum of all counted inputs, modulo 2^32").optional(),
            Slot::read(
                "count",
                Element::U32,
                "count[0] = elements to scan, from an earlier pass; clamped to the `count` parameter, dispatches become indirect",
            )
            .optional(),
        ],
    }
}

/// Whether the local scan uses subgroup operations.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum Subgroups {
    /// Subgroup scans where the device has `SUBGROUP`, the shared-memory scan elsewhere.
    #[default]
    Auto,
    /// Always the shared-memory Hillis–Steele scan (to compare, or to test that path).
    Off,
}

impl Subgroups {
    fn parse(value: &str) -> Result<Self> {
        match value {
            "auto" => Ok(Self::Auto),
            "off" => Ok(Self::Off),
            other => Err(GraphError::parameter(format!(
                "`subgroups` must be \"auto\" or \"off\", not {other:?}"
            ))),
        }
    }
    /// True when this mode uses subgroups on a device with `features`.
    pub fn enabled(self, features: wgpu::Features) -> bool {
        self == Self::Auto && features.contains(wgpu::Features::SUBGROUP)
    }
}

/// How a lane reaches its part of the tile in the scan kernels.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum TileAccess {
    /// Consecutive lanes load consecutive elements into workgroup memory (fully coalesced),
    /// and each lane reads its run from there. Scalar loads and six barriers a tile: the
    /// default until vector tiles, half their speed on the H100.
    Staged,
    /// Each lane loads and stores its run itself: no workgroup-memory round trip, strided
    /// accesses that the cache merges. Slower on the H100 (0.9 against 0.63 ms for
    /// `scan_fan` at 2^26, docs/BENCHMARKS.md): kept to compare on other GPUs.
    Direct,
    /// Each lane loads and stores 16-byte words (`vec4<u32>`, `items_per_thread / 4` of
    /// them; one narrower word below 4 items) and keeps them in registers between the load
    /// and the store. A subgroup owns a contiguous run of the tile, each of its loads one
    /// coalesced stretch; rows of words are scanned across the subgroup, and workgroup
    /// memory holds only one sum per subgroup. Capacities under [`VECTOR_MIN_COUNT`]
    /// elements run the staged kernels (a vector view needs 16 bytes).
    #[default]
    Vector,
}

impl TileAccess {
    fn parse(value: &str) -> Result<Self> {
        match value {
            "staged" => Ok(Self::Staged),
            "direct" => Ok(Self::Direct),
            "vector" => Ok(Self::Vector),
            other => Err(GraphError::parameter(format!(
                "`tile_access` must be \"staged\", \"direct\" or \"vector\", not {other:?}"
            ))),
        }
    }
}

/// What every implementation is configured with.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct ScanOptions {
    /// Elements to scan; with the `count` slot bound, the most the GPU count may say.
    pub count: u32,
    /// Inclusive sums (`output[i]` includes `input[i]`) instead of exclusive ones.
    pub inclusive: bool,
    /// Whether to use subgroup scans where the device has them (`auto`) or never (`off`).
    pub subgroups: Subgroups,
    /// Elements each lane scans; a tile is 256 × this. 1 gives the plain 256-element
    /// chunk; larger values cut the barriers and the fan per element, which is what makes
    /// the scan bandwidth-bound. 32 only with vector tiles.
    pub items_per_thread: u32,
    /// How a lane reaches its part of a tile.
    pub tile_access: TileAccess,
}

/// Parameter names a pipeline file may use.
const PARAM_KEYS: [&str; 5] = [
    "count",
    "inclusive",
    "subgroups",
    "items_per_thread",
    "tile_access",
];

impl ScanOptions {
    /// Elements per lane of `scan_fan` and `two_step` (2,048-element tiles), and of any
    /// implementation with staged or direct tiles.
    pub const DEFAULT_ITEMS_PER_THREAD: u32 = 8;
    /// Elements per lane of `decoupled_lookback` with vector tiles (8,192-element tiles):
    /// the bigger the tile, the fewer look-backs per byte (0.27 ms at 2^26 on the H100
    /// against 0.29 with 16 and 0.34 with 8).
    pub const DEFAULT_LOOKBACK_ITEMS_PER_THREAD: u32 = 32;

    /// Vector tiles of [`Self::DEFAULT_ITEMS_PER_THREAD`] elements per lane.
    pub fn new(count: u32) -> Self {
        Self {
            count,
            inclusive: false,
            subgroups: Subgroups::Auto,
            items_per_thread: Self::DEFAULT_ITEMS_PER_THREAD,
            tile_access: TileAccess::Vector,
        }
    }

    /// The defaults of `decoupled_lookback`: vector tiles of
    /// [`Self::DEFAULT_LOOKBACK_ITEMS_PER_THREAD`] elements per lane.
    pub fn for_lookback(count: u32) -> Self {
        Self {
            items_per_thread: Self::DEFAULT_LOOKBACK_ITEMS_PER_THREAD,
            ..Self::new(count)
        }
    }

    /// Reads `count`, `inclusive`, `subgroups` ("auto" | "off"), `items_per_thread` and
    /// `tile_access` ("vector" | "staged" | "direct"), with the defaults of `scan_fan`.
    pub fn from_params(params: &Params) -> Result<Self> {
        Self::from_params_with(params, |_| Self::DEFAULT_ITEMS_PER_THREAD)
    }

    /// [`Self::from_params`] with the defaults of `decoupled_lookback`.
    pub fn from_params_for_lookback(params: &Params) -> Result<Self> {
        Self::from_params_with(params, Self::lookback_items)
    }

    /// The default `items_per_thread` of `decoupled_lookback` with `tile_access`.
    pub fn lookback_items(tile_access: TileAccess) -> u32 {
        match tile_access {
            TileAccess::Vector => Self::DEFAULT_LOOKBACK_ITEMS_PER_THREAD,
            TileAccess::Staged | TileAccess::Direct => Self::DEFAULT_ITEMS_PER_THREAD,
        }
    }

    fn from_params_with(params: &Params, default_items: fn(TileAccess) -> u32) -> Result<Self> {
        params.only(&PARAM_KEYS)?;
        let tile_access = TileAccess::parse(&params.string("tile_access", "vector")?)?;
        let options = Self {
            count: params.u32("count", 0)?,
            inclusive: params.bool("inclusive", false)?,
            subgroups: Subgroups::parse(&params.string("subgroups", "auto")?)?,
            items_per_thread: params.u32("items_per_thread", default_items(tile_access))?,
            tile_access,
        };
        options.validate()?;
        Ok(options)
    }

    /// Elements per tile.
    pub fn tile(&self) -> u32 {
        WORKGROUP * self.items_per_thread
    }

    /// Refuses options no kernel runs (an `items_per_thread` other than the listed ones,
    /// 32 without vector tiles, a count past 2^31), naming the parameter to change.
    pub fn validate(&self) -> Result<()> {
        let bad = |message: String| Err(GraphError::parameter(message));
        if !matches!(self.items_per_thread, 1 | 2 | 4 | 8 | 16 | 32) {
            return bad(format!(
                "`items_per_thread` = {} must be 1, 2, 4, 8 or 16 (32 with vector tiles)",
                self.items_per_thread
            ));
        }
        if self.items_per_thread == 32 && self.tile_access != TileAccess::Vector {
            return bad(
                "`items_per_thread` = 32 needs `tile_access = \"vector\"` (a staged tile of 8,192 \
                 elements does not fit workgroup memory)"
                    .to_string(),
            );
        }
        if self.count > MAX_COUNT {
            return bad(format!(
                "`count` = {} exceeds the largest supported scan, {MAX_COUNT}; split the data",
                self.count
            ));
        }
        Ok(())
    }
}

/// Registers the implementations of stage `scan_fan` for pipeline files.
pub fn register(registry: &mut Registry) {
    registry.register(STAGE, "scan_fan", |p| {
        ScanOptions::from_params(p).map(ScanFan::with_options)
    });
    registry.register(STAGE, "two_step", |p| {
        ScanOptions::from_params(p).map(TwoStep::with_options)
    });
    registry.register(STAGE, "decoupled_lookback", |p| {
        ScanOptions::from_params_for_lookback(p).map(DecoupledLookback::with_options)
    });
}
