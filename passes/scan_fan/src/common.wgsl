#define_import_path scan_fan::common

// What every tile layout of the scan shares: the parameters, the bindings of the levels,
// the invocation's builtins, and the workgroup-wide Hillis–Steele scan.
//
// Levels: level 0 is `input` -> `output`. Level l > 0 holds the tile totals of level l - 1
// and lives in the `fan` scratch buffer at `params.src_offset`; it is scanned in place.
// Work is cut into tiles of WG lanes × ITEMS elements. All sums are u32 and wrap modulo
// 2^32, like the CPU reference.

// The uniform block, declared once for Rust and WGSL by `GpuParams` in kernels.rs.
#import scan_fan::params::Params

// Write inclusive sums (element i includes itself) instead of exclusive ones.
const FLAG_INCLUSIVE: u32 = 1u;
// Add the tile's carry, read from the next level, to every element of the tile.
const FLAG_CARRY: u32 = 2u;
// Write the sum of the whole level to `total[0]` (the top level, a single tile).
const FLAG_TOTAL: u32 = 4u;
// `dispatch_args`: launch at least one workgroup for level 0 even when the count is 0, so
// a single-pass scan still writes `total[0]`.
const FLAG_ONE_GROUP_AT_LEAST: u32 = 8u;
// `lookback`: tiles from the counter in `state[0]` (else tile 0: one tile, no waiting).
const FLAG_TILE_COUNTER: u32 = 32u;

const WG: u32 = 256u;
const ITEMS: u32 = #{ITEMS};
const TILE: u32 = WG * ITEMS;
// Dispatch dimensions are capped by the API; larger grids are split into rows.
const MAX_GROUPS_PER_DIM: u32 = 65535u;

// Level 0 values, read once per element by `reduce` and once by `scan_add`.
@group(0) @binding(0) var<storage, read> input: array<u32>;
// Level 0 prefix sums; elements at or past the count are never written.
@group(0) @binding(1) var<storage, read_write> output: array<u32>;
// Tile totals of every level above 0, one region per level, scanned in place.
@group(0) @binding(2) var<storage, read_write> fan: array<u32>;
// total[0] = the sum of all counted elements.
@group(0) @binding(3) var<storage, read_write> total: array<u32>;
// Per-dispatch parameters.
@group(0) @binding(4) var<uniform> params: Params;
#ifdef GPU_COUNT
// gpu_count[0] = the number of elements of level 0, written by an earlier pass.
@group(0) @binding(5) var<storage, read> gpu_count: array<u32>;
#endif

// Hillis–Steele ping-pong buffers (two halves of WG).
var<workgroup> lanes: array<u32, 512>;

struct Invocation {
    @builtin(local_invocation_index) index: u32,
    @builtin(workgroup_id) workgroup: vec3<u32>,
    @builtin(num_workgroups) workgroups: vec3<u32>,
#ifdef SUBGROUPS
    @builtin(subgroup_id) subgroup: u32,
    @builtin(num_subgroups) subgroups: u32,
    @builtin(subgroup_invocation_id) subgroup_lane: u32,
    @builtin(subgroup_size) subgroup_size: u32,
#endif
}

fn div_ceil(a: u32, b: u32) -> u32 {
    return a / b + select(0u, 1u, a % b != 0u);
}

// Elements at `level`: the level-0 count, divided into tiles once per level above it.
fn level_count(level: u32) -> u32 {
#ifdef GPU_COUNT
    var n = min(gpu_count[0], params.capacity);
#else
    var n = params.count;
#endif
    for (var l = 0u; l < level; l++) {
        n = div_ceil(n, TILE);
    }
    return n;
}

fn tile_index(inv: Invocation) -> u32 {
    return inv.workgroup.x + inv.workgroup.y * inv.workgroups.x;
}

// Element i of the current level.
fn load_element(i: u32) -> u32 {
    if params.level == 0u {
        return input[i];
    }
    return fan[params.src_offset + i];
}

fn store_element(i: u32, value: u32) {
    if params.level == 0u {
        output[i] = value;
    } else {
        fan[params.src_offset + i] = value;
    }
}

// True when subgroups tile the workgroup exactly, so (subgroup, lane) orders the lanes.
// Vulkan does not promise full subgroups; when they are not, the shared-memory scan runs.
fn full_subgroups(inv: Invocation) -> bool {
#ifdef SUBGROUPS
    return inv.subgroups * inv.subgroup_size == WG;
#else
    return false;
#endif
}

// Hillis–Steele over the whole workgroup: log2(WG) steps, each adding the value `offset`
// lanes back. Returns the exclusive prefix of `value` in `position` order and the
// workgroup total. Every lane must call it.
fn scan_lanes_shared(position: u32, value: u32) -> vec2<u32> {
    lanes[position] = value;
    workgroupBarrier();
    var src = 0u;
    for (var offset = 1u; offset < WG; offset = offset << 1u) {
        let dst = WG - src;
        var x = lanes[src + position];
        if position >= offset {
            x += lanes[src + position - offset];
        }
        lanes[dst + position] = x;
        workgroupBarrier();
        src = dst;
    }
    let result = vec2(lanes[src + position] - value, lanes[src + WG - 1u]);
    workgroupBarrier();
    return result;
}
