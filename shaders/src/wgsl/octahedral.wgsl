#define_import_path meshlight::octahedral

// Unit normals as two 16-bit signed-normalised values in one u32: the normal is
// projected onto the octahedron |x| + |y| + |z| = 1 and the lower half folded over the
// diagonals, which spreads precision evenly (about 0.003 degrees worst case).
// `cpu::octahedral` is the bit-exact reference the asset builder encodes with.

#import meshlight::math::{sign_not_zero, pack_snorm2x16, unpack_snorm2x16}

// Unit vector to octahedral coordinates in [-1, 1]^2.
fn octahedral_encode(n: vec3<f32>) -> vec2<f32> {
    let p = n.xy / (abs(n.x) + abs(n.y) + abs(n.z));
    if n.z < 0.0 {
        return (vec2(1.0) - abs(p.yx)) * sign_not_zero(p);
    }
    return p;
}

// Octahedral coordinates to a unit vector.
fn octahedral_decode(e: vec2<f32>) -> vec3<f32> {
    var n = vec3(e, 1.0 - abs(e.x) - abs(e.y));
    // Unfold the lower hemisphere; t is how far the point lies outside the diamond.
    let t = max(-n.z, 0.0);
    n.x += select(t, -t, n.x >= 0.0);
    n.y += select(t, -t, n.y >= 0.0);
    return normalize(n);
}

fn pack_octahedral_normal(n: vec3<f32>) -> u32 {
    return pack_snorm2x16(octahedral_encode(n));
}

fn unpack_octahedral_normal(packed: u32) -> vec3<f32> {
    return octahedral_decode(unpack_snorm2x16(packed));
}
