//! Compression round trips, save/load, determinism, and refusal of damaged files.

mod common;

use std::collections::HashMap;
use std::path::Path;

use meshlight_scene::asset::format::{
    MeshletRecord, PayloadLayout, SECTION_MESHLETS, SECTION_PAYLOAD, VERSION,
};
use meshlight_scene::compress::{AUTO_ERROR_SHARE, MAX_POSITION_BITS, PositionBits, Quantization};
use meshlight_scene::{
    BuildOptions, Built, MeshletAsset, SceneError, build_asset, load::load_mesh, procedural_mesh,
};
use proptest::prelude::*;

fn build(mesh: &meshlight_scene::Mesh) -> Built {
    build_asset(mesh, &BuildOptions::default(), &mut |_| {}).unwrap()
}

/// The two origin words of meshlet `i`'s UV block.
fn uv_origin(asset: &MeshletAsset, i: usize) -> [u32; 2] {
    let m = &asset.meshlets()[i];
    let at = (m.data_offset + PayloadLayout::of(m, meshlight_scene::asset::format::FLAG_UVS).uvs)
        as usize;
    [asset.payload()[at], asset.payload()[at + 1]]
}

/// A flat square of `n × n` cells whose map repeats `repeats` times across it, as a
/// tiling ground texture does.
fn tiled_square(n: u32, repeats: f32) -> meshlight_scene::Mesh {
    common::generators::textured_square("tiled square", n, |x, y| (0.0, [x * repeats, y * repeats]))
}

/// A map repeated 64 times over a square: each meshlet's UVs keep a precision set by
/// its own extent in the map (within its extent over 65,535), not the map's, so a
/// compact LOD-0 meshlet keeps a small part of a texel of a 1,024² texture where 16 bits
/// over the whole map were a quarter texel.
#[test]
fn a_tiling_map_keeps_its_uvs_to_a_small_part_of_a_texel() {
    let built = build(&tiled_square(128, 64.0));
    check_round_trip(&built);
    let asset = &built.asset;
    let h = asset.header();
    let texel = 1.0 / 1024.0;
    let whole_map_half_step = 64.0 / 65535.0 * 0.5;
    let mut lod0_errors = Vec::new();
    for (i, cluster) in built.dag.clusters.iter().enumerate() {
        let d = asset.decode_meshlet(i);
        let mut locals: Vec<u32> = Vec::new();
        for &g in &cluster.indices {
            if !locals.contains(&g) {
                locals.push(g);
            }
        }
        let uvs: Vec<[f32; 2]> = locals.iter().map(|&g| built.mesh.uvs[g as usize]).collect();
        let mut worst = 0.0f32;
        for a in 0..2 {
            let lo = uvs.iter().map(|u| u[a]).fold(f32::INFINITY, f32::min);
            let hi = uvs.iter().map(|u| u[a]).fold(f32::NEG_INFINITY, f32::max);
            let rounding = 2.0 * f32::EPSILON * (h.uv_min[a].abs() + 64.0);
            // The smallest shift that fits the extent leaves a step of at most twice the
            // extent over 65,535, and the precision target a step of at most
            // `UV_STEP_TARGET` (a grid code of rounding besides).
            let target = meshlight_scene::compress::UV_STEP_TARGET * 1.001;
            let bound = ((hi - lo) / 65535.0).max(target * 0.5) + h.uv_step[a] + rounding;
            for (k, uv) in uvs.iter().enumerate() {
                let e = (d.uvs[k][a] - uv[a]).abs();
                assert!(
                    e <= bound,
                    "meshlet {i}: UV error {e} past {bound} for an extent of {}",
                    hi - lo
                );
                worst = worst.max(e);
            }
        }
        if cluster.level == 0 {
            lod0_errors.push(worst / texel);
        }
    }
    lod0_errors.sort_by(f32::total_cmp);
    let median = lod0_errors[lod0_errors.len() / 2];
    println!(
        "tiled square: LOD-0 meshlets' worst UV error, in texels of a 1,024² texture: median \
         {median:.4}, largest {:.4}; 16 bits over the map: {:.4}",
        lod0_errors.last().unwrap(),
        whole_map_half_step / texel
    );
    assert!(
        median * texel <= whole_map_half_step / 4.0,
        "the median LOD-0 meshlet is {median} texels off"
    );
}

