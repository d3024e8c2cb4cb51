// Prefix sum of u32 counts, shared by both implementations of stage `scan_fan`.
//
// Work is cut into tiles of WG lanes × ITEMS elements. A lane owns ITEMS consecutive
// elements of its tile, scans them serially in registers, and the lanes' totals are scanned
// across the workgroup (Hillis–Steele in workgroup memory, or subgroup scans when the
// adapter has them). With ITEMS = 1 a tile is exactly one 256-element Hillis–Steele chunk.
//
// Levels: level 0 is `input` -> `output`. Level l > 0 holds the tile totals of level l - 1
// and lives in the `fan` scratch buffer at `params.src_offset`; it is scanned in place.
// All sums are u32 and wrap modulo 2^32, like the CPU reference.

struct Params {
    // Elements of level 0 when the count comes from the CPU (unused with GPU_COUNT).
    count: u32,
    // The level this dispatch works on (0 = input/output, l > 0 = fan level l).
    level: u32,
    // Offset in `fan` of this level's values (levels > 0).
    src_offset: u32,
    // Offset in `fan` of the next level: `reduce` writes tile totals there, `scan_add` reads
    // each tile's carry from there.
    dst_offset: u32,
    // FLAG_* bits.
    flags: u32,
    // The most elements level 0 may hold; a GPU count above it is clamped.
    capacity: u32,
    // Levels whose dispatch arguments `dispatch_args` writes (GPU_COUNT only).
    indirect_levels: u32,
    _pad: u32,
}

// Write inclusive sums (element i includes itself) instead of exclusive ones.
const FLAG_INCLUSIVE: u32 = 1u;
// Add the tile's carry, read from the next level, to every element of the tile.
const FLAG_CARRY: u32 = 2u;
// Write the sum of the whole level to `total[0]` (the top level, a single tile).
const FLAG_TOTAL: u32 = 4u;
// `dispatch_args`: launch at least one workgroup for level 0 even when the count is 0, so
// a single-pass scan still writes `total[0]`.
const FLAG_ONE_GROUP_AT_LEAST: u32 = 8u;

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

// One tile, padded every 32 words so lanes reading ITEMS consecutive words hit distinct banks.
var<workgroup> tile: array<u32, TILE + TILE / 32u>;
// Hillis–Steele ping-pong buffers (two halves of WG).
var<workgroup> lanes: array<u32, 512>;
// Per-subgroup totals, then their exclusive prefixes.
var<workgroup> subgroup_sums: array<u32, 256>;
// The workgroup total, broadcast from the lane that computed it.
var<workgroup> workgroup_total: u32;

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

