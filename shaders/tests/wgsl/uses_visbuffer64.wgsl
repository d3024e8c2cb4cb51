// The u64 visibility value written with a 64-bit atomicMax, as the software rasteriser
// does; needs SHADER_INT64 and SHADER_INT64_ATOMIC_MIN_MAX.

#import meshlight::visbuffer::{visbuffer_cluster, visbuffer_depth}
#import meshlight::visbuffer64::{visbuffer64_pack, visbuffer64_to_pair, visbuffer64_from_pair}

@group(0) @binding(0) var<storage, read_write> visbuffer: array<atomic<u64>>;
@group(0) @binding(1) var<storage, read_write> out: array<vec2<u32>>;

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    let value = visbuffer64_pack(f32(id.x) / 64.0, id.y, id.z);
    atomicMax(&visbuffer[id.x % 16u], value);
    let pair = visbuffer64_to_pair(value);
    let again = visbuffer64_from_pair(pair);
    out[id.x] = vec2(visbuffer_cluster(pair), bitcast<u32>(visbuffer_depth(visbuffer64_to_pair(again))));
}
