// The frame's image drawn into a target of any colour format: one fullscreen triangle,
// one texel per pixel (the image has the target's size). `cpu::presented` is the
// reference.

// The image resolve wrote: sRGB-encoded bytes in an Rgba8Unorm texture, as a PNG holds.
@group(0) @binding(0) var color: texture_2d<f32>;

@vertex
fn fullscreen_vs(@builtin(vertex_index) v: u32) -> @builtin(position) vec4<f32> {
    // One triangle covering the viewport: (-1, -1), (3, -1), (-1, 3).
    let xy = vec2(f32((v << 1u) & 2u), f32(v & 2u)) * 2.0 - 1.0;
    return vec4(xy, 0.0, 1.0);
}

// sRGB-encoded value to linear light, the inverse of what an sRGB target's store does.
fn srgb_to_linear(c: vec3<f32>) -> vec3<f32> {
    let low = c / 12.92;
    let high = pow((c + 0.055) / 1.055, vec3(2.4));
    return select(high, low, c <= vec3(0.04045));
}

@fragment
fn present_fs(@builtin(position) p: vec4<f32>) -> @location(0) vec4<f32> {
    let size = vec2<i32>(textureDimensions(color));
    let texel = textureLoad(color, min(vec2<i32>(p.xy), size - 1), 0);
#ifdef SRGB_TARGET
    // The target encodes what it stores: hand it linear light, so it stores the bytes
    // the image holds.
    return vec4(srgb_to_linear(texel.rgb), 1.0);
#else
    return vec4(texel.rgb, 1.0);
#endif
}
