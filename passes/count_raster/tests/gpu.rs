//! `count_raster` on the GPU, both implementations, against `cpu_count` on the list
//! `z_slice` wrote on the GPU: seeded random scenes of every kind under perspective and
//! orthographic views, hand-placed lights, zero objects. Counts may differ from the
//! reference only by pairs whose deciding value lies within `NEAR` (relative) of its
//! threshold; such pairs are counted and bounded.

use glam::Vec3;
use meshlight_graph::Imports;
use meshlight_pass_count_raster::KINDS;
use meshlight_pass_count_raster::cpu::{CountResult, cpu_count};
use meshlight_pass_count_raster::testbed::{Counted, Implementation, Scene};
use meshlight_pass_z_slice::scenes::{Rng, object, perspective, random_camera, random_objects};
use meshlight_pass_z_slice::testbed::read;
use meshlight_pass_z_slice::{GridSettings, SliceInstance, ZSlice};
use meshlight_shaders::cpu::layout::{ClusterGrid, ClusterableKind, ClusterableObject, View};
use meshlight_testing::executor;

/// A pair decided differently from the reference must lie this close to its threshold.
const NEAR: f32 = 1e-5;

struct GpuCounts {
    instances: Vec<SliceInstance>,
    counts: Vec<u32>,
    grid: ClusterGrid,
}

fn run(scene: &Scene, implementation: Implementation) -> GpuCounts {
    let mut counted = Counted::add(scene, implementation).unwrap();
    let counts = counted.outputs.buffer("cluster_counts").unwrap();
    counted.graph.export(counts);
    let mut exec = executor();
    let (instances, grid) = counted.run(&mut exec, Imports::new()).unwrap();
    GpuCounts {
        instances,
        counts: read(&mut exec, "cluster_counts"),
        grid,
    }
}

/// How many pairs of each (froxel, kind) cell the GPU may decide otherwise: near
/// decisions, and the ring of froxels around a rectangle whose edge lies near a tile
/// boundary.
fn slack(
    grid: &ClusterGrid,
    objects: &[ClusterableObject],
    instances: &[SliceInstance],
    reference: &CountResult,
) -> Vec<u32> {
    let mut slack = vec![0u32; reference.counts.len()];
    for (pair, walked) in instances.iter().zip(&reference.instances) {
        let kind = objects[pair.object as usize].kind;
        for (froxel, decision) in &walked.tested {
            if decision.closeness < NEAR {
                slack[(froxel * KINDS + kind) as usize] += 1;
            }
        }
        if walked.rect_closeness < NEAR {
            let r = walked.rect;
            let (x0, y0) = (r.min[0].saturating_sub(1), r.min[1].saturating_sub(1));
            let x1 = (r.max[0] + 1).min(grid.dims[0] - 1);
            let y1 = (r.max[1] + 1).min(grid.dims[1] - 1);
            for y in y0..=y1 {
                for x in x0..=x1 {
                    let froxel = (pair.slice * grid.dims[1] + y) * grid.dims[0] + x;
                    slack[(froxel * KINDS + kind) as usize] += 1;
                }
            }
        }
    }
    slack
}

/// Checks the GPU's counts against the reference; returns how many pairs differed.
fn compare(
    view: &View,
    objects: &[ClusterableObject],
    got: &GpuCounts,
    expected_grid: &ClusterGrid,
    label: &str,
) -> (usize, u32) {
    assert_eq!(&got.grid, expected_grid, "{label}: grid");
    let reference = cpu_count(view, &got.grid, objects, &got.instances);
    assert_eq!(got.counts.len(), reference.counts.len());
    let slack = slack(&got.grid, objects, &got.instances, &reference);
    let mut differing = 0;
    for (cell, (&gpu, &cpu)) in got.counts.iter().zip(&reference.counts).enumerate() {
        let diff = gpu.abs_diff(cpu);
        assert!(
            diff <= slack[cell],
            "{label}: froxel {} kind {}: GPU {gpu}, reference {cpu}, only {} pairs near a threshold",
            cell as u32 / KINDS,
            cell as u32 % KINDS,
            slack[cell]
        );
        differing += diff as usize;
    }
    (differing, reference.counts.iter().sum())
}

fn scene(rng: &mut Rng, index: u32) -> Scene {
    let (camera, target) = random_camera(rng, index % 2 == 1);
    let viewport = [[320, 180], [256, 256], [640, 360]][rng.below(3) as usize];
    let view = camera.view(viewport, index, None);
    let objects = random_objects(rng, 200, target, 60.0);
    let z_slice = ZSlice {
        grid: GridSettings {
            dims: [[16, 9, 24], [8, 8, 16], [12, 7, 1], [32, 18, 32]][index as usize % 4],
            first_slice_end: [5.0, 1.0, 0.5][rng.below(3) as usize],
            far: [100.0, 1000.0][rng.below(2) as usize],
        },
        quad_vertices: [4, 6][rng.below(2) as usize],
        ..ZSlice::default()
    };
    Scene {
        view,
        objects,
        z_slice,
    }
}

