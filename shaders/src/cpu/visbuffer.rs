//! The visibility-buffer value, as `meshlight::visbuffer` packs it.

/// Bits of the triangle index in the low word.
pub const TRIANGLE_BITS: u32 = 7;
/// Bits of the cluster index in the low word.
pub const CLUSTER_BITS: u32 = 25;
/// Clusters per frame at most.
pub const MAX_CLUSTERS: u32 = 1 << CLUSTER_BITS;
/// Triangles per cluster at most.
pub const MAX_TRIANGLES: u32 = 1 << TRIANGLE_BITS;
/// The cleared value; depth 0 is the infinitely far plane under reverse-Z.
pub const EMPTY: u64 = 0;

/// Reverse-Z depth as bits that order like the depth; NaN and negatives become 0, and
/// depths above 1 become 1.
pub fn depth_bits(depth: f32) -> u32 {
    let d = if depth > 0.0 { depth.min(1.0) } else { 0.0 };
    d.to_bits()
}

/// Packs `depth_bits << 32 | cluster << 7 | triangle`.
///
/// Out-of-range ids are a caller bug (they would alias other clusters), so they panic in
/// debug builds; the triangle is masked like the shader does.
pub fn pack(depth: f32, cluster: u32, triangle: u32) -> u64 {
    debug_assert!(
        cluster < MAX_CLUSTERS,
        "cluster {cluster} needs more than {CLUSTER_BITS} bits"
    );
    debug_assert!(
        triangle < MAX_TRIANGLES,
        "triangle {triangle} needs more than {TRIANGLE_BITS} bits"
    );
    let payload = (cluster << TRIANGLE_BITS) | (triangle & (MAX_TRIANGLES - 1));
    (u64::from(depth_bits(depth)) << 32) | u64::from(payload)
}

/// The depth stored in a packed value.
pub fn depth(value: u64) -> f32 {
    f32::from_bits((value >> 32) as u32)
}

/// The cluster index stored in a packed value.
pub fn cluster(value: u64) -> u32 {
    (value as u32) >> TRIANGLE_BITS
}

/// The triangle index stored in a packed value.
pub fn triangle(value: u64) -> u32 {
    (value as u32) & (MAX_TRIANGLES - 1)
}

/// The pair form `[low word, high word]` the WGSL `vec2<u32>` helpers use.
pub fn to_pair(value: u64) -> [u32; 2] {
    [value as u32, (value >> 32) as u32]
}

/// The u64 form of a `[low word, high word]` pair.
pub fn from_pair(pair: [u32; 2]) -> u64 {
    (u64::from(pair[1]) << 32) | u64::from(pair[0])
}
