// Prefix sum of u32 counts with vector tiles (`tile_access = "vector"`): the same kernels,
// levels and parameters as scan.wgsl, but a lane reads and writes its part of a tile in
// words of WIDTH elements, 16 bytes (a vec4<u32>) when WIDTH is 4, and keeps them in
// registers from the load to the store. Workgroup memory holds one word per subgroup.
//
// A tile is WG lanes × ITEMS elements = WG × ROWS words. The lanes are cut into groups:
// a subgroup each where subgroups tile the workgroup, else the whole workgroup. A group
// owns a contiguous run of group-size × ROWS words of the tile; in row k its lane r holds
// word k × group-size + r of that run, so every load and store of a row is one coalesced
// stretch of group-size × 16 bytes. A row is scanned across the group (one subgroup scan,
// or Hillis–Steele in workgroup memory), the rows one after another with a running sum,
// and the groups' sums are combined through workgroup memory.
//
// Views: the graph binds whole buffers at offset 0, so the vec4<u32> views (`input4`,
// `output4`, `fan4`) are 16-byte aligned; element i of a level is lane i % 4 of word i / 4,
// and every level in `fan` starts at a multiple of 4 words. Whole words below the count go
// through the vector views; the elements of a partial last word (count % 4 of them) go
// through the u32 views one by one, so elements at or past the count are never touched.
// All sums are u32 and wrap modulo 2^32, like the CPU reference.

