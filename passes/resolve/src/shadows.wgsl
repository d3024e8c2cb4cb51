#define_import_path resolve::shadows

// The sun's shadow: which cascade a point falls in, and how much of the sun reaches it,
// filtered over the cascade's depth map (`shadows::cpu` is the reference; each step has
// its mirror there).

#import meshlight::view::View
#import resolve::shadow_params::Shadows

// Every cascade's map, `resolution²` reverse-Z depth bits each (0: nothing drawn),
// cascade after cascade, as the depth-only software rasteriser writes them.
@group(0) @binding(20) var<storage, read> shadow_maps: array<u32>;
@group(0) @binding(21) var<uniform> shadows: Shadows;

fn cascade_matrix(k: u32) -> mat4x4<f32> {
    switch k {
        case 0u: { return shadows.cascade_a; }
        case 1u: { return shadows.cascade_b; }
        case 2u: { return shadows.cascade_c; }
        default: { return shadows.cascade_d; }
    }
}

// The first cascade whose slice reaches the point's view-space depth; `count` past the
// last (no shadow there).
fn cascade_index(view: View, world: vec3<f32>) -> u32 {
    let depth = -(view.view * vec4(world, 1.0)).z;
    for (var k = 0u; k < shadows.count; k++) {
        if depth <= shadows.splits[k] {
            return k;
        }
    }
    return shadows.count;
}

// 1 where the texel lets the sun through to a receiver at `receiver`: nothing nearer the
// light than it was drawn there. Texels off the map let it through.
fn lit_texel(k: u32, x: i32, y: i32, receiver: f32) -> f32 {
    let r = i32(shadows.resolution);
    if x < 0 || y < 0 || x >= r || y >= r {
        return 1.0;
    }
    let stored = bitcast<f32>(shadow_maps[k * shadows.resolution * shadows.resolution + u32(y) * shadows.resolution + u32(x)]);
    return select(0.0, 1.0, stored <= receiver);
}

// The share of the sun reaching `world` (normal `n`): the receiver moved along its normal
// by `normal_offset` and towards the light by `depth_bias`, compared with the 4 × 4
// texels around it, weighted (1 − f, 1, 1, f) / 3 on each axis: nine bilinear taps one
// texel apart (a 3 × 3 tent), so the edge is smooth across three texels. 1 outside
// every cascade.
fn shadow_factor(view: View, world: vec3<f32>, n: vec3<f32>) -> f32 {
    let k = cascade_index(view, world);
    if k >= shadows.count {
        return 1.0;
    }
    let p = world + n * shadows.normal_offset[k];
    let clip = cascade_matrix(k) * vec4(p, 1.0);
    let ndc = clip.xyz / clip.w;
    let texel = vec2((ndc.x * 0.5 + 0.5), (0.5 - ndc.y * 0.5)) * f32(shadows.resolution) - 0.5;
    let base = floor(texel);
    let f = texel - base;
    let receiver = ndc.z + shadows.depth_bias[k];
    let wx = array(1.0 - f.x, 1.0, 1.0, f.x);
    let wy = array(1.0 - f.y, 1.0, 1.0, f.y);
    var lit = 0.0;
    for (var j = 0; j < 4; j++) {
        var row = 0.0;
        for (var i = 0; i < 4; i++) {
            row += wx[i] * lit_texel(k, i32(base.x) + i - 1, i32(base.y) + j - 1, receiver);
        }
        lit += wy[j] * row;
    }
    return lit / 9.0;
}
