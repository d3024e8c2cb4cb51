#define_import_path scan_fan::staged_tile

// Tiles of single elements (`tile_access = "staged"` or `"direct"`): a lane owns ITEMS
// consecutive elements of its tile, scans them serially, and the lanes' totals are
// scanned across the workgroup (Hillis–Steele in workgroup memory, or subgroup scans when
// the adapter has them). With ITEMS = 1 a tile is exactly one 256-element Hillis–Steele
// chunk.
//
// What `scan.wgsl` calls, as for every tile layout: `load_tile`, `store_tile`,
// `tile_total` and `between_tiles`.

#import scan_fan::common::{Invocation, WG, ITEMS, TILE, load_element, store_element, full_subgroups, scan_lanes_shared}

// One tile, padded every 32 words so lanes reading ITEMS consecutive words hit distinct banks.
var<workgroup> tile: array<u32, TILE + TILE / 32u>;
// Per-subgroup totals, then their exclusive prefixes.
var<workgroup> subgroup_sums: array<u32, 256>;
// The workgroup total, broadcast from the lane that computed it.
var<workgroup> workgroup_total: u32;

fn padded(i: u32) -> u32 {
    return i + (i >> 5u);
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
            v = load_element(base + first + k);
        }
        items[k] = v;
        own += v;
    }
#else
    for (var k = 0u; k < ITEMS; k++) {
        let j = k * WG + inv.index;
        var v = 0u;
        if base + j < n {
            v = load_element(base + j);
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
            store_element(base + first + k, out);
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
            store_element(base + j, tile[padded(j)]);
        }
    }
    // The tile is reused by the caller's next iteration.
    workgroupBarrier();
#endif
}

// Reads tile t of the current level (n elements): the sum of the elements before the
// lane's and the tile's total. Every lane of the workgroup must call it.
fn load_tile(inv: Invocation, t: u32, n: u32) -> vec2<u32> {
    let position = lane_position(inv);
    return scan_lanes(inv, position, gather(inv, position, t * TILE, n));
}

// Writes the lane's running sums of the tile `load_tile` read, from `start`.
fn store_tile(inv: Invocation, t: u32, n: u32, start: u32, inclusive: bool) {
    scatter(inv, lane_position(inv), t * TILE, n, start, inclusive);
}

// The sum of tile t. The order does not matter for a sum, so consecutive lanes read
// consecutive elements.
fn tile_total(inv: Invocation, t: u32, n: u32) -> u32 {
    let base = t * TILE;
    var own = 0u;
    for (var k = 0u; k < ITEMS; k++) {
        let i = base + k * WG + inv.index;
        if i < n {
            own += load_element(i);
        }
    }
    return scan_lanes(inv, lane_position(inv), own).y;
}

// Between two tiles of one workgroup: nothing, `scatter` and the lane scans end on a
// barrier.
fn between_tiles() {}
