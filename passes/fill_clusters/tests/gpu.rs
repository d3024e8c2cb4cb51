//! `fill_clusters` on the GPU against `cpu_fill`: which instances request clusters, the
//! clusters themselves (as a multiset: the order of the runs follows the atomics), each
//! instance's run contiguous and in meshlet order, and with a small capacity the two
//! count words, the straddling instance's prefix and an untouched guard region after
//! the capacity.

mod support;

use glam::{Mat4, Quat, Vec3};
use meshlight_gpu_scene::{Camera, Material, SceneData, data::Limits};
use meshlight_pass_fill_clusters::{FillClusters, FillResult, cpu_fill};
use meshlight_scene::procedural_mesh;
use meshlight_shaders::cpu::layout::{Cluster, View};
use std::collections::BTreeMap;
use support::run::{Frame, run_fill};
use support::scenes::bake;
use support::*;

/// Two meshes of different sizes (the larger with more meshlets than a workgroup has
/// threads, so threads write several clusters each); instances in view, behind the camera, far to the
/// side, rotated and scaled unevenly, and one whose sphere reaches into the view only
/// because of its scale.
fn scene() -> SceneData {
    let mut data = SceneData::new(Limits::default());
    let material = data
        .add_material(Material {
            base_color: [1.0; 3],
            ..Material::default()
        })
        .unwrap();
    let mut meshes = Vec::new();
    for segments in [4, 20] {
        let asset = bake(&procedural_mesh(segments));
        meshes.push(data.add_mesh("knot", &asset).unwrap());
    }
    let placements = [
        (0, Mat4::from_translation(Vec3::new(-8.0, 0.0, 0.0))),
        (1, Mat4::from_translation(Vec3::new(0.0, 0.0, 0.0))),
        (0, Mat4::from_translation(Vec3::new(0.0, 0.0, 40.0))), // behind the camera
        (
            1,
            Mat4::from_scale_rotation_translation(
                Vec3::new(0.5, 2.0, 1.0),
                Quat::from_rotation_y(0.7),
                Vec3::new(8.0, 0.0, -4.0),
            ),
        ),
        (1, Mat4::from_translation(Vec3::new(-300.0, 0.0, 0.0))), // far left
        (0, Mat4::from_translation(Vec3::new(0.0, 6.0, -20.0))),
        (1, Mat4::from_translation(Vec3::new(0.0, -200.0, 0.0))), // far below
        (
            1,
            // Off to the right at 40 units, pulled into view by a scale of 20.
            Mat4::from_scale_rotation_translation(
                Vec3::splat(20.0),
                Quat::IDENTITY,
                Vec3::new(60.0, 0.0, 0.0),
            ),
        ),
        (0, Mat4::from_translation(Vec3::new(4.0, -3.0, 2.0))),
    ];
    for (mesh, transform) in placements {
        data.add_instance(meshes[mesh], transform, material)
            .unwrap()
            .expect("an invertible transform");
    }
    data
}

fn view() -> View {
    Camera::perspective(Vec3::new(0.0, 2.0, 20.0), Vec3::ZERO, 1.0, 0.1).view([320, 240], 0, None)
}

/// What every test starts from: the scene, the view, and `cpu_fill`'s list of it with no
/// capacity.
fn scene_view_and_reference() -> (SceneData, View, FillResult) {
    let (data, view) = (scene(), view());
    let reference = cpu_fill(&data, &view, u32::MAX);
    (data, view, reference)
}

/// Runs `pass` over a sentinel-filled list of `slots`.
fn run(data: &mut SceneData, view: &View, pass: FillClusters, slots: u32) -> Frame {
    run_fill(data, view, Box::new(pass), slots, None)
}

/// The written slots as runs per instance: instance → (first slot, clusters in order).
fn runs(written: &[Cluster]) -> BTreeMap<u32, (usize, Vec<Cluster>)> {
    let mut runs: BTreeMap<u32, (usize, Vec<Cluster>)> = BTreeMap::new();
    for (slot, c) in written.iter().enumerate() {
        let run = runs.entry(c.instance).or_insert((slot, Vec::new()));
        assert_eq!(
            run.0 + run.1.len(),
            slot,
            "instance {}'s clusters are not contiguous (slot {slot})",
            c.instance
        );
        run.1.push(*c);
    }
    runs
}

