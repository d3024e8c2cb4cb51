#define_import_path scan_fan::vector_tile

// Vector tiles (`tile_access = "vector"`, WIDTH given): a lane reads and writes its part of
// a tile in words of WIDTH elements, 16 bytes (a vec4<u32>) when WIDTH is 4, and keeps them
// in registers from the load to the store. Workgroup memory holds one word per subgroup.
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
//
// What `scan.wgsl` calls, as for every tile layout: `load_tile`, `store_tile`,
// `tile_total` and `between_tiles`.

#import scan_fan::common::{Invocation, WG, ITEMS, TILE, params, load_element, store_element, full_subgroups, scan_lanes_shared}

// Elements per word: 4, or ITEMS when a lane holds fewer than 4.
const WIDTH: u32 = #{WIDTH};
// Words per lane and tile.
const ROWS: u32 = ITEMS / WIDTH;
const TILE_WORDS: u32 = WG * ROWS;

// The same buffers as bindings 0, 1 and 2, seen as 16-byte words.
@group(0) @binding(8) var<storage, read> input4: array<vec4<u32>>;
@group(0) @binding(9) var<storage, read_write> output4: array<vec4<u32>>;
@group(0) @binding(10) var<storage, read_write> fan4: array<vec4<u32>>;

// Per-group sums of the tile.
var<workgroup> group_sums: array<u32, WG>;

// The lane's words of the tile and, per word, the sum of its group's elements before it.
var<private> words: array<vec4<u32>, ROWS>;
var<private> before_word: array<u32, ROWS>;

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

fn group_of(inv: Invocation) -> Group {
#ifdef SUBGROUPS
    if full_subgroups(inv) {
        return Group(inv.subgroup, inv.subgroup_lane, inv.subgroup_size, inv.subgroups);
    }
#endif
    return Group(0u, inv.index, WG, 1u);
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
            v[c] = load_element(first + c);
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
            store_element(first + c, value[c]);
        }
    }
}

fn word_sum(v: vec4<u32>) -> u32 {
    return v.x + v.y + v.z + v.w;
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

// Reads tile t of the current level (n elements) into the lane's registers: the sum of
// the elements before the lane's words in the tile, and the tile's total. Every lane of
// the workgroup must call it; `group_sums` may be reused only after a barrier.
fn load_tile(inv: Invocation, t: u32, n: u32) -> vec2<u32> {
    let g = group_of(inv);
    load_rows(t, g, n);
    return combine_groups(inv, g, scan_rows(inv, g));
}

// Writes the running sums of the words `load_tile` read, from `start`.
fn store_tile(inv: Invocation, t: u32, n: u32, start: u32, inclusive: bool) {
    store_rows(group_of(inv), t, n, start, inclusive);
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

// The sum of tile t. The order does not matter for a sum, so consecutive lanes read
// consecutive words.
fn tile_total(inv: Invocation, t: u32, n: u32) -> u32 {
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
    return workgroup_sum(inv, own);
}

// Between two tiles of one workgroup: `group_sums` is reused.
fn between_tiles() {
    workgroupBarrier();
}
