// Compute kernels for the frame-graph feature tests.

struct Params {
    // Elements, texels or frame value, depending on the kernel.
    a: u32,
    // Second operand (width, level, …).
    b: u32,
    c: u32,
    d: u32,
}

// ---- mip chain: mip 0 from a buffer, each further mip the conservative minimum of the
// texels of the mip before that it covers (odd sizes take the extra row and column).

@group(0) @binding(0) var<storage, read> source: array<f32>;
@group(0) @binding(1) var base_mip: texture_storage_2d<r32float, write>;
@group(0) @binding(2) var<uniform> params: Params;

@compute @workgroup_size(8, 8)
fn write_base(@builtin(global_invocation_id) id: vec3<u32>) {
    let size = textureDimensions(base_mip);
    if id.x < size.x && id.y < size.y {
        textureStore(base_mip, id.xy, vec4<f32>(source[id.y * size.x + id.x], 0.0, 0.0, 0.0));
    }
}

@group(0) @binding(3) var src_mip: texture_2d<f32>;
@group(0) @binding(4) var dst_mip: texture_storage_2d<r32float, write>;

@compute @workgroup_size(8, 8)
fn downsample(@builtin(global_invocation_id) id: vec3<u32>) {
    let dst = textureDimensions(dst_mip);
    let src = textureDimensions(src_mip);
    if id.x >= dst.x || id.y >= dst.y {
        return;
    }
    var x_end = id.x * 2u + 2u;
    var y_end = id.y * 2u + 2u;
    if id.x == dst.x - 1u && (src.x & 1u) == 1u { x_end = src.x; }
    if id.y == dst.y - 1u && (src.y & 1u) == 1u { y_end = src.y; }
    var m = 3.4e38;
    for (var y = id.y * 2u; y < min(y_end, src.y); y++) {
        for (var x = id.x * 2u; x < min(x_end, src.x); x++) {
            m = min(m, textureLoad(src_mip, vec2<u32>(x, y), 0).r);
        }
    }
    textureStore(dst_mip, id.xy, vec4<f32>(m, 0.0, 0.0, 0.0));
}

// Gathers every mip through a nearest sampler into one buffer, mip after mip.
@group(0) @binding(5) var pyramid: texture_2d<f32>;
@group(0) @binding(6) var nearest: sampler;
@group(0) @binding(7) var<storage, read_write> gathered: array<f32>;

@compute @workgroup_size(64)
fn gather(@builtin(global_invocation_id) id: vec3<u32>) {
    // params.a: mip level, params.b: offset of the mip in `gathered`.
    let size = textureDimensions(pyramid, params.a);
    if id.x >= size.x * size.y {
        return;
    }
    let texel = vec2<u32>(id.x % size.x, id.x / size.x);
    let uv = (vec2<f32>(texel) + 0.5) / vec2<f32>(size);
    gathered[params.b + id.x] = textureSampleLevel(pyramid, nearest, uv, f32(params.a)).r;
}

// ---- append, then indirect: every third id appends itself; args[0] counts the appends
// and is the workgroup count of the indirect dispatch that follows.

@group(0) @binding(8) var<storage, read_write> args: array<atomic<u32>>;
@group(0) @binding(9) var<storage, read_write> items: array<u32>;

@compute @workgroup_size(64)
fn append(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x == 0u {
        atomicStore(&args[1], 1u);
        atomicStore(&args[2], 1u);
    }
    if id.x < params.a && id.x % 3u == 0u {
        let slot = atomicAdd(&args[0], 1u);
        items[slot] = id.x;
    }
}

@group(0) @binding(10) var<storage, read> items_in: array<u32>;
@group(0) @binding(11) var<storage, read_write> marks: array<u32>;

// One workgroup per appended item: marks the item's id.
@compute @workgroup_size(1)
fn mark(@builtin(workgroup_id) wg: vec3<u32>) {
    marks[items_in[wg.x]] = 1u + params.b;
}

@group(0) @binding(12) var<storage, read> args_in: array<u32>;
@group(0) @binding(13) var<storage, read_write> seen: array<u32>;

// Reads the arguments it was dispatched with: storage and indirect in one dispatch.
@compute @workgroup_size(1)
fn count_groups(@builtin(workgroup_id) wg: vec3<u32>) {
    seen[wg.x] = args_in[0] * 1000u + wg.x;
}

// ---- frame data and growth: writes this frame's value, fills a list as long as the
// buffer bound to it, and counts up a history buffer.

@group(0) @binding(14) var<storage, read_write> stamp: array<u32>;

@compute @workgroup_size(1)
fn write_stamp() {
    // params.a: the frame's value, params.b: the frame index.
    stamp[0] = params.a;
    stamp[1] = params.b;
}

@group(0) @binding(15) var<storage, read_write> list: array<u32>;
@group(0) @binding(16) var<storage, read> history_prev: array<u32>;
@group(0) @binding(17) var<storage, read_write> history: array<u32>;

@compute @workgroup_size(64)
fn grow(@builtin(global_invocation_id) id: vec3<u32>) {
    // params.a: elements, params.b: 1 when last frame's history is valid.
    if id.x < params.a {
        list[id.x] = id.x * 2u + 1u;
        history[id.x] = select(0u, history_prev[id.x], params.b == 1u) + 1u;
    }
}

// ---- texture arrays: one pass per layer writes through a one-layer view, then every
// layer is read back through the whole array.

@group(0) @binding(18) var layer_out: texture_storage_2d_array<r32float, write>;
@group(0) @binding(19) var layers_in: texture_2d_array<f32>;
@group(0) @binding(20) var<storage, read_write> layers_flat: array<f32>;

@compute @workgroup_size(8, 8)
fn fill_layer(@builtin(global_invocation_id) id: vec3<u32>) {
    // params.a: the value to write.
    let size = textureDimensions(layer_out);
    if id.x < size.x && id.y < size.y {
        textureStore(layer_out, id.xy, 0u, vec4<f32>(f32(params.a) + f32(id.x), 0.0, 0.0, 0.0));
    }
}

@compute @workgroup_size(8, 8, 1)
fn flatten_layers(@builtin(global_invocation_id) id: vec3<u32>) {
    let size = textureDimensions(layers_in);
    if id.x < size.x && id.y < size.y && id.z < textureNumLayers(layers_in) {
        layers_flat[(id.z * size.y + id.y) * size.x + id.x] = textureLoad(layers_in, id.xy, id.z, 0).r;
    }
}
