#define_import_path meshlight::texture

// Trilinear sampling of the scene's textures from a storage buffer, one RGBA8 texel a
// word. A compute shader without descriptor arrays (lavapipe has none) cannot pick one
// of many textures per pixel; a buffer holds them all, and each material names where
// its maps lie (`cpu::layout::TextureRef`). Filtering is done here, so it is the same on
// every adapter and `meshlight_gpu_scene::texture` mirrors it step by step: sRGB texels
// are decoded to linear light before they are weighed, wrap modes apply per axis, and
// the level comes from the UV derivatives the pixel's triangle gives analytically
// (meshlight::surface).

#import meshlight::scene_buffers::textures

const TEXTURE_PRESENT: u32 = 0x80000000u;
const TEXTURE_SRGB: u32 = 16u;
const WRAP_CLAMP: u32 = 1u;
const WRAP_MIRROR: u32 = 2u;
// The largest side a texture may have, as a power of two (`MAX_TEXTURE_SIZE_LOG2`).
const MAX_SIZE_LOG2: u32 = 12u;

fn texture_present(map: vec2<u32>) -> bool {
    return (map.y & TEXTURE_PRESENT) != 0u;
}

fn texture_size_log2(map: vec2<u32>) -> u32 {
    return min(map.y & 15u, MAX_SIZE_LOG2);
}

// Linear light of the 8-bit sRGB value `v`: the f32 bits in word `v` of `textures`, whose
// first 256 words are that table (`cpu::layout::SRGB_TABLE_WORDS`). A trilinear sample
// decodes up to 24 channels; a cached load costs far less than a `pow`, and a table kept
// with the textures costs a frame without textures nothing.
fn srgb_decoded(v: u32) -> f32 {
    return bitcast<f32>(textures[v]);
}

// A vertex colour word (`meshlight::meshlet`'s `meshlet_color_word`): sRGB red,
// green and blue decoded to linear light through the same table, alpha linear.
fn vertex_color(word: u32) -> vec4<f32> {
    let c = unpack4x8unorm(word);
    return vec4(srgb_decoded(word & 0xffu), srgb_decoded((word >> 8u) & 0xffu), srgb_decoded((word >> 16u) & 0xffu), c.w);
}

// Words before `level` in a chain of side 2^size_log2 (`cpu::layout::mip_offset`).
fn mip_offset(size_log2: u32, level: u32) -> u32 {
    let n1 = size_log2 + 1u;
    return ((1u << (2u * n1)) - (1u << (2u * (n1 - level)))) / 3u;
}

// A coordinate brought into 0..1 before texels are addressed, so that integer texel
// indices stay small however far a tiling UV runs.
fn wrap_coordinate(u: f32, mode: u32) -> f32 {
    switch mode {
        case WRAP_CLAMP: {
            return clamp(u, 0.0, 1.0);
        }
        case WRAP_MIRROR: {
            return u - 2.0 * floor(u * 0.5);
        }
        default: {
            return u - floor(u);
        }
    }
}

// Texel index `i` of a row or column of `side` texels (a power of two), wrapped by
// `mode`: masks rather than remainders, which a GPU divides slowly (two's complement
// makes `i & (side - 1)` the Euclidean remainder for negative `i` too).
fn wrap_index(i: i32, side: i32, mode: u32) -> i32 {
    switch mode {
        case WRAP_CLAMP: {
            return clamp(i, 0, side - 1);
        }
        case WRAP_MIRROR: {
            let m = i & (2 * side - 1);
            return select(m, 2 * side - 1 - m, m >= side);
        }
        default: {
            return i & (side - 1);
        }
    }
}

fn texel(map: vec2<u32>, start: u32, side: i32, x: i32, y: i32) -> vec4<f32> {
    let mode = vec2((map.y >> 5u) & 3u, (map.y >> 7u) & 3u);
    let at = start + u32(wrap_index(y, side, mode.y) * side + wrap_index(x, side, mode.x));
    let word = textures[at];
    if (map.y & TEXTURE_SRGB) != 0u {
        return vec4(
            srgb_decoded(word & 255u),
            srgb_decoded((word >> 8u) & 255u),
            srgb_decoded((word >> 16u) & 255u),
            f32(word >> 24u) / 255.0,
        );
    }
    return unpack4x8unorm(word);
}

// The four texels bilinear filtering of one level at `uv` (already wrapped into 0..1)
// weighs: the level's first word and side, the top-left texel, and the weights.
struct Taps {
    start: u32,
    side: i32,
    x: i32,
    y: i32,
    f: vec2<f32>,
}

