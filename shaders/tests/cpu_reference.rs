//! Round trips and ordering of the Rust references for the bit-exact encodings.

use meshlight_shaders::cpu::{octahedral, visbuffer};
use proptest::prelude::*;

fn unit(v: [f32; 3]) -> Option<[f32; 3]> {
    let len = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
    (len > 1e-3).then(|| [v[0] / len, v[1] / len, v[2] / len])
}

/// Angle between two vectors, via atan2 in f64 so tiny angles are not lost to acos.
fn angle_degrees(a: [f32; 3], b: [f32; 3]) -> f32 {
    let [a, b] = [a, b].map(|v| v.map(f64::from));
    let cross = [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ];
    let sin = (cross[0] * cross[0] + cross[1] * cross[1] + cross[2] * cross[2]).sqrt();
    let cos = a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
    sin.atan2(cos).to_degrees() as f32
}

proptest! {
    #[test]
    fn octahedral_normals_round_trip_within_quantisation(
        x in -1.0f32..1.0, y in -1.0f32..1.0, z in -1.0f32..1.0,
    ) {
        let Some(n) = unit([x, y, z]) else { return Ok(()) };
        let back = octahedral::unpack(octahedral::pack(n));
        // 16 bits per axis: the worst case is a few thousandths of a degree.
        prop_assert!(angle_degrees(n, back) < 0.01, "{n:?} -> {back:?}");
    }

    #[test]
    fn visbuffer_values_round_trip(depth in 0.0f32..=1.0, cluster in 0u32..visbuffer::MAX_CLUSTERS, triangle in 0u32..128) {
        let value = visbuffer::pack(depth, cluster, triangle);
        prop_assert_eq!(visbuffer::depth(value), depth);
        prop_assert_eq!(visbuffer::cluster(value), cluster);
        prop_assert_eq!(visbuffer::triangle(value), triangle);
        prop_assert_eq!(visbuffer::from_pair(visbuffer::to_pair(value)), value);
    }

    #[test]
    fn the_larger_value_is_the_nearer_surface(
        a in 0.0f32..=1.0, b in 0.0f32..=1.0,
        ca in 0u32..visbuffer::MAX_CLUSTERS, cb in 0u32..visbuffer::MAX_CLUSTERS,
        ta in 0u32..128, tb in 0u32..128,
    ) {
        // Reverse-Z: larger depth is nearer, and atomicMax must keep it whatever the ids.
        prop_assume!(a != b);
        let (va, vb) = (visbuffer::pack(a, ca, ta), visbuffer::pack(b, cb, tb));
        prop_assert_eq!(va > vb, a > b);
    }
}

#[test]
fn visbuffer_depth_rejects_nan_and_negative_zero() {
    assert_eq!(visbuffer::depth_bits(f32::NAN), 0);
    assert_eq!(visbuffer::depth_bits(-0.0), 0);
    assert_eq!(visbuffer::depth_bits(-1.0), 0);
    assert_eq!(visbuffer::depth_bits(2.0), 1.0f32.to_bits());
    assert_eq!(visbuffer::pack(0.0, 0, 0), visbuffer::EMPTY);
}

#[test]
fn visbuffer_layout_is_depth_then_cluster_then_triangle() {
    let value = visbuffer::pack(0.5, 5, 3);
    assert_eq!(value, (u64::from(0.5f32.to_bits()) << 32) | (5 << 7) | 3);
}

#[test]
fn octahedral_poles_and_axes_are_exact_enough() {
    for n in [
        [0.0, 0.0, 1.0],
        [0.0, 0.0, -1.0],
        [1.0, 0.0, 0.0],
        [0.0, -1.0, 0.0],
    ] {
        let back = octahedral::unpack(octahedral::pack(n));
        assert!(angle_degrees(n, back) < 1e-3, "{n:?} -> {back:?}");
    }
    // +Z encodes to the centre of the square.
    assert_eq!(octahedral::pack([0.0, 0.0, 1.0]), 0);
}

#[test]
fn snorm16_rounds_half_up_and_clamps() {
    assert_eq!(octahedral::snorm16(1.0), 32767);
    assert_eq!(octahedral::snorm16(-1.0) as i16, -32767);
    assert_eq!(octahedral::snorm16(-2.0) as i16, -32767);
    assert_eq!(octahedral::snorm16(0.5 / 32767.0), 1);
    assert_eq!(octahedral::snorm16_to_f32(0x8000), -1.0);
}

mod light {
    use meshlight_shaders::cpu::layout::ClusterGrid;
    use meshlight_shaders::cpu::light::*;

