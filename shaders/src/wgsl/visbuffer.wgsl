#define_import_path meshlight::visbuffer

// The visibility buffer: one 64-bit value per pixel,
//     depth_bits << 32 | cluster << 7 | triangle
// written with a 64-bit atomicMax so the nearest triangle wins. With reverse-Z the
// nearest surface has the largest depth, and the bits of non-negative floats order like
// the floats, so no conversion is needed. Ties at equal depth go to the larger
// cluster/triangle id, which keeps the result independent of thread order.
//
// This module uses the pair form vec2<u32>(low word, high word), which is how the u64 is
// laid out in memory (little-endian), so it works on devices without 64-bit integers;
// `meshlight::visbuffer64` adds the u64 form. `cpu::visbuffer` is the Rust reference.

const VISBUFFER_TRIANGLE_BITS: u32 = 7u;
const VISBUFFER_CLUSTER_BITS: u32 = 25u;
const VISBUFFER_TRIANGLE_MASK: u32 = 0x7fu;
// Clusters per frame at most: ids must fit in 25 bits.
const VISBUFFER_MAX_CLUSTERS: u32 = 0x2000000u;

// The cleared value: depth 0 is the far plane at infinity, where nothing is drawn.
const VISBUFFER_EMPTY: vec2<u32> = vec2<u32>(0u, 0u);

// The depth as ordered bits: clamped to [0, 1] so NaN and -0.0 cannot win atomicMax.
fn visbuffer_depth_bits(depth: f32) -> u32 {
    // max(NaN, 0) may return either operand; select makes NaN map to 0 explicitly.
    let d = select(0.0, min(depth, 1.0), depth > 0.0);
    return bitcast<u32>(d);
}

// The low word: cluster (25 bits) above triangle (7 bits).
fn visbuffer_payload(cluster: u32, triangle: u32) -> u32 {
    return (cluster << VISBUFFER_TRIANGLE_BITS) | (triangle & VISBUFFER_TRIANGLE_MASK);
}

fn visbuffer_pack(depth: f32, cluster: u32, triangle: u32) -> vec2<u32> {
    return vec2(visbuffer_payload(cluster, triangle), visbuffer_depth_bits(depth));
}

fn visbuffer_depth(value: vec2<u32>) -> f32 {
    return bitcast<f32>(value.y);
}

fn visbuffer_cluster(value: vec2<u32>) -> u32 {
    return value.x >> VISBUFFER_TRIANGLE_BITS;
}

fn visbuffer_triangle(value: vec2<u32>) -> u32 {
    return value.x & VISBUFFER_TRIANGLE_MASK;
}

fn visbuffer_is_empty(value: vec2<u32>) -> bool {
    return value.y == 0u;
}

// True when `a` would win atomicMax over `b` (compares the pairs as u64).
fn visbuffer_nearer(a: vec2<u32>, b: vec2<u32>) -> bool {
    return a.y > b.y || (a.y == b.y && a.x > b.x);
}