/// Each run is a prefix of its visible instance's reference clusters, in meshlet order;
/// returns how many runs are partial (cut by the capacity).
fn check_runs(reference: &FillResult, written: &[Cluster]) -> usize {
    let mut want: BTreeMap<u32, Vec<Cluster>> = BTreeMap::new();
    for c in &reference.clusters {
        want.entry(c.instance).or_default().push(*c);
    }
    let mut partial = 0;
    for (instance, (_, got)) in runs(written) {
        let want = want
            .get(&instance)
            .unwrap_or_else(|| panic!("instance {instance} is not visible but wrote clusters"));
        assert!(
            got.len() <= want.len() && got[..] == want[..got.len()],
            "instance {instance}: clusters out of meshlet order or wrong"
        );
        partial += usize::from(got.len() < want.len());
    }
    partial
}

#[test]
fn clusters_equal_the_reference_when_the_capacity_suffices() {
    let (mut data, view, reference) = scene_view_and_reference();
    // The scene exercises both outcomes, with no instance within rounding of a plane.
    assert!(
        reference.visible_instances.len() >= 5,
        "{:?}",
        reference.visible_instances
    );
    assert!(reference.visible_instances.len() < data.instances.len());
    assert!(
        reference.visible_instances.contains(&7),
        "the scaled instance is visible"
    );
    assert!(
        data.meshes[1].meshlet_count > 64,
        "{}",
        data.meshes[1].meshlet_count
    );
    for (i, instance) in data.instances.iter().enumerate() {
        let s = meshlight_pass_fill_clusters::cpu::instance_sphere(&data, instance);
        let margin =
            meshlight_pass_fill_clusters::cpu::frustum_margin(&view, [s[0], s[1], s[2]], s[3]);
        assert!(margin.abs() > 0.1, "instance {i} lies on a plane: {margin}");
    }
    let capacity = reference.requested + 5;
    let got = run(&mut data, &view, FillClusters::default(), capacity);
    assert_eq!(got.cluster_count, [reference.written, reference.requested]);
    let n = reference.requested as usize;
    let written = &got.list[..n];
    let mut sorted = written.to_vec();
    sorted.sort_by_key(|c| (c.instance, c.meshlet));
    assert_eq!(sorted, reference.clusters, "the multiset of clusters");
    assert_eq!(check_runs(&reference, written), 0);
    assert!(
        got.list[n..].iter().all(|c| *c == SENTINEL),
        "a slot past the requested ones was written"
    );
}

/// Subset sums of the visible instances' cluster counts: a capacity that is none of
/// them must cut some instance's run.
fn subset_sums(counts: &[u32]) -> Vec<bool> {
    let total: u32 = counts.iter().sum();
    let mut reachable = vec![false; total as usize + 1];
    reachable[0] = true;
    for &c in counts {
        for s in (c as usize..=total as usize).rev() {
            reachable[s] |= reachable[s - c as usize];
        }
    }
    reachable
}

#[test]
fn a_small_capacity_writes_exactly_the_capacity_and_nothing_past_it() {
    let (mut data, view, full) = scene_view_and_reference();
    let counts: Vec<u32> = full
        .visible_instances
        .iter()
        .map(|&i| data.instances[i as usize].meshlet_count)
        .collect();
    let sums = subset_sums(&counts);
    // Near half the clusters, at a count no set of whole instances adds up to.
    let capacity = (full.requested / 2..full.requested)
        .find(|&c| !sums[c as usize])
        .expect("a capacity that cuts an instance");
    let reference = cpu_fill(&data, &view, capacity);
    assert_eq!(reference.written, capacity);
    // The list is longer than the capacity: the pass is told the capacity by parameter,
    // so a write past it lands in the guard instead of being dropped by bounds checks.
    let pass = FillClusters {
        capacity: Some(capacity),
        instance_count: None,
        ..FillClusters::default()
    };
    let got = run(&mut data, &view, pass, capacity + GUARD);
    assert_eq!(got.cluster_count, [capacity, full.requested]);
    let written = got.filled_to(capacity);
    assert_eq!(
        check_runs(&full, written),
        1,
        "exactly one instance straddles"
    );
}

#[test]
fn instance_count_limits_the_instances_visited() {
    let (mut data, view, full) = scene_view_and_reference();
    let mut first_four = data.clone();
    first_four.instances.truncate(4);
    let reference = cpu_fill(&first_four, &view, u32::MAX);
    assert!(reference.requested < full.requested);
    let pass = FillClusters {
        capacity: None,
        instance_count: Some(4),
        ..FillClusters::default()
    };
    let got = run(&mut data, &view, pass, full.requested);
    assert_eq!(
        got.cluster_count,
        [reference.requested, reference.requested]
    );
    let mut sorted = got.list[..reference.requested as usize].to_vec();
    sorted.sort_by_key(|c| (c.instance, c.meshlet));
    assert_eq!(sorted, reference.clusters);
}
