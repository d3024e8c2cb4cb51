//! Octahedral unit normals in 2×16 snorm, as `meshlight::octahedral` encodes them.

/// A float in [-1, 1] to a 16-bit two's-complement value, rounding half up, exactly as
/// `f32_to_snorm16` in `meshlight::math` (the WGSL builtin's rounding varies by driver).
pub fn snorm16(x: f32) -> u16 {
    (0.5 + 32767.0 * x.clamp(-1.0, 1.0)).floor() as i32 as u16
}

/// The inverse of [`snorm16`].
pub fn snorm16_to_f32(bits: u16) -> f32 {
    (f32::from(bits as i16) / 32767.0).max(-1.0)
}

fn sign_not_zero(x: f32) -> f32 {
    if x >= 0.0 { 1.0 } else { -1.0 }
}

/// Unit vector to octahedral coordinates in [-1, 1]².
pub fn encode(n: [f32; 3]) -> [f32; 2] {
    let l1 = n[0].abs() + n[1].abs() + n[2].abs();
    let p = [n[0] / l1, n[1] / l1];
    if n[2] < 0.0 {
        [
            (1.0 - p[1].abs()) * sign_not_zero(p[0]),
            (1.0 - p[0].abs()) * sign_not_zero(p[1]),
        ]
    } else {
        p
    }
}

/// Octahedral coordinates to a unit vector.
pub fn decode(e: [f32; 2]) -> [f32; 3] {
    let mut n = [e[0], e[1], 1.0 - e[0].abs() - e[1].abs()];
    let t = (-n[2]).max(0.0);
    n[0] += if n[0] >= 0.0 { -t } else { t };
    n[1] += if n[1] >= 0.0 { -t } else { t };
    let len = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
    [n[0] / len, n[1] / len, n[2] / len]
}

/// A unit normal packed in one u32: x in the low half, y in the high half.
pub fn pack(n: [f32; 3]) -> u32 {
    let e = encode(n);
    u32::from(snorm16(e[0])) | (u32::from(snorm16(e[1])) << 16)
}

/// The inverse of [`pack`], up to quantisation.
pub fn unpack(packed: u32) -> [f32; 3] {
    decode([
        snorm16_to_f32(packed as u16),
        snorm16_to_f32((packed >> 16) as u16),
    ])
}