fn level_taps(map: vec2<u32>, uv: vec2<f32>, level: u32) -> Taps {
    let size_log2 = texture_size_log2(map);
    let side = i32(1u << (size_log2 - level));
    let p = uv * f32(side) - 0.5;
    let corner = floor(p);
    return Taps(map.x + mip_offset(size_log2, level), side, i32(corner.x), i32(corner.y), p - corner);
}

// Bilinear filtering of one level at `uv` (already wrapped into 0..1).
fn sample_level(map: vec2<u32>, uv: vec2<f32>, level: u32) -> vec4<f32> {
    let t = level_taps(map, uv, level);
    let top = mix(texel(map, t.start, t.side, t.x, t.y), texel(map, t.start, t.side, t.x + 1, t.y), t.f.x);
    let bottom = mix(texel(map, t.start, t.side, t.x, t.y + 1), texel(map, t.start, t.side, t.x + 1, t.y + 1), t.f.x);
    return mix(top, bottom, t.f.y);
}

// The level of detail a pixel footprint of `uv_dx`, `uv_dy` (UV per pixel step) asks of
// a texture of side 2^size_log2: log2 of the longer footprint axis in texels, clamped to
// the chain (the isotropic rule GPUs use).
fn texture_lod(map: vec2<u32>, uv_dx: vec2<f32>, uv_dy: vec2<f32>) -> f32 {
    let size_log2 = texture_size_log2(map);
    let side = f32(1u << size_log2);
    let rho = max(length(uv_dx), length(uv_dy)) * side;
    return clamp(log2(max(rho, 1e-20)), 0.0, f32(size_log2));
}

// Where trilinear filtering reads: `uv` wrapped, the finer of the two levels around the
// footprint's, and how much of the coarser one is mixed in.
struct Trilinear {
    uv: vec2<f32>,
    fine: u32,
    blend: f32,
}

fn trilinear(map: vec2<u32>, uv: vec2<f32>, uv_dx: vec2<f32>, uv_dy: vec2<f32>) -> Trilinear {
    let wrapped = vec2(wrap_coordinate(uv.x, (map.y >> 5u) & 3u), wrap_coordinate(uv.y, (map.y >> 7u) & 3u));
    let lod = texture_lod(map, uv_dx, uv_dy);
    let fine = u32(floor(lod));
    return Trilinear(wrapped, fine, lod - f32(fine));
}

// Trilinear filtering: the two levels around the footprint's, each bilinear, mixed.
fn sample_texture(map: vec2<u32>, uv: vec2<f32>, uv_dx: vec2<f32>, uv_dy: vec2<f32>) -> vec4<f32> {
    let t = trilinear(map, uv, uv_dx, uv_dy);
    let c = sample_level(map, t.uv, t.fine);
    if t.blend <= 0.0 {
        return c;
    }
    return mix(c, sample_level(map, t.uv, t.fine + 1u), t.blend);
}

// The alpha of texel (x, y) of a level starting at `start` (`texel(...).a`, without
// decoding the colour).
fn texel_alpha(map: vec2<u32>, start: u32, side: i32, x: i32, y: i32) -> f32 {
    let mode = vec2((map.y >> 5u) & 3u, (map.y >> 7u) & 3u);
    let at = start + u32(wrap_index(y, side, mode.y) * side + wrap_index(x, side, mode.x));
    return f32(textures[at] >> 24u) / 255.0;
}

// `sample_level(...).a`: the same taps and weights over the alpha channel alone.
fn sample_level_alpha(map: vec2<u32>, uv: vec2<f32>, level: u32) -> f32 {
    let t = level_taps(map, uv, level);
    let top = mix(texel_alpha(map, t.start, t.side, t.x, t.y), texel_alpha(map, t.start, t.side, t.x + 1, t.y), t.f.x);
    let bottom = mix(texel_alpha(map, t.start, t.side, t.x, t.y + 1), texel_alpha(map, t.start, t.side, t.x + 1, t.y + 1), t.f.x);
    return mix(top, bottom, t.f.y);
}

// `sample_texture(...).a`, reading only the alpha byte of each texel: a MASK material's
// cut-out test samples it for every covered pixel, and the colour's decoding (three
// sRGB table reads a texel) would be wasted there.
fn sample_alpha(map: vec2<u32>, uv: vec2<f32>, uv_dx: vec2<f32>, uv_dy: vec2<f32>) -> f32 {
    let t = trilinear(map, uv, uv_dx, uv_dy);
    let a = sample_level_alpha(map, t.uv, t.fine);
    if t.blend <= 0.0 {
        return a;
    }
    return mix(a, sample_level_alpha(map, t.uv, t.fine + 1u), t.blend);
}
