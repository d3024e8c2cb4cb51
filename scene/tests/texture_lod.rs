//! Textures through the LOD levels: at every level of a textured mesh, the texel a
//! coarse triangle draws at a point was drawn at full detail within the level's stored
//! error of that point, and coarse cuts close up across UV seams.

mod common;

use glam::{Vec2, Vec3};
use meshlight_scene::load::load_mesh;
use meshlight_scene::uv_slide::{UvSurface, texel_size, uv_charts};
use meshlight_scene::watertight::crack_problems;
use meshlight_scene::{BuildOptions, Built, Mesh, build_asset};

fn build(mesh: &Mesh) -> Built {
    build_asset(mesh, &BuildOptions::default(), &mut |_| {}).unwrap()
}

/// A bumpy square of `n × n` cells whose UVs are warped (not a linear function of the
/// position), so that dropping a vertex moves the texture even where the surface barely
/// moves.
fn warped_grid(n: u32) -> Mesh {
    let tau = std::f32::consts::TAU;
    common::generators::textured_square("warped grid", n, |x, y| {
        let z = 0.02 * (tau * 2.0 * x).sin() * (tau * 1.5 * y).cos();
        let uv = [
            x + 0.03 * (tau * 2.0 * y).sin(),
            y + 0.03 * (tau * 3.0 * x).sin(),
        ];
        (z, uv)
    })
}

/// A latitude-longitude sphere whose map wraps: the column at longitude 0 is there
/// twice, once with U = 0 and once with U = 1 (a UV seam), and each pole triangle has
/// its own copy of the pole.
fn wrapped_sphere(rings: u32, segments: u32) -> Mesh {
    let mut mesh = Mesh {
        source: "wrapped sphere".into(),
        ..Mesh::default()
    };
    let pi = std::f32::consts::PI;
    for r in 0..=rings {
        for s in 0..=segments {
            let (u, v) = (s as f32 / segments as f32, r as f32 / rings as f32);
            let (theta, phi) = (u * 2.0 * pi, v * pi);
            let p = Vec3::new(phi.sin() * theta.cos(), phi.cos(), -phi.sin() * theta.sin());
            // The poles exactly on the axis, so their copies share one position.
            let p = if r == 0 || r == rings {
                Vec3::new(0.0, p.y.signum(), 0.0)
            } else {
                p
            };
            mesh.positions.push(p);
            mesh.normals.push(p.normalize());
            mesh.uvs.push([u, v]);
        }
    }
    let at = |r: u32, s: u32| r * (segments + 1) + s;
    for r in 0..rings {
        for s in 0..segments {
            let (a, b, c, d) = (at(r, s), at(r + 1, s), at(r + 1, s + 1), at(r, s + 1));
            if r != 0 {
                mesh.indices.extend_from_slice(&[a, b, d]);
            }
            if r != rings - 1 {
                mesh.indices.extend_from_slice(&[b, c, d]);
            }
        }
    }
    mesh
}

/// Float rounding allowance, as a share of the mesh's largest extent.
const ROUNDING: f32 = 1e-5;

/// For every simplified meshlet, the texel drawn at each sample point (corners, edge
/// midpoints, centroid) lies within the meshlet's stored LOD error of where LOD 0 draws
/// it, measured directly against LOD 0 rather than level by level as the builder does.
/// Returns the worst slide per level, and prints it with its ratio to the stored error.
fn check_texture_slide(name: &str, built: &Built) -> Vec<f32> {
    let mesh = &built.mesh;
    assert!(mesh.has_uvs(), "{name} has no UVs");
    let charts = uv_charts(mesh.positions.len(), &mesh.indices);
    let texel = texel_size(&mesh.positions, &mesh.uvs, &mesh.indices);
    let lod0: Vec<u32> = built
        .dag
        .clusters
        .iter()
        .filter(|c| c.level == 0)
        .flat_map(|c| c.indices.iter().copied())
        .collect();
    let surface = UvSurface::new(&mesh.positions, &mesh.uvs, &charts, &lod0, texel);
    let (min, max) = mesh.bounds();
    let rounding = ROUNDING * (max - min).max_element();
    let levels = built.dag.level_count as usize;
    let (mut worst, mut ratio) = (vec![0.0f32; levels], vec![0.0f32; levels]);
    for cluster in built.dag.clusters.iter().filter(|c| c.level > 0) {
        let bound = cluster.lod.error;
        for t in cluster.indices.chunks_exact(3) {
            let p = [t[0], t[1], t[2]].map(|v| mesh.positions[v as usize]);
            let uv = [t[0], t[1], t[2]].map(|v| Vec2::from(mesh.uvs[v as usize]));
            let chart = charts[t[0] as usize];
            let samples = [
                [1.0, 0.0, 0.0],
                [0.0, 1.0, 0.0],
                [0.0, 0.0, 1.0],
                [0.5, 0.5, 0.0],
                [0.0, 0.5, 0.5],
                [0.5, 0.0, 0.5],
                [1.0 / 3.0; 3],
            ];
            for w in samples {
                let at = p[0] * w[0] + p[1] * w[1] + p[2] * w[2];
                let at_uv = uv[0] * w[0] + uv[1] * w[1] + uv[2] * w[2];
                let slide = surface.slide(at, at_uv, chart);
                let level = cluster.level as usize;
                worst[level] = worst[level].max(slide);
                if bound > 0.0 {
                    ratio[level] = ratio[level].max(slide / bound);
                }
                assert!(
                    slide <= bound + rounding,
                    "{name}: level {level}: the texel at UV {at_uv} is drawn at {at}, {slide} \
                     from where LOD 0 draws it; the stored error is {bound}"
                );
            }
        }
    }
    println!("{name}: worst texture slide per level {worst:?}, over the stored error {ratio:.3?}");
    worst
}

#[test]
fn every_level_draws_each_texel_within_its_stored_error_of_lod_0() {
    let grid = build(&warped_grid(64));
    let slides = check_texture_slide("warped grid", &grid);
    // The check has something to check: the warped map does slide at coarse levels.
    assert!(
        slides.iter().any(|&s| s > 1e-3),
        "the warped grid's texture never slid: {slides:?}"
    );
    check_texture_slide("wrapped sphere", &build(&wrapped_sphere(32, 64)));
    let spot = load_mesh(&common::shared_mesh("spot.obj")).unwrap();
    check_texture_slide("spot", &build(&spot));
}

#[test]
fn coarse_cuts_close_up_across_uv_seams() {
    for mesh in [
        wrapped_sphere(32, 64),
        load_mesh(&common::shared_mesh("spot.obj")).unwrap(),
    ] {
        let built = build(&mesh);
        assert!(built.dag.level_count > 3, "{}: too few levels", mesh.source);
        let seams = meshlight_scene::mesh::position_remap(&built.mesh.positions)
            .iter()
            .enumerate()
            .filter(|&(v, &r)| r != v as u32 && built.mesh.uvs[v] != built.mesh.uvs[r as usize])
            .count();
        assert!(seams > 0, "{}: no UV seam to check", mesh.source);
        // The crack check joins the copies of a position, whatever their UVs.
        let problems = crack_problems(&built.asset);
        assert!(problems.is_empty(), "{}: {problems:?}", mesh.source);
    }
}