#[test]
fn random_scenes_count_like_the_reference_in_both_implementations() {
    let mut rng = Rng(0xc0ff_ee00_1234_5678);
    let mut per_kind = [0u32; 4];
    let (mut differing, mut orthographic_scenes, mut scenes_in_rounds) = (0, 0, 0);
    for index in 0..6 {
        let scene = scene(&mut rng, index);
        let [w, h] = scene.view.viewport_size.map(|v| v as u32);
        let grid = scene.z_slice.grid([w, h]);
        let raster = run(&scene, Implementation::Raster);
        let compute = run(&scene, Implementation::Compute);
        let rounds = run(&scene, Implementation::ComputeRounds);
        if rounds.instances.len() > 2 * 64 {
            scenes_in_rounds += 1;
        }
        assert!(
            rounds.counts == compute.counts,
            "scene {index}: the walk in rounds counted otherwise than the one-round walk"
        );
        let sorted = |list: &[SliceInstance]| {
            let mut list = list.to_vec();
            list.sort();
            list
        };
        assert!(
            sorted(&raster.instances) == sorted(&compute.instances),
            "scene {index}: z_slice wrote different lists in two runs"
        );
        let [(d_raster, total), (d_compute, _)] = [
            (&raster, Implementation::Raster),
            (&compute, Implementation::Compute),
        ]
        .map(|(got, i)| {
            let label = format!("scene {index} {i:?} ({:?})", scene.z_slice.grid);
            compare(&scene.view, &scene.objects, got, &grid, &label)
        });
        assert!(
            total > 100,
            "scene {index}: only {total} pairs; the scene tests little"
        );
        // The two implementations run the same test functions.
        let between = raster
            .counts
            .iter()
            .zip(&compute.counts)
            .filter(|(a, b)| a != b)
            .count();
        assert!(
            between <= d_raster + d_compute,
            "scene {index}: raster and compute differ in {between} cells beyond near pairs"
        );
        differing += d_raster + d_compute;
        orthographic_scenes += index % 2;
        for (cell, c) in raster.counts.iter().enumerate() {
            per_kind[cell % KINDS as usize] += c;
        }
        eprintln!(
            "scene {index}: {total} pairs, {} instances, near pairs decided otherwise: raster {d_raster}, compute {d_compute}",
            raster.instances.len()
        );
    }
    assert!(per_kind.iter().all(|&c| c > 0), "{per_kind:?}");
    assert!(orthographic_scenes > 0);
    assert!(
        scenes_in_rounds >= 3,
        "only {scenes_in_rounds} scenes took the one workgroup three rounds or more"
    );
    assert!(differing <= 12, "{differing} pairs decided otherwise");
}

#[test]
fn lights_around_the_camera_count_where_they_must() {
    let view = perspective(Vec3::ZERO, Vec3::new(0.0, 0.0, -1.0), 1.2).view([320, 180], 0, None);
    let z_slice = ZSlice::default();
    let grid = z_slice.grid([320, 180]);
    let p = ClusterableKind::PointLight;
    let objects = vec![
        // Contains the camera: every froxel of the first slices.
        object(p, Vec3::ZERO, 2.0),
        // Straddles the far end of the grid.
        object(p, Vec3::new(0.0, 0.0, -1000.0), 50.0),
        // Behind the camera: nothing.
        object(p, Vec3::new(0.0, 0.0, 30.0), 5.0),
        // A small light on the view axis at 10 m: the centre tiles of its slices only.
        object(p, Vec3::new(0.0, 0.0, -10.0), 0.5),
    ];
    let scene = Scene {
        view,
        objects,
        z_slice,
    };
    for implementation in Implementation::ALL {
        let got = run(&scene, implementation);
        let label = format!("{implementation:?}");
        let (differing, _) = compare(&scene.view, &scene.objects, &got, &grid, &label);
        assert_eq!(differing, 0, "{label}");
        let at = |x: u32, y: u32, z: u32| got.counts[((z * 9 + y) * 16 + x) as usize * 4];
        // The light reaches 2 m around the camera: every tile of slice 0 (from the near
        // plane to 5 m) touches it.
        for y in 0..9 {
            for x in 0..16 {
                assert!(at(x, y, 0) >= 1, "{label}: tile {x},{y} of slice 0");
            }
        }
        let slice_of_10m = meshlight_shaders::cpu::light::z_slice_of_depth(&grid, 10.0);
        // Centred on the boundary between tile columns 7 and 8, inside row 4.
        assert_eq!(at(7, 4, slice_of_10m), 1, "{label}: the small light");
        assert_eq!(at(8, 4, slice_of_10m), 1, "{label}: the small light");
        assert_eq!(at(8, 3, slice_of_10m), 0, "{label}: the small light's row");
        assert_eq!(
            at(0, 0, slice_of_10m),
            0,
            "{label}: the small light in a corner tile"
        );
        let last = grid.dims[2] - 1;
        assert!(at(8, 4, last) >= 1, "{label}: the far light");
    }
}

#[test]
fn no_objects_count_nothing() {
    let scene = Scene {
        view: perspective(Vec3::ZERO, Vec3::new(0.0, 0.0, -1.0), 1.2).view([320, 180], 0, None),
        objects: Vec::new(),
        z_slice: ZSlice::default(),
    };
    for implementation in Implementation::ALL {
        let got = run(&scene, implementation);
        assert!(got.instances.is_empty());
        assert!(got.counts.iter().all(|&c| c == 0), "{implementation:?}");
    }
}