/// Checks every decoded meshlet against the DAG cluster it came from.
fn check_round_trip(built: &Built) {
    let asset = &built.asset;
    let quant = asset.quantization();
    let step = quant.step;
    let h = asset.header();
    for (i, cluster) in built.dag.clusters.iter().enumerate() {
        let d = asset.decode_meshlet(i);
        let decoded: Vec<u32> = d.triangles.iter().flatten().map(|&l| l as u32).collect();
        // Same corners in the same order, through the local vertex list.
        let mut locals: Vec<u32> = Vec::new();
        let mut slot = HashMap::new();
        for &g in &cluster.indices {
            slot.entry(g).or_insert_with(|| {
                locals.push(g);
                locals.len() as u32 - 1
            });
        }
        // Triangles may be rotated (winding kept), never reordered or re-wound.
        let rotated = |t: &[u32]| {
            let r = (0..3).min_by_key(|&k| t[k]).unwrap();
            [t[r], t[(r + 1) % 3], t[(r + 2) % 3]]
        };
        let expected: Vec<u32> = cluster.indices.iter().map(|g| slot[g]).collect();
        assert_eq!(
            decoded.chunks_exact(3).map(rotated).collect::<Vec<_>>(),
            expected.chunks_exact(3).map(rotated).collect::<Vec<_>>()
        );
        assert_eq!(d.positions.len(), locals.len());
        for (k, &g) in locals.iter().enumerate() {
            let p = built.mesh.positions[g as usize];
            let e = (d.positions[k] - p).abs().max_element();
            // Half a step, plus f32 rounding of `origin + q * step` at the mesh's magnitude.
            let rounding = 4.0
                * f32::EPSILON
                * (quant.origin.abs().max_element() + step * (1u32 << quant.bits) as f32);
            assert!(
                e <= step * 0.5 + rounding,
                "meshlet {i}: position error {e} > half step {}",
                step * 0.5
            );
            let n = built.mesh.normals[g as usize];
            assert!(
                (d.normals[k] - n).length() <= meshlight_scene::compress::NORMAL_ERROR_BOUND,
                "meshlet {i}: normal {} vs {n}",
                d.normals[k]
            );
            if h.has_uvs() {
                let uv = built.mesh.uvs[g as usize];
                #[allow(clippy::needless_range_loop)]
                for a in 0..2 {
                    // Half the meshlet's step: the grid's, times 2^shift.
                    let shift = uv_origin(asset, i)[a] >> 24;
                    let half = h.uv_step[a] * (1u32 << shift) as f32 * 0.5;
                    // Plus f32 rounding of `uv_min + code * uv_step` at the map's magnitude.
                    let rounding = 2.0
                        * f32::EPSILON
                        * (h.uv_min[a].abs() + h.uv_step[a] * (1u32 << 24) as f32);
                    let e = (d.uvs[k][a] - uv[a]).abs();
                    assert!(
                        e <= half + rounding,
                        "meshlet {i}: uv error {e}, half its step {half}, rounding {rounding}"
                    );
                }
            }
            assert_eq!(h.has_colors(), built.mesh.has_colors());
            if h.has_colors() {
                // Colour words: RGB as the nearest 8-bit sRGB value, alpha linear.
                let want = built.mesh.colors[g as usize];
                let got = d.colors[k];
                let srgb = |l: f32| meshlight_scene::texture::from_linear(l);
                for c in 0..3 {
                    assert_eq!(
                        meshlight_scene::texture::to_linear(srgb(want[c])),
                        got[c],
                        "meshlet {i}: colour {got:?}, wanted {want:?}"
                    );
                }
                assert!(
                    (got[3] - want[3]).abs() <= 0.5 / 255.0 + 1e-6,
                    "meshlet {i}: alpha {got:?}, wanted {want:?}"
                );
            }
        }
        // The culling sphere holds the decoded vertices.
        let m = &asset.meshlets()[i];
        let c = glam::Vec3::new(m.bounds[0], m.bounds[1], m.bounds[2]);
        assert!(
            d.positions
                .iter()
                .all(|p| p.distance(c) <= m.bounds[3] * (1.0 + 1e-6))
        );
    }
}

