// Demo compute rasteriser: one thread per triangle, 64-bit atomicMax into a visibility
// buffer holding (1 - depth) in the high word and triangle + 1 in the low word, so the
// nearest triangle wins and zero means "empty".

struct RasterParams {
    // Clip-from-world transform.
    view_proj: mat4x4<f32>,
    // Target width in pixels.
    width: u32,
    // Target height in pixels.
    height: u32,
    // Number of triangles to rasterise.
    triangle_count: u32,
    // Threads per row of the 2-D dispatch.
    threads_per_row: u32,
}

@group(0) @binding(0) var<storage, read> positions: array<vec4<f32>>;
@group(0) @binding(1) var<storage, read> indices: array<u32>;
@group(0) @binding(2) var<storage, read_write> visbuffer: array<atomic<u64>>;
@group(0) @binding(3) var<uniform> params: RasterParams;

@compute @workgroup_size(64)
fn clear(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.y * params.threads_per_row + id.x;
    if i < params.width * params.height {
        atomicStore(&visbuffer[i], 0lu);
    }
}

fn to_screen(clip: vec4<f32>) -> vec3<f32> {
    let ndc = clip.xyz / clip.w;
    return vec3(
        (ndc.x * 0.5 + 0.5) * f32(params.width),
        (0.5 - ndc.y * 0.5) * f32(params.height),
        ndc.z,
    );
}

fn edge(a: vec2<f32>, b: vec2<f32>, p: vec2<f32>) -> f32 {
    return (b.x - a.x) * (p.y - a.y) - (b.y - a.y) * (p.x - a.x);
}

@compute @workgroup_size(64)
fn raster(@builtin(global_invocation_id) id: vec3<u32>) {
    let t = id.y * params.threads_per_row + id.x;
    if t >= params.triangle_count {
        return;
    }
    let c0 = params.view_proj * positions[indices[3u * t]];
    let c1 = params.view_proj * positions[indices[3u * t + 1u]];
    let c2 = params.view_proj * positions[indices[3u * t + 2u]];
    // Triangles touching the near plane are skipped: the demo camera keeps the mesh in front.
    if c0.w <= 0.0 || c1.w <= 0.0 || c2.w <= 0.0 {
        return;
    }
    let s0 = to_screen(c0);
    let s1 = to_screen(c1);
    let s2 = to_screen(c2);
    // Screen y points down, so counter-clockwise front faces have negative area here.
    let area = edge(s0.xy, s1.xy, s2.xy);
    if area >= 0.0 {
        return;
    }
    let lo = max(floor(min(s0.xy, min(s1.xy, s2.xy))), vec2(0.0));
    let hi = min(ceil(max(s0.xy, max(s1.xy, s2.xy))), vec2(f32(params.width), f32(params.height)) - 1.0);
    for (var y = lo.y; y <= hi.y; y += 1.0) {
        for (var x = lo.x; x <= hi.x; x += 1.0) {
            let p = vec2(x + 0.5, y + 0.5);
            let w0 = edge(s1.xy, s2.xy, p) / area;
            let w1 = edge(s2.xy, s0.xy, p) / area;
            let w2 = 1.0 - w0 - w1;
            if w0 < 0.0 || w1 < 0.0 || w2 < 0.0 {
                continue;
            }
            let z = w0 * s0.z + w1 * s1.z + w2 * s2.z;
            if z < 0.0 || z > 1.0 {
                continue;
            }
            let value = (u64(bitcast<u32>(1.0 - z)) << 32u) | u64(t + 1u);
            atomicMax(&visbuffer[u32(y) * params.width + u32(x)], value);
        }
    }
}