    #[test]
    fn slices_are_logarithmic_and_clamped() {
        let grid = ClusterGrid::new([16, 9, 24], [1920, 1080], 0.1, 1000.0);
        assert_eq!(grid.tile_size, [120.0, 120.0]);
        assert_eq!(grid.cluster_count, 16 * 9 * 24);
        assert_eq!(z_slice_of_depth(&grid, 0.01), 0);
        assert_eq!(z_slice_of_depth(&grid, 1e6), 23);
        // 0.1..1000 is 4 decades over 24 slices: 6 slices per decade.
        assert_eq!(z_slice_of_depth(&grid, 1.05), 6);
        assert_eq!(z_slice_of_depth(&grid, 9.5), 11);
        for slice in 0..24 {
            let (start, end) = (z_slice_start(&grid, slice), z_slice_start(&grid, slice + 1));
            assert!(start < end);
            let middle = (start * end).sqrt();
            assert_eq!(
                z_slice_of_depth(&grid, middle),
                slice,
                "middle of slice {slice}"
            );
        }
        assert_eq!(z_slice_start(&grid, 24), 1000.0);
        assert_eq!(cluster_index(&grid, [15, 8, 23]), grid.cluster_count - 1);
        assert_eq!(cluster_index(&grid, [1, 0, 0]), 1);
        assert_eq!(cluster_index(&grid, [0, 1, 0]), 16);
    }

    #[test]
    fn sphere_cone_and_box_tests() {
        use meshlight_shaders::cpu::froxel::*;
        use meshlight_shaders::cpu::layout::ClusterableKind;
        let unit_box = Aabb {
            min: [0.0; 3],
            max: [1.0; 3],
        };
        assert!(sphere_touches_aabb([2.0, 0.5, 0.5], 1.01, &unit_box).value);
        assert!(!sphere_touches_aabb([2.0, 0.5, 0.5], 0.99, &unit_box).value);
        let close = sphere_touches_aabb([2.0, 0.5, 0.5], 1.0 + 1e-7, &unit_box);
        assert!(close.closeness < 1e-6, "{close:?}");
        let (cos, sin) = (30f32.to_radians().cos(), 30f32.to_radians().sin());
        let spot = ViewObject {
            center: [0.0; 3],
            range: 10.0,
            axes: [[0.0; 3], [0.0; 3], [0.0, 0.0, -1.0]],
            kind: ClusterableKind::SpotLight as u32,
            cos_angle: cos,
            sin_angle: sin,
        };
        let cone = |center, radius| cone_touches_sphere(&spot, center, radius).value;
        assert!(cone([0.0, 0.0, -5.0], 0.1), "on the axis");
        assert!(!cone([0.0, 0.0, 5.0], 1.0), "behind the apex");
        assert!(!cone([0.0, 0.0, -12.0], 1.0), "beyond the cap");
        // At depth 5 the side is at 5 * tan(30°) ≈ 2.89; a point at x = 4 is about
        // (4 - 2.89) * cos 30° ≈ 0.96 outside it.
        assert!(!cone([4.0, 0.0, -5.0], 0.9));
        assert!(cone([4.0, 0.0, -5.0], 1.0));
        // A cube of half-extent 1 turned 45° about z: its corner reaches x = 2 + √2.
        let h = std::f32::consts::FRAC_1_SQRT_2;
        let turned = |x: f32| ViewObject {
            center: [x, 0.5, 0.5],
            range: 1.0,
            axes: [[h, h, 0.0], [-h, h, 0.0], [0.0, 0.0, 1.0]],
            kind: ClusterableKind::Probe as u32,
            cos_angle: 1.0,
            sin_angle: 0.0,
        };
        assert!(box_touches_aabb(&turned(2.4), &unit_box).value);
        assert!(!box_touches_aabb(&turned(2.45), &unit_box).value);
        // A thin slab facing the box's (1, 1) corner: apart at (2, 2), across the corner at
        // (1.1, 1.1).
        let edge = ViewObject {
            center: [2.0, 2.0, 0.5],
            range: 1.0,
            axes: [[h, -h, 0.0], [0.0, 0.0, 0.2], [0.2 * h, 0.2 * h, 0.0]],
            kind: ClusterableKind::Decal as u32,
            cos_angle: 1.0,
            sin_angle: 0.0,
        };
        assert!(!box_touches_aabb(&edge, &unit_box).value);
        let nearer = ViewObject {
            center: [1.1, 1.1, 0.5],
            ..edge
        };
        assert!(box_touches_aabb(&nearer, &unit_box).value);
    }
}