struct Params {
    // Elements of level 0 when the count comes from the CPU (unused with GPU_COUNT).
    count: u32,
    // The level this dispatch works on (0 = input/output, l > 0 = fan level l).
    level: u32,
    // Offset in `fan` of this level's values (levels > 0); a multiple of 4.
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

const FLAG_INCLUSIVE: u32 = 1u;
const FLAG_CARRY: u32 = 2u;
const FLAG_TOTAL: u32 = 4u;
const FLAG_ONE_GROUP_AT_LEAST: u32 = 8u;
// `lookback`: tiles from the counter in `state[0]` (else tile 0: one tile, no waiting).
const FLAG_TILE_COUNTER: u32 = 32u;

const WG: u32 = 256u;
const ITEMS: u32 = #{ITEMS};
// Elements per word: 4, or ITEMS when a lane holds fewer than 4.
const WIDTH: u32 = #{WIDTH};
// Words per lane and tile.
const ROWS: u32 = ITEMS / WIDTH;
const TILE: u32 = WG * ITEMS;
const TILE_WORDS: u32 = WG * ROWS;
const MAX_GROUPS_PER_DIM: u32 = 65535u;

@group(0) @binding(0) var<storage, read> input: array<u32>;
@group(0) @binding(1) var<storage, read_write> output: array<u32>;
@group(0) @binding(2) var<storage, read_write> fan: array<u32>;
@group(0) @binding(3) var<storage, read_write> total: array<u32>;
@group(0) @binding(4) var<uniform> params: Params;
#ifdef GPU_COUNT
@group(0) @binding(5) var<storage, read> gpu_count: array<u32>;
#endif
// The same buffers as bindings 0, 1 and 2, seen as 16-byte words.
@group(0) @binding(8) var<storage, read> input4: array<vec4<u32>>;
@group(0) @binding(9) var<storage, read_write> output4: array<vec4<u32>>;
@group(0) @binding(10) var<storage, read_write> fan4: array<vec4<u32>>;

// Per-group sums of the tile.
var<workgroup> group_sums: array<u32, WG>;
// Hillis–Steele ping-pong buffers, when the group is the whole workgroup.
var<workgroup> lanes: array<u32, 512>;

// The lane's words of the tile and, per word, the sum of its group's elements before it.
var<private> words: array<vec4<u32>, ROWS>;
var<private> before_word: array<u32, ROWS>;

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

// The lanes that scan rows together.
struct Group {
    // Which group of the workgroup.
    index: u32,
    // The lane's place in the group.
    lane: u32,
    // Lanes per group.
    size: u32,
    // Groups per workgroup.
    count: u32,
}

fn div_ceil(a: u32, b: u32) -> u32 {
    return a / b + select(0u, 1u, a % b != 0u);
}

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

fn full_subgroups(inv: Invocation) -> bool {
#ifdef SUBGROUPS
    return inv.subgroups * inv.subgroup_size == WG;
#else
    return false;
#endif
}

fn group_of(inv: Invocation) -> Group {
#ifdef SUBGROUPS
    if full_subgroups(inv) {
        return Group(inv.subgroup, inv.subgroup_lane, inv.subgroup_size, inv.subgroups);
    }
#endif
    return Group(0u, inv.index, WG, 1u);
}

fn load1(i: u32) -> u32 {
    if params.level == 0u {
        return input[i];
    }
    return fan[params.src_offset + i];
}

fn store1(i: u32, value: u32) {
    if params.level == 0u {
        output[i] = value;
    } else {
        fan[params.src_offset + i] = value;
    }
}

fn load4(w: u32) -> vec4<u32> {
    if params.level == 0u {
        return input4[w];
    }
    return fan4[params.src_offset / 4u + w];
}

fn store4(w: u32, value: vec4<u32>) {
    if params.level == 0u {
        output4[w] = value;
    } else {
        fan4[params.src_offset / 4u + w] = value;
    }
}

// Word w of the level (elements w × WIDTH onwards); lanes at or past n, and past WIDTH,
// read as 0.
fn load_word(w: u32, n: u32) -> vec4<u32> {
    let first = w * WIDTH;
    if WIDTH == 4u && first + 4u <= n {
        return load4(w);
    }
    var v = vec4(0u);
    for (var c = 0u; c < WIDTH; c++) {
        if first + c < n {
            v[c] = load1(first + c);
        }
    }
    return v;
}

// Writes the first WIDTH lanes of `value` to word w, the elements below n only.
fn store_word(w: u32, n: u32, value: vec4<u32>) {
    let first = w * WIDTH;
    if WIDTH == 4u && first + 4u <= n {
        store4(w, value);
        return;
    }
    for (var c = 0u; c < WIDTH; c++) {
        if first + c < n {
            store1(first + c, value[c]);
        }
    }
}

fn word_sum(v: vec4<u32>) -> u32 {
    return v.x + v.y + v.z + v.w;
}

// Hillis–Steele over the whole workgroup: the exclusive prefix of `value` in lane order
// and the workgroup total. Every lane must call it.
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

// The exclusive prefix of `value` over the group's lanes, and the group's sum. Every lane
// of the workgroup must call it.
fn scan_group(inv: Invocation, g: Group, value: u32) -> vec2<u32> {
#ifdef SUBGROUPS
    if full_subgroups(inv) {
        let inclusive = subgroupInclusiveAdd(value);
        return vec2(inclusive - value, subgroupShuffle(inclusive, g.size - 1u));
    }
#endif
    return scan_lanes_shared(g.lane, value);
}

// The sum of the groups before the lane's group, and of all groups, from each group's
// `sum`. Every lane of the workgroup must call it; `group_sums` may be reused only after
// a barrier.
fn combine_groups(inv: Invocation, g: Group, sum: u32) -> vec2<u32> {
#ifdef SUBGROUPS
    if full_subgroups(inv) {
        if g.lane == 0u {
            group_sums[g.index] = sum;
        }
        workgroupBarrier();
        var before = 0u;
        var all = 0u;
        for (var base = 0u; base < g.count; base += g.size) {
            let j = base + g.lane;
            var s = 0u;
            if j < g.count {
                s = group_sums[j];
            }
            before += subgroupAdd(select(0u, s, j < g.index));
            all += subgroupAdd(s);
        }
        return vec2(before, all);
    }
#endif
    return vec2(0u, sum);
}

// Word k of the lane's share of tile t.
fn word_index(t: u32, g: Group, k: u32) -> u32 {
    return t * TILE_WORDS + g.index * g.size * ROWS + k * g.size + g.lane;
}

// Word k of the lane's share of tile t of the current level; below n, the lanes past n
// read as 0. `full`: the whole tile is below n and words are vec4 (no checks).
fn fetch(t: u32, g: Group, k: u32, n: u32, full: bool) -> vec4<u32> {
    let w = word_index(t, g, k);
    if full {
        return load4(w);
    }
    return load_word(w, n);
}

// True when every word of tile t is a whole vec4 below n.
fn full_tile(t: u32, n: u32) -> bool {
    return WIDTH == 4u && t * TILE + TILE <= n;
}

// The rows below are written out one by one (k a call argument, ROWS a constant) rather
// than looped over: with a loop the compiler kept `words` in memory and serialised the
// loads (measured on the H100: 0.29 against 0.47 ms for the single pass at 2^26 with
// 8,192-element tiles, docs/BENCHMARKS.md). ROWS is at most 8.

// Rows are named by a call argument, so that no constant index past ROWS appears in
// the code a smaller ROWS leaves unreached.
fn put_word(k: u32, value: vec4<u32>) {
    words[k] = value;
}

// Loads the lane's words of tile t into `words`.
fn load_rows(t: u32, g: Group, n: u32) {
    let full = full_tile(t, n);
    put_word(0u, fetch(t, g, 0u, n, full));
    if ROWS > 1u {
        put_word(1u, fetch(t, g, 1u, n, full));
    }
    if ROWS > 2u {
        put_word(2u, fetch(t, g, 2u, n, full));
        put_word(3u, fetch(t, g, 3u, n, full));
    }
    if ROWS > 4u {
        put_word(4u, fetch(t, g, 4u, n, full));
        put_word(5u, fetch(t, g, 5u, n, full));
        put_word(6u, fetch(t, g, 6u, n, full));
        put_word(7u, fetch(t, g, 7u, n, full));
    }
}

// Row k of the group scan: `before_word[k]` = the group's sum before the lane's word k,
// from the sum of the rows before (`running`); returns the sum through row k.
fn scan_row(inv: Invocation, g: Group, k: u32, running: u32) -> u32 {
    let scanned = scan_group(inv, g, word_sum(words[k]));
    before_word[k] = running + scanned.x;
    return running + scanned.y;
}

// Scans the lane's `words` across its group, rows in order; returns the group's sum.
// Every lane of the workgroup must call it.
fn scan_rows(inv: Invocation, g: Group) -> u32 {
    var running = scan_row(inv, g, 0u, 0u);
    if ROWS > 1u {
        running = scan_row(inv, g, 1u, running);
    }
    if ROWS > 2u {
        running = scan_row(inv, g, 2u, running);
        running = scan_row(inv, g, 3u, running);
    }
    if ROWS > 4u {
        running = scan_row(inv, g, 4u, running);
        running = scan_row(inv, g, 5u, running);
        running = scan_row(inv, g, 6u, running);
        running = scan_row(inv, g, 7u, running);
    }
    return running;
}

fn store_row(g: Group, t: u32, k: u32, n: u32, start: u32, inclusive: bool, full: bool) {
    let v = words[k];
    let x0 = start + before_word[k];
    let x1 = x0 + v.x;
    let x2 = x1 + v.y;
    let x3 = x2 + v.z;
    var out = vec4(x0, x1, x2, x3);
    if inclusive {
        out = vec4(x1, x2, x3, x3 + v.w);
    }
    let w = word_index(t, g, k);
    if full {
        store4(w, out);
    } else {
        store_word(w, n, out);
    }
}

// Writes the running sums of the lane's words from `start` (the tile's carry plus the
// groups before the lane's group).
fn store_rows(g: Group, t: u32, n: u32, start: u32, inclusive: bool) {
    let full = full_tile(t, n);
    store_row(g, t, 0u, n, start, inclusive, full);
    if ROWS > 1u {
        store_row(g, t, 1u, n, start, inclusive, full);
    }
    if ROWS > 2u {
        store_row(g, t, 2u, n, start, inclusive, full);
        store_row(g, t, 3u, n, start, inclusive, full);
    }
    if ROWS > 4u {
        store_row(g, t, 4u, n, start, inclusive, full);
        store_row(g, t, 5u, n, start, inclusive, full);
        store_row(g, t, 6u, n, start, inclusive, full);
        store_row(g, t, 7u, n, start, inclusive, full);
    }
}

// Scans tile t of the current level with `carry` added; returns the tile's own total.
// `group_sums` may be reused only after a barrier.
fn scan_tile(inv: Invocation, t: u32, n: u32, carry: u32, inclusive: bool) -> u32 {
    let g = group_of(inv);
    load_rows(t, g, n);
    let sums = combine_groups(inv, g, scan_rows(inv, g));
    store_rows(g, t, n, carry + sums.x, inclusive);
    return sums.y;
}

// The sum of `value` over the workgroup, in every lane.
fn workgroup_sum(inv: Invocation, value: u32) -> u32 {
#ifdef SUBGROUPS
    if full_subgroups(inv) {
        return combine_groups(inv, group_of(inv), subgroupAdd(value)).y;
    }
#endif
    return scan_lanes_shared(inv.index, value).y;
}

// The sum of word k × WG + lane of tile t.
fn reduce_row(t: u32, k: u32, lane: u32, n: u32, full: bool) -> u32 {
    let w = t * TILE_WORDS + k * WG + lane;
    if full {
        return word_sum(load4(w));
    }
    return word_sum(load_word(w, n));
}

// Step 1: each tile's total into the next level's region of `fan`. The order does not
// matter for a sum, so consecutive lanes read consecutive words.
@compute @workgroup_size(256)
fn reduce(inv: Invocation) {
    let n = level_count(params.level);
    let t = tile_index(inv);
    if t >= div_ceil(n, TILE) {
        return;
    }
    let full = full_tile(t, n);
    var own = reduce_row(t, 0u, inv.index, n, full);
    if ROWS > 1u {
        own += reduce_row(t, 1u, inv.index, n, full);
    }
    if ROWS > 2u {
        own += reduce_row(t, 2u, inv.index, n, full) + reduce_row(t, 3u, inv.index, n, full);
    }
    if ROWS > 4u {
        own += reduce_row(t, 4u, inv.index, n, full) + reduce_row(t, 5u, inv.index, n, full);
        own += reduce_row(t, 6u, inv.index, n, full) + reduce_row(t, 7u, inv.index, n, full);
    }
    let sum = workgroup_sum(inv, own);
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

// One workgroup walks all tiles of a level in order: the two-step scheme's middle step
// (level 1), and the whole scan of a few tiles (level 0) in one dispatch.
@compute @workgroup_size(256)
fn walk(inv: Invocation) {
    let n = level_count(params.level);
    let inclusive = (params.flags & FLAG_INCLUSIVE) != 0u;
    var running = 0u;
    for (var t = 0u; t < div_ceil(n, TILE); t++) {
        running += scan_tile(inv, t, n, running, inclusive);
        workgroupBarrier();
    }
    if inv.index == 0u {
        total[0] = running;
    }
}

#ifdef GPU_COUNT
@group(0) @binding(6) var<storage, read_write> args: array<u32>;

// As in scan.wgsl: the tile grid of every level from the GPU count.
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
// Single pass: decoupled look-back, as in scan.wgsl (see the comments there), with the
// tile held in registers while the carry is found.

@group(0) @binding(7) var<storage, read_write> state: array<atomic<u32>>;

const STATE_NONE: u32 = 0u;
const STATE_AGGREGATE: u32 = 1u;
const STATE_PREFIX: u32 = 2u;

var<workgroup> taken_tile: u32;
var<workgroup> tile_carry: u32;

fn publish(t: u32, flag: u32, value: u32) {
    atomicStore(&state[1u + 2u * t], (flag << 16u) | (value & 0xffffu));
    atomicStore(&state[2u + 2u * t], (flag << 16u) | (value >> 16u));
}

fn observe(t: u32) -> vec2<u32> {
    let low = atomicLoad(&state[1u + 2u * t]);
    let high = atomicLoad(&state[2u + 2u * t]);
    if (low >> 16u) != (high >> 16u) {
        return vec2(STATE_NONE, 0u);
    }
    return vec2(low >> 16u, (high << 16u) | (low & 0xffffu));
}

const SPIN_LIMIT: u32 = 1024u;

fn reduce_tile_alone(t: u32, n: u32) -> u32 {
    var sum = 0u;
    let end = min(t * TILE + TILE, n);
    for (var i = t * TILE; i < end; i++) {
        sum += input[i];
    }
    return sum;
}

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
    let g = group_of(inv);
    load_rows(t, g, n);
    let sums = combine_groups(inv, g, scan_rows(inv, g));
    let carry = find_carry(inv, t, tiles, n, sums.y);
    store_rows(g, t, n, carry + sums.x, (params.flags & FLAG_INCLUSIVE) != 0u);
}
