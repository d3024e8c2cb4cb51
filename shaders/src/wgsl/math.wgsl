#define_import_path meshlight::math

// Constants and small helpers every pass needs; no bindings.

const PI: f32 = 3.141592653589793;
const TAU: f32 = 6.283185307179586;
const HALF_PI: f32 = 1.5707963267948966;
// Largest finite f32, used as "no limit" (e.g. the parent error of a root meshlet).
const F32_MAX: f32 = 3.40282347e38;
const U32_MAX: u32 = 0xffffffffu;

fn saturate(x: f32) -> f32 {
    return clamp(x, 0.0, 1.0);
}

fn saturate3(x: vec3<f32>) -> vec3<f32> {
    return clamp(x, vec3(0.0), vec3(1.0));
}

// Normalises v, or returns `fallback` when v is too short to have a direction
// (normalize of a zero vector is NaN on most GPUs).
fn safe_normalize(v: vec3<f32>, fallback: vec3<f32>) -> vec3<f32> {
    let len2 = dot(v, v);
    if len2 > 1e-30 {
        return v * inverseSqrt(len2);
    }
    return fallback;
}

// ceil(a / b) for workgroup counts; b must be non-zero.
fn div_ceil(a: u32, b: u32) -> u32 {
    return (a + b - 1u) / b;
}

// ±1 with sign(0) = +1, unlike the builtin sign() which returns 0.
fn sign_not_zero(v: vec2<f32>) -> vec2<f32> {
    return select(vec2(-1.0), vec2(1.0), v >= vec2(0.0));
}

fn max_component(v: vec3<f32>) -> f32 {
    return max(v.x, max(v.y, v.z));
}

// Two's complement i16 from a float in [-1, 1], rounding half up: the exact rule of
// `cpu::snorm16` (the builtin pack2x16snorm may round differently per driver).
fn f32_to_snorm16(x: f32) -> u32 {
    let i = i32(floor(0.5 + 32767.0 * clamp(x, -1.0, 1.0)));
    return u32(i) & 0xffffu;
}

fn snorm16_to_f32(bits: u32) -> f32 {
    // Sign-extend the low 16 bits.
    let i = i32(bits << 16u) >> 16u;
    return max(f32(i) / 32767.0, -1.0);
}

// Packs two signed-normalised values, x in the low half.
fn pack_snorm2x16(v: vec2<f32>) -> u32 {
    return f32_to_snorm16(v.x) | (f32_to_snorm16(v.y) << 16u);
}

fn unpack_snorm2x16(bits: u32) -> vec2<f32> {
    return vec2(snorm16_to_f32(bits & 0xffffu), snorm16_to_f32(bits >> 16u));
}

// `count` bits (0..=32) starting at bit `bit` (0..31) of the little-endian pair
// `words` = (words[i], words[i + 1]): a field may straddle the two words.
fn read_bits(words: vec2<u32>, bit: u32, count: u32) -> u32 {
    let low_count = min(count, 32u - bit);
    let low = extractBits(words.x, bit, low_count);
    if count <= low_count {
        return low;
    }
    // Here bit > 0, so the shift below is in 1..=31.
    let high = extractBits(words.y, 0u, count - low_count);
    return low | (high << low_count);
}

// Byte `index` (0..3) of a word holding four u8 values, the first in the low byte.
fn unpack_u8(word: u32, index: u32) -> u32 {
    return extractBits(word, index * 8u, 8u);
}
