//! Matrix times vector as the WGSL computes it: a column-major matrix, summed column by
//! column in order, so a CPU reference rounds like the shader it mirrors.

/// `m * v` for a column-major matrix, summed column by column.
pub fn mat_vec(m: &[[f32; 4]; 4], v: [f32; 4]) -> [f32; 4] {
    std::array::from_fn(|r| m[0][r] * v[0] + m[1][r] * v[1] + m[2][r] * v[2] + m[3][r] * v[3])
}

/// `(m * vec4(p, 1.0)).xyz`: a point through an affine transform (`instance_transform_point`
/// with the instance's matrix).
pub fn transform_point(m: &[[f32; 4]; 4], p: [f32; 3]) -> [f32; 3] {
    let v = mat_vec(m, [p[0], p[1], p[2], 1.0]);
    [v[0], v[1], v[2]]
}