#[test]
fn compressed_vertices_decode_within_the_quantisation_step() {
    check_round_trip(&build(&procedural_mesh(32)));
    // With UVs and seams.
    {
        let path = common::shared_mesh("spot.obj");
        let built = build(&load_mesh(&path).unwrap());
        assert!(built.asset.header().has_uvs());
        check_round_trip(&built);
    }
    // With vertex colours: after the UV block, and without UVs.
    for uvs in [true, false] {
        let mut mesh = load_mesh(&common::shared_mesh("spot.obj")).unwrap();
        if !uvs {
            mesh.uvs.clear();
        }
        mesh.colors = mesh
            .positions
            .iter()
            .map(|p| {
                [
                    p.x.abs().min(1.0),
                    0.5 + 0.4 * p.y.sin(),
                    0.02,
                    0.25 + 0.5 * p.z.abs().min(1.0),
                ]
            })
            .collect();
        let built = build(&mesh);
        assert!(built.asset.header().has_colors());
        assert_eq!(built.asset.header().has_uvs(), uvs);
        check_round_trip(&built);
    }
}

#[test]
fn coarser_grids_pack_fewer_bits() {
    let mesh = procedural_mesh(24);
    let size = |bits| {
        build_asset(
            &mesh,
            &BuildOptions {
                position_bits: PositionBits::Fixed(bits),
                ..Default::default()
            },
            &mut |_| {},
        )
        .unwrap()
        .asset
        .bytes()
        .len()
    };
    assert!(size(12) < size(16) && size(16) < size(20));
}

/// The automatic grid is the coarsest whose worst error is at most
/// [`AUTO_ERROR_SHARE`] of the 10th-percentile LOD-0 error.
fn check_auto_grid(name: &str, built: &Built) {
    let (min, max) = built.mesh.bounds();
    let mut errors: Vec<f32> = built
        .dag
        .clusters
        .iter()
        .filter(|c| c.level == 0 && c.parent.error.is_finite())
        .map(|c| c.parent.error)
        .collect();
    errors.sort_unstable_by(f32::total_cmp);
    let reference = errors[errors.len() / 10];
    let budget = reference * AUTO_ERROR_SHARE;
    let quant = built.asset.quantization();
    assert!(
        quant.max_error() <= budget,
        "{name}: grid error {} above {budget}",
        quant.max_error()
    );
    if quant.bits > 4 && quant.bits < MAX_POSITION_BITS {
        let coarser = Quantization::new(min, max, quant.bits - 1);
        assert!(
            coarser.max_error() > budget,
            "{name}: {} bits would also do; the automatic grid should be the coarsest",
            quant.bits - 1
        );
    }
}

#[test]
fn automatic_grid_is_the_coarsest_far_below_the_lod0_error() {
    check_auto_grid("procedural 32", &build(&procedural_mesh(32)));
    {
        let path = common::shared_mesh("stanford-bunny.obj");
        check_auto_grid("bunny", &build(&load_mesh(&path).unwrap()));
    }
    // A fixed precision is taken as given.
    let fixed = build_asset(
        &procedural_mesh(12),
        &BuildOptions {
            position_bits: PositionBits::Fixed(11),
            ..Default::default()
        },
        &mut |_| {},
    )
    .unwrap();
    assert_eq!(fixed.asset.header().quant_bits, 11);
}