fn padded(i: u32) -> u32 {
    return i + (i >> 5u);
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

fn load(i: u32) -> u32 {
    if params.level == 0u {
        return input[i];
    }
    return fan[params.src_offset + i];
}

fn store(i: u32, value: u32) {
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

// The lane's place in the tile's order.
fn lane_position(inv: Invocation) -> u32 {
#ifdef SUBGROUPS
    if full_subgroups(inv) {
        return inv.subgroup * inv.subgroup_size + inv.subgroup_lane;
    }
#endif
    return inv.index;
}

// Exclusive prefix of `value` over lanes in `position` order, and the workgroup total.
// Every lane of the workgroup must call it.
fn scan_lanes(inv: Invocation, position: u32, value: u32) -> vec2<u32> {
#ifdef SUBGROUPS
    if full_subgroups(inv) {
        return scan_lanes_subgroups(inv, value);
    }
#endif
    return scan_lanes_shared(position, value);
}

// Hillis–Steele: log2(WG) steps, each adding the value `offset` lanes back.
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

#ifdef SUBGROUPS
// Scan within each subgroup, then the first subgroup scans the subgroup totals in blocks
// of its own size, so any subgroup size from 1 to WG works.
fn scan_lanes_subgroups(inv: Invocation, value: u32) -> vec2<u32> {
    let inclusive = subgroupInclusiveAdd(value);
    if inv.subgroup_lane == inv.subgroup_size - 1u {
        subgroup_sums[inv.subgroup] = inclusive;
    }
    workgroupBarrier();
    if inv.subgroup == 0u {
        var carry = 0u;
        for (var base = 0u; base < inv.subgroups; base += inv.subgroup_size) {
            let i = base + inv.subgroup_lane;
            var s = 0u;
            if i < inv.subgroups {
                s = subgroup_sums[i];
            }
            let before = subgroupExclusiveAdd(s);
            if i < inv.subgroups {
                subgroup_sums[i] = before + carry;
            }
            carry += subgroupAdd(s);
        }
        if inv.subgroup_lane == 0u {
            workgroup_total = carry;
        }
    }
    workgroupBarrier();
    let result = vec2(subgroup_sums[inv.subgroup] + inclusive - value, workgroup_total);
    workgroupBarrier();
    return result;
}
#endif

#ifdef DIRECT
// The lane's ITEMS elements, held in registers between `gather` and `scatter`.
var<private> items: array<u32, ITEMS>;
#endif

// Reads the tile at `base` and returns the sum of the lane's ITEMS consecutive elements
// (from `position * ITEMS`). Staged: consecutive lanes load consecutive elements into
// workgroup memory, then each lane sums its run there. Direct: each lane loads its own
// run straight into registers, which saves two passes over workgroup memory and a
// barrier, and relies on the cache to merge the lanes' strided loads.
fn gather(inv: Invocation, position: u32, base: u32, n: u32) -> u32 {
    let first = position * ITEMS;
    var own = 0u;
#ifdef DIRECT
    for (var k = 0u; k < ITEMS; k++) {
        var v = 0u;
        if base + first + k < n {
            v = load(base + first + k);
        }
        items[k] = v;
        own += v;
    }
#else
    for (var k = 0u; k < ITEMS; k++) {
        let j = k * WG + inv.index;
        var v = 0u;
        if base + j < n {
            v = load(base + j);
        }
        tile[padded(j)] = v;
    }
    workgroupBarrier();
    for (var k = 0u; k < ITEMS; k++) {
        own += tile[padded(first + k)];
    }
#endif
    return own;
}

// Writes the lane's run of the tile gathered by `gather` as running sums from `start`,
// the same way it was read. Every lane of the workgroup must call it.
fn scatter(inv: Invocation, position: u32, base: u32, n: u32, start: u32, inclusive: bool) {
    let first = position * ITEMS;
    var running = start;
#ifdef DIRECT
    for (var k = 0u; k < ITEMS; k++) {
        let v = items[k];
        var out = running;
        running += v;
        if inclusive {
            out = running;
        }
        if base + first + k < n {
            store(base + first + k, out);
        }
    }
#else
    for (var k = 0u; k < ITEMS; k++) {
        let v = tile[padded(first + k)];
        if inclusive {
            running += v;
            tile[padded(first + k)] = running;
        } else {
            tile[padded(first + k)] = running;
            running += v;
        }
    }
    workgroupBarrier();
    for (var k = 0u; k < ITEMS; k++) {
        let j = k * WG + inv.index;
        if base + j < n {
            store(base + j, tile[padded(j)]);
        }
    }
    // The tile is reused by the caller's next iteration.
    workgroupBarrier();
#endif
}

// Scans tile `t` of the current level (n elements) with `carry` added to every element.
// Returns the tile's own total (without the carry).
fn scan_tile(inv: Invocation, t: u32, n: u32, carry: u32, inclusive: bool) -> u32 {
    let position = lane_position(inv);
    let own = gather(inv, position, t * TILE, n);
    let scanned = scan_lanes(inv, position, own);
    scatter(inv, position, t * TILE, n, carry + scanned.x, inclusive);
    return scanned.y;
}

// Step 1: each tile's total into the next level's region of `fan`.
@compute @workgroup_size(256)
fn reduce(inv: Invocation) {
    let n = level_count(params.level);
    let t = tile_index(inv);
    if t >= div_ceil(n, TILE) {
        return;
    }
    let base = t * TILE;
    var own = 0u;
    for (var k = 0u; k < ITEMS; k++) {
        let i = base + k * WG + inv.index;
        if i < n {
            own += load(i);
        }
    }
    // Any lane order gives the same sum, so the position is the plain index.
    let sums = scan_lanes(inv, lane_position(inv), own);
    if inv.index == 0u {
        fan[params.dst_offset + t] = sums.y;
    }
}

// Steps 2 and 3: scan each tile and add its carry from the (already scanned) next level.
// The top level is one tile; it runs even when empty so the total is always written.
@compute @workgroup_size(256)
fn scan_add(inv: Invocation) {
    let n = level_count(params.level);
    let t = tile_index(inv);
    if t >= max(div_ceil(n, TILE), 1u) {
        return;
    }
    var carry = 0u;
    if (params.flags & FLAG_CARRY) != 0u {
        carry = fan[params.dst_offset + t];
    }
    let sum = scan_tile(inv, t, n, carry, (params.flags & FLAG_INCLUSIVE) != 0u);
    if (params.flags & FLAG_TOTAL) != 0u && inv.index == 0u {
        total[0] = sum;
    }
}

// One workgroup walks all tiles of a level in order, scanning each with the running
// total of the tiles before it: the two-step scheme's middle step (level 1), and the
// whole scan of a few tiles (level 0) in one dispatch.
@compute @workgroup_size(256)
fn walk(inv: Invocation) {
    let n = level_count(params.level);
    let inclusive = (params.flags & FLAG_INCLUSIVE) != 0u;
    var running = 0u;
    for (var t = 0u; t < div_ceil(n, TILE); t++) {
        running += scan_tile(inv, t, n, running, inclusive);
    }
    if inv.index == 0u {
        total[0] = running;
    }
}

#ifdef GPU_COUNT
// Indirect dispatch arguments, three words per level below the top.
@group(0) @binding(6) var<storage, read_write> args: array<u32>;

// One invocation turns the GPU count into the tile grid of every level, splitting grids
// wider than MAX_GROUPS_PER_DIM into rows (the kernels skip the surplus of the last row).
@compute @workgroup_size(1)
fn dispatch_args() {
    var n = min(gpu_count[0], params.capacity);
    for (var l = 0u; l < params.indirect_levels; l++) {
        var tiles = div_ceil(n, TILE);
        if l == 0u && (params.flags & FLAG_ONE_GROUP_AT_LEAST) != 0u {
            tiles = max(tiles, 1u);
        }
        let rows = max(div_ceil(tiles, MAX_GROUPS_PER_DIM), 1u);
        args[3u * l] = div_ceil(tiles, rows);
        args[3u * l + 1u] = rows;
        args[3u * l + 2u] = 1u;
        n = tiles;
    }
}
#endif

// ---------------------------------------------------------------------------------------
// Single pass: Merrill and Garland's decoupled look-back.
//
// Each workgroup takes the next tile from a counter, so tiles are handed out in the order
// workgroups start and a workgroup only ever waits on tiles that started before it. It
// reduces its tile, publishes the tile's total (AGGREGATE), walks back over its
// predecessors adding their totals until one has published its inclusive prefix (PREFIX),
// publishes its own inclusive prefix, then scans the tile with that carry. Each element is
// read once and written once. A predecessor silent for too long has its tile reduced by
// the waiting workgroup instead (a bounded wait, so correctness never depends on how the
// device schedules workgroups).
//
// A tile's state is 32 bits of sum plus a flag, which one u32 cannot hold, and 64-bit
// atomics are not everywhere. So the sum is split into two 16-bit halves, each in its own
// word beside a copy of the flag. Every flag value is written once per word, so a reader
// that sees the same flag in both words has both halves of one publication; on a mismatch
// it reads again.

// state[0]: the tile counter; state[1 + 2t], state[2 + 2t]: tile t's low and high halves,
// each `flag << 16 | half`. Cleared to 0 (no flag) before every dispatch.
@group(0) @binding(7) var<storage, read_write> state: array<atomic<u32>>;

const STATE_NONE: u32 = 0u;
const STATE_AGGREGATE: u32 = 1u;
const STATE_PREFIX: u32 = 2u;

// The tile this workgroup took from the counter.
var<workgroup> taken_tile: u32;
// The sum of every tile before it, found by the look-back.
var<workgroup> tile_carry: u32;

fn publish(t: u32, flag: u32, value: u32) {
    atomicStore(&state[1u + 2u * t], (flag << 16u) | (value & 0xffffu));
    atomicStore(&state[2u + 2u * t], (flag << 16u) | (value >> 16u));
}

// (flag, value) of tile t; STATE_NONE while nothing consistent is published.
fn observe(t: u32) -> vec2<u32> {
    let low = atomicLoad(&state[1u + 2u * t]);
    let high = atomicLoad(&state[2u + 2u * t]);
    if (low >> 16u) != (high >> 16u) {
        return vec2(STATE_NONE, 0u);
    }
    return vec2(low >> 16u, (high << 16u) | (low & 0xffffu));
}

// Looks at a silent predecessor this many times before reducing its tile itself. Far
// longer than a running workgroup takes to publish on a GPU; on lavapipe, whose loops are
// also cut off after 65,535 iterations, it keeps every loop short.
const SPIN_LIMIT: u32 = 1024u;

// The sum of tile t's elements, by one lane: the fallback when its workgroup has not
// published (it may not be running, or not yet started), so no workgroup ever depends on
// another one making progress.
fn reduce_tile_alone(t: u32, n: u32) -> u32 {
    var sum = 0u;
    let end = min(t * TILE + TILE, n);
    for (var i = t * TILE; i < end; i++) {
        sum += input[i];
    }
    return sum;
}

// The exclusive prefix of tile t: its predecessors' totals back to the nearest published
// inclusive prefix (or to tile 0).
fn look_back(t: u32, n: u32) -> u32 {
    var sum = 0u;
    for (var i = t; i > 0u; i--) {
        var seen = vec2(STATE_NONE, 0u);
        for (var spin = 0u; spin < SPIN_LIMIT && seen.x == STATE_NONE; spin++) {
            seen = observe(i - 1u);
        }
        if seen.x == STATE_NONE {
            seen = vec2(STATE_AGGREGATE, reduce_tile_alone(i - 1u, n));
        }
        sum += seen.y;
        if seen.x == STATE_PREFIX {
            break;
        }
    }
    return sum;
}

#ifdef SUBGROUPS
// No lane: larger than any subgroup lane index.
const NO_LANE: u32 = 0xffffffffu;

// `look_back` by a whole subgroup: lane k looks at tile i - 1 - k, so one round trip to
// memory covers as many predecessors as the subgroup has lanes. Lanes past tile 0 see an
// inclusive prefix of 0. Every lane of the subgroup must call it.
fn look_back_subgroup(inv: Invocation, t: u32, n: u32) -> u32 {
    let k = inv.subgroup_lane;
    var sum = 0u;
    var i = t;
    loop {
        if i == 0u {
            break;
        }
        var seen = vec2(STATE_PREFIX, 0u);
        var first_prefix = NO_LANE;
        var first_none = NO_LANE;
        for (var spin = 0u; spin < SPIN_LIMIT; spin++) {
            if k < i {
                seen = observe(i - 1u - k);
            }
            first_prefix = subgroupMin(select(NO_LANE, k, seen.x == STATE_PREFIX));
            first_none = subgroupMin(select(NO_LANE, k, seen.x == STATE_NONE));
            // Every tile back to the nearest prefix has its total.
            if first_none == NO_LANE || first_none > first_prefix {
                break;
            }
        }
        if seen.x == STATE_NONE && k < first_prefix {
            seen = vec2(STATE_AGGREGATE, reduce_tile_alone(i - 1u - k, n));
        }
        sum += subgroupAdd(select(0u, seen.y, k <= first_prefix));
        if first_prefix != NO_LANE {
            break;
        }
        i -= inv.subgroup_size;
    }
    return sum;
}
#endif

// Publishes tile t's total, finds its carry and publishes its inclusive prefix; the carry
// goes to `tile_carry`. Called by the lanes that do the look-back, `leader` among them.
fn resolve_carry(t: u32, tiles: u32, aggregate: u32, carry: u32, leader: bool) {
    if leader {
        publish(t, STATE_PREFIX, carry + aggregate);
        if t == tiles - 1u {
            total[0] = carry + aggregate;
        }
        tile_carry = carry;
    }
}

@compute @workgroup_size(256)
fn lookback(inv: Invocation) {
    let n = level_count(0u);
    let tiles = max(div_ceil(n, TILE), 1u);
    if inv.index == 0u {
        taken_tile = atomicAdd(&state[0], 1u);
    }
    let t = workgroupUniformLoad(&taken_tile);
    // The surplus of the last row of a split grid.
    if t >= tiles {
        return;
    }
    let position = lane_position(inv);
    let own = gather(inv, position, t * TILE, n);
    let scanned = scan_lanes(inv, position, own);
    let aggregate = scanned.y;
#ifdef SUBGROUPS
    if full_subgroups(inv) {
        if inv.subgroup == 0u {
            let leader = inv.subgroup_lane == 0u;
            if leader && t > 0u {
                publish(t, STATE_AGGREGATE, aggregate);
            }
            var carry = 0u;
            if t > 0u {
                carry = look_back_subgroup(inv, t, n);
            }
            resolve_carry(t, tiles, aggregate, carry, leader);
        }
    } else {
#endif
        if inv.index == 0u {
            var carry = 0u;
            if t > 0u {
                publish(t, STATE_AGGREGATE, aggregate);
                carry = look_back(t, n);
            }
            resolve_carry(t, tiles, aggregate, carry, true);
        }
#ifdef SUBGROUPS
    }
#endif
    let carry = workgroupUniformLoad(&tile_carry);
    scatter(inv, position, t * TILE, n, carry + scanned.x, (params.flags & FLAG_INCLUSIVE) != 0u);
}
