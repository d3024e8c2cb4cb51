#define_import_path meshlight::visbuffer64

// The u64 form of the visibility value (see `meshlight::visbuffer` for the layout).
// Needs SHADER_INT64; the atomicMax on `atomic<u64>` that writes it additionally needs
// SHADER_INT64_ATOMIC_MIN_MAX in the pass that declares the buffer.

#import meshlight::visbuffer::{visbuffer_depth_bits, visbuffer_payload}

fn visbuffer64_pack(depth: f32, cluster: u32, triangle: u32) -> u64 {
    return (u64(visbuffer_depth_bits(depth)) << 32u) | u64(visbuffer_payload(cluster, triangle));
}

// The pair form (low word, high word), for the unpacking helpers of `meshlight::visbuffer`.
fn visbuffer64_to_pair(value: u64) -> vec2<u32> {
    return vec2(u32(value & 0xfffffffflu), u32(value >> 32u));
}

fn visbuffer64_from_pair(pair: vec2<u32>) -> u64 {
    return (u64(pair.y) << 32u) | u64(pair.x);
}