#[test]
fn save_then_load_gives_the_same_asset() {
    let built = build(&procedural_mesh(24));
    let dir = common::scratch("roundtrip");
    let path = dir.join("a.mlasset");
    built.asset.save(&path).unwrap();
    let loaded = MeshletAsset::load(&path).unwrap();
    assert_eq!(loaded, built.asset);
    assert_eq!(loaded.decode_meshlet(3), built.asset.decode_meshlet(3));
}

#[test]
fn builds_are_byte_identical_whatever_the_thread_count() {
    let mesh = procedural_mesh(40);
    let on = |threads| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| build(&mesh).asset.bytes().to_vec())
    };
    let (a, b, c) = (on(1), on(2), on(3));
    assert!(a == b && b == c, "same input must give the same bytes");
    {
        let path = common::shared_mesh("beast.obj");
        let mesh = load_mesh(&path).unwrap();
        assert_eq!(build(&mesh).asset.bytes(), build(&mesh).asset.bytes());
    }
}

fn write(dir: &Path, name: &str, bytes: &[u8]) -> std::path::PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, bytes).unwrap();
    p
}

#[test]
fn damaged_files_are_refused_with_typed_errors() {
    let built = build(&procedural_mesh(12));
    let good = built.asset.bytes().to_vec();
    let dir = common::scratch("damaged");

    let err = MeshletAsset::load(&write(&dir, "t.mlasset", &good[..good.len() - 7])).unwrap_err();
    assert!(matches!(err, SceneError::AssetTruncated { .. }), "{err:?}");
    let err = MeshletAsset::load(&write(&dir, "h.mlasset", &good[..40])).unwrap_err();
    assert!(matches!(err, SceneError::AssetTruncated { .. }), "{err:?}");

    let mut bad = good.clone();
    bad[..4].copy_from_slice(b"PLY\n");
    let err = MeshletAsset::load(&write(&dir, "m.mlasset", &bad)).unwrap_err();
    assert!(matches!(err, SceneError::AssetMagic { .. }), "{err:?}");
    assert!(err.to_string().contains("m.mlasset") && err.to_string().contains("meshlight bake"));
    let err = MeshletAsset::load(&write(&dir, "e.mlasset", b"")).unwrap_err();
    assert!(matches!(err, SceneError::AssetMagic { .. }), "{err:?}");

    let mut bad = good.clone();
    bad[8..12].copy_from_slice(&(VERSION + 1).to_le_bytes());
    let err = MeshletAsset::load(&write(&dir, "v.mlasset", &bad)).unwrap_err();
    assert!(
        matches!(err, SceneError::AssetVersion { found, .. } if found == VERSION + 1),
        "{err:?}"
    );
    assert!(err.to_string().contains("re-bake"));

    // A flip in the resident part fails the header's checksum; one in a page fails
    // that page's, named.
    let mut bad = good.clone();
    let at = built.asset.resident_bytes() as usize - 100;
    bad[at] ^= 0x10;
    let err = MeshletAsset::load(&write(&dir, "c.mlasset", &bad)).unwrap_err();
    assert!(matches!(err, SceneError::AssetChecksum { .. }), "{err:?}");
    let mut bad = good.clone();
    let payload = built.asset.header().sections[SECTION_PAYLOAD].offset as usize * 4;
    let page = built.asset.pages().len() / 2;
    bad[payload + built.asset.pages()[page].first_word as usize * 4 + 5] ^= 0x10;
    let err = MeshletAsset::load(&write(&dir, "p.mlasset", &bad)).unwrap_err();
    assert!(
        matches!(err, SceneError::AssetPageChecksum { page: p, .. } if p as usize == page),
        "{err:?}"
    );
    assert!(
        err.to_string()
            .contains(&format!("p.mlasset: page {page} of the asset is corrupt")),
        "{err}"
    );

    let err = MeshletAsset::load(&dir.join("missing.mlasset")).unwrap_err();
    assert!(matches!(err, SceneError::Io { .. }), "{err:?}");
}

