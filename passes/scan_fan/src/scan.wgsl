// Prefix sum of u32 counts: the kernels of every implementation of stage `scan_fan`, for
// both tile layouts. The kernels see a tile only through `load_tile`, `store_tile`,
// `tile_total` and `between_tiles`, which the layout's module gives: vector tiles
// (`vector_tile.wgsl`) where WIDTH, the vector width, is given, else tiles of single
// elements, staged through workgroup memory or direct (`staged_tile.wgsl`). What the
// layouts share, the parameters, the levels' bindings and the Hillis–Steele scan, is in
// `common.wgsl`.

#import scan_fan::common::{Invocation, TILE, MAX_GROUPS_PER_DIM, FLAG_INCLUSIVE, FLAG_CARRY, FLAG_TOTAL, FLAG_ONE_GROUP_AT_LEAST, FLAG_TILE_COUNTER, params, input, fan, total, div_ceil, level_count, tile_index, full_subgroups}
#ifdef GPU_COUNT
#import scan_fan::common::gpu_count
#endif
#ifdef WIDTH
#import scan_fan::vector_tile::{load_tile, store_tile, tile_total, between_tiles}
#else
#import scan_fan::staged_tile::{load_tile, store_tile, tile_total, between_tiles}
#endif

// Scans tile `t` of the current level (n elements) with `carry` added to every element.
// Returns the tile's own total (without the carry).
fn scan_tile(inv: Invocation, t: u32, n: u32, carry: u32, inclusive: bool) -> u32 {
    let scanned = load_tile(inv, t, n);
    store_tile(inv, t, n, carry + scanned.x, inclusive);
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
    let sum = tile_total(inv, t, n);
    if inv.index == 0u {
        fan[params.dst_offset + t] = sum;
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
        between_tiles();
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
// device schedules workgroups). With vector tiles the tile stays in registers while the
// carry is found.
//
// A tile's state is 32 bits of sum plus a flag, which one u32 cannot hold, and 64-bit
// atomics are not everywhere. So the sum is split into two 16-bit halves, each in its own
// word beside a copy of the flag. Every flag value is written once per word, so a reader
// that sees the same flag in both words has both halves of one publication; on a mismatch
// it reads again.

// state[0]: the tile counter; state[1 + 2t], state[2 + 2t]: tile t's low and high halves,
// each `flag << 16 | half`. Cleared to 0 (no flag) before every dispatch that waits.
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

// Takes a tile from the counter (lane 0 asks; every lane gets it). Written once per
// workgroup, so one barrier is enough to read it.
fn take_tile(inv: Invocation) -> u32 {
    if inv.index == 0u {
        taken_tile = atomicAdd(&state[0], 1u);
    }
    workgroupBarrier();
    return taken_tile;
}

// Finds the carry of tile t with its own sum `aggregate` and publishes its inclusive
// prefix; returns the carry in every lane. Every lane of the workgroup must call it.
fn find_carry(inv: Invocation, t: u32, tiles: u32, n: u32, aggregate: u32) -> u32 {
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
    // Written once per workgroup, so one barrier is enough to read it.
    workgroupBarrier();
    return tile_carry;
}

@compute @workgroup_size(256)
fn lookback(inv: Invocation) {
    let n = level_count(0u);
    let tiles = max(div_ceil(n, TILE), 1u);
    // Without the counter (one tile, its count known on the CPU) the tile is 0.
    var t = 0u;
    if (params.flags & FLAG_TILE_COUNTER) != 0u {
        t = take_tile(inv);
    }
    // The surplus of the last row of a split grid.
    if t >= tiles {
        return;
    }
    let scanned = load_tile(inv, t, n);
    let carry = find_carry(inv, t, tiles, n, scanned.y);
    store_tile(inv, t, n, carry + scanned.x, (params.flags & FLAG_INCLUSIVE) != 0u);
}
