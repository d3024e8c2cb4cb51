// The bandwidth yardstick: a plain compute copy of the benchmark's bytes, 16 bytes per
// load and store, a grid-stride loop over as many workgroups as one dispatch allows.

struct Params {
    // Whole vec4<u32> words to copy.
    words4: u32,
    // Elements in all (u32), for the tail of fewer than four.
    count: u32,
    // Threads in the grid: the stride of the loop.
    threads: u32,
    _pad: u32,
}

@group(0) @binding(0) var<storage, read> src4: array<vec4<u32>>;
@group(0) @binding(1) var<storage, read_write> dst4: array<vec4<u32>>;
@group(0) @binding(2) var<uniform> params: Params;

@compute @workgroup_size(256)
fn copy4(@builtin(global_invocation_id) id: vec3<u32>) {
    for (var i = id.x; i < params.words4; i += params.threads) {
        dst4[i] = src4[i];
    }
}

@group(0) @binding(3) var<storage, read> src1: array<u32>;
@group(0) @binding(4) var<storage, read_write> dst1: array<u32>;

// The last count % 4 elements, one thread each.
@compute @workgroup_size(4)
fn copy_tail(@builtin(local_invocation_index) lane: u32) {
    let i = params.words4 * 4u + lane;
    if i < params.count {
        dst1[i] = src1[i];
    }
}