/// A file with a valid checksum but inconsistent records (a buggy writer) is refused by
/// the structural checks, so no accessor can later index out of bounds.
#[test]
fn structurally_broken_files_with_valid_checksums_are_refused() {
    let built = build(&procedural_mesh(12));
    let words: Vec<u32> = bytemuck::cast_slice(built.asset.bytes()).to_vec();
    type Edit = (&'static str, fn(&mut MeshletRecord));
    let edits: [Edit; 2] = [
        ("data outside the payload", |m| m.data_offset = u32::MAX / 2),
        ("more than 128 triangles", |m| {
            m.counts = (m.counts & !0xff00) | (200 << 8)
        }),
    ];
    for (what, edit) in edits {
        let mut w = words.clone();
        edit(common::damage::record_mut(&mut w, SECTION_MESHLETS, 0));
        common::damage::reseal(&mut w);
        let len = w.len() as u64 * 4;
        let err = MeshletAsset::from_words(w, len, Path::new("x.mlasset")).unwrap_err();
        assert!(
            matches!(err, SceneError::AssetField { .. }),
            "{what}: {err:?}"
        );
    }
}

/// A triangle record pointing past its meshlet's vertices (valid checksum): decoding
/// clamps it into the meshlet, as the GPU does, so nothing can index out of bounds, and
/// `verify` (what `inspect` runs) reports the damage.
#[test]
fn damaged_triangle_records_decode_in_range_and_are_reported() {
    let built = build(&procedural_mesh(12));
    let mut w: Vec<u32> = bytemuck::cast_slice(built.asset.bytes()).to_vec();
    let m = built.asset.meshlets()[0];
    let payload = built.asset.header().sections[meshlight_scene::asset::format::SECTION_PAYLOAD];
    let layout = meshlight_scene::asset::format::PayloadLayout::of(&m, 0);
    // The first record's corner offset field zero: its largest corner lies half the
    // field's range below the prediction (about 0 for the first triangle), below 0.
    let at = (payload.offset + m.data_offset + layout.triangles) as usize;
    w[at] &= !((1u32 << m.triangle_bits().offset) - 1);
    common::damage::reseal(&mut w);
    let len = w.len() as u64 * 4;
    let asset = MeshletAsset::from_words(w, len, Path::new("t.mlasset")).unwrap();
    let vc = m.vertex_count() as u8;
    assert!(
        asset
            .decode_meshlet(0)
            .triangles
            .iter()
            .flatten()
            .all(|&i| i < vc)
    );
    let problems = meshlight_scene::verify::verify(&asset);
    assert!(
        problems
            .iter()
            .any(|p| p.starts_with("meshlet 0: triangle 0 refers past")),
        "{problems:?}"
    );
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 64, ..ProptestConfig::default() })]
    /// Any truncation or single-bit flip is refused, never accepted and never a panic.
    #[test]
    fn random_damage_is_always_refused(cut in 0usize..1 << 20, bit in 0usize..1 << 23, truncate: bool) {
        thread_local! {
            static GOOD: Vec<u8> = build(&procedural_mesh(6)).asset.bytes().to_vec();
        }
        let good = GOOD.with(|g| g.clone());
        let mut bad = good.clone();
        if truncate {
            bad.truncate(cut % good.len());
        } else {
            let b = bit % (good.len() * 8);
            bad[b / 8] ^= 1 << (b % 8);
        }
        let words: Vec<u32> = bad.chunks(4).map(|c| {
            let mut w = [0u8; 4];
            w[..c.len()].copy_from_slice(c);
            u32::from_le_bytes(w)
        }).collect();
        prop_assert!(MeshletAsset::from_words(words, bad.len() as u64, Path::new("p")).is_err());
    }
}
