//! The whole light clustering on the GPU (lavapipe in CI): the lists equal the CPU
//! reference of the assignment as sets, for both implementations, perspective and
//! orthographic, built in code and from the pipeline file; the implementation swap is
//! one line of the file; overflow grows and the lists are exact within the stated frames;
//! bad input gives typed errors and counted warnings.

use glam::Vec3;
use meshlight::graph::GraphError;
use meshlight::shaders::cpu::layout::{ClusterableKind, ClusterableObject, View};
use meshlight::z_slice::scenes::{Rng, object, perspective, random_camera, random_objects};
use meshlight_light_clustering::reference::{Assignment, cpu_assign, cpu_assign_parallel};
use meshlight_light_clustering::{
    Clustered, Clusterer, ClusteringSettings, ClusteringSource, ClusteringWarning,
};
use std::collections::BTreeSet;
use std::path::PathBuf;

const NEAR: f32 = 1e-5;
const KINDS: u32 = 4;

fn pipeline_file() -> PathBuf {
    PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/../.."))
        .join("pipelines/light_clustering.toml")
}

fn settings(viewport: [u32; 2], implementation: &str) -> ClusteringSettings {
    ClusteringSettings {
        implementation: Some(implementation.into()),
        ..ClusteringSettings::new(viewport, 1024)
    }
}

/// Compares every (froxel, kind) list as a set; returns the pairs decided otherwise, all
/// of which must lie within `NEAR` of a threshold: a froxel test, a rectangle edge, or
/// the object's slice range in z_slice.
fn compare(
    view: &View,
    got: &Clustered,
    want: &Assignment,
    objects: &[ClusterableObject],
    label: &str,
) -> usize {
    assert_eq!(got.grid, want.grid, "{label}: grid");
    assert!(
        !got.counts.overflowed(),
        "{label}: still overflowing: {:?}",
        got.counts
    );
    let near_slices: BTreeSet<u32> = (0..objects.len() as u32)
        .filter(|&o| {
            meshlight::z_slice::cpu::object_extent(view, &want.grid, &objects[o as usize])
                .closeness(&want.grid)
                < NEAR
        })
        .collect();
    let mut near: Vec<BTreeSet<u32>> = vec![BTreeSet::new(); want.lists.counts.len()];
    for (pair, walked) in want.instances.iter().zip(&want.counted.instances) {
        let kind = objects[pair.object as usize].kind;
        for (froxel, d) in &walked.tested {
            if d.closeness < NEAR || walked.rect_closeness < NEAR {
                near[(froxel * KINDS + kind) as usize].insert(pair.object);
            }
        }
    }
    let mut differing = 0;
    for froxel in 0..want.grid.cluster_count {
        for kind in 0..KINDS {
            let list = got.lists.list(froxel, kind);
            let mine: BTreeSet<u32> = list.iter().copied().collect();
            assert_eq!(mine.len(), list.len(), "{label}: an object twice in a list");
            let theirs: BTreeSet<u32> = want.lists.list(froxel, kind).iter().copied().collect();
            for o in mine.symmetric_difference(&theirs) {
                assert!(
                    near[(froxel * KINDS + kind) as usize].contains(o) || near_slices.contains(o),
                    "{label}: froxel {froxel} kind {kind}: object {o} {}",
                    if mine.contains(o) {
                        "only on the GPU"
                    } else {
                        "missing on the GPU"
                    }
                );
                differing += 1;
            }
        }
    }
    differing
}

fn random_scene(rng: &mut Rng, index: u32) -> (View, Vec<ClusterableObject>) {
    let (camera, target) = random_camera(rng, index % 2 == 1);
    (
        camera.view([320, 180], index, None),
        random_objects(rng, 200, target, 60.0),
    )
}

#[test]
fn the_lists_equal_the_reference_for_both_implementations_and_the_pipeline_file() {
    let mut rng = Rng(0x11c4_7c15_7e12);
    let mut differing = 0;
    for index in 0..4 {
        let (view, objects) = random_scene(&mut rng, index);
        let mut sources = vec![];
        for implementation in ["compute", "raster"] {
            sources.push((implementation, ClusteringSource::Code));
        }
        sources.push(("compute", ClusteringSource::File(pipeline_file())));
        let want = cpu_assign(&view, &settings([320, 180], "compute"), &objects);
        assert!(
            want.lists.needed > 500,
            "scene {index}: {} entries",
            want.lists.needed
        );
        for (implementation, source) in sources {
            let label = format!("scene {index} {implementation:?} {source:?}");
            let mut clusterer = Clusterer::new(settings([320, 180], implementation), &source)
                .unwrap_or_else(|e| panic!("{label}: {e}"));
            let got = clusterer.cluster_still(&view, &objects).unwrap();
            differing += compare(&view, &got, &want, &objects, &label);
            assert_eq!(got.frames, 1, "{label}: the default sizes overflowed");
        }
    }
    assert!(differing <= 8, "{differing} pairs decided otherwise");
}

#[test]
fn the_implementation_swap_is_one_line_of_the_pipeline_file() {
    let mut rng = Rng(0x5a4b_0001_0203_0405);
    let (view, objects) = random_scene(&mut rng, 0);
    let want = cpu_assign(&view, &settings([320, 180], "compute"), &objects);
    let text = std::fs::read_to_string(pipeline_file()).unwrap();
    for stage in ["count_raster", "populate"] {
        let from = format!("stage = \"{stage}\"\nimplementation = \"compute\"");
        let to = format!("stage = \"{stage}\"\nimplementation = \"raster\"");
        assert!(
            text.contains(&from),
            "the file names {stage}'s implementation on one line"
        );
        let swapped = text.replace(&from, &to);
        let changed = text
            .lines()
            .zip(swapped.lines())
            .filter(|(a, b)| a != b)
            .count();
        assert_eq!(changed, 1);
        let path = std::env::temp_dir().join(format!("light_clustering_{stage}_raster.toml"));
        std::fs::write(&path, swapped).unwrap();
        let label = format!("{stage} swapped to raster");
        // Settings that name no implementation: the file's stands.
        let mut clusterer = Clusterer::new(
            ClusteringSettings::new([320, 180], 1024),
            &ClusteringSource::File(path.clone()),
        )
        .unwrap_or_else(|e| panic!("{label}: {e}"));
        let implementations: Vec<&str> = clusterer
            .compiled
            .plan
            .passes
            .iter()
            .map(|p| p.implementation)
            .collect();
        assert!(
            implementations.contains(&"raster"),
            "{label}: {implementations:?}"
        );
        let got = clusterer.cluster_still(&view, &objects).unwrap();
        compare(&view, &got, &want, &objects, &label);
        std::fs::remove_file(path).ok();
    }
}

#[test]
fn the_parallel_reference_equals_the_serial_one() {
    let mut rng = Rng(0x9a4a_11e1_0000_0001);
    for index in 0..4 {
        let (view, objects) = random_scene(&mut rng, index);
        let s = settings([320, 180], "compute");
        let serial = cpu_assign(&view, &s, &objects);
        let parallel = cpu_assign_parallel(&view, &s, &objects);
        assert_eq!(serial.instances, parallel.instances);
        assert_eq!(serial.lists, parallel.lists);
    }
}

#[test]
fn overflowing_lists_grow_and_are_exact_within_three_frames() {
    let mut rng = Rng(0x0f10_0f10_0f10_0f10);
    let (view, objects) = random_scene(&mut rng, 2);
    for implementation in ["compute", "raster"] {
        let s = ClusteringSettings {
            slice_instances: 4,
            entries: 16,
            ..settings([320, 180], implementation)
        };
        let want = cpu_assign(&view, &s, &objects);
        let mut clusterer = Clusterer::new(s, &ClusteringSource::Code).unwrap();
        let got = clusterer.cluster_still(&view, &objects).unwrap();
        let label = format!("{implementation:?}");
        assert!(got.frames <= 3, "{label}: {} frames", got.frames);
        let params: Vec<&str> = clusterer.counters.growths.iter().map(|g| g.param).collect();
        assert!(params.contains(&"slice_instances"), "{label}: {params:?}");
        assert!(params.contains(&"cluster_entries"), "{label}: {params:?}");
        compare(&view, &got, &want, &objects, &label);
        // Every later frame is exact too.
        clusterer.frame(&view, &objects).unwrap();
        let again = clusterer.cluster_still(&view, &objects).unwrap();
        assert_eq!(again.frames, 1, "{label}");
        compare(&view, &again, &want, &objects, &label);
    }
}

#[test]
fn bad_objects_are_skipped_counted_and_warned_about() {
    let view = perspective(Vec3::ZERO, Vec3::new(0.0, 0.0, -1.0), 1.2).view([320, 180], 0, None);
    let p = ClusterableKind::PointLight;
    let mut nan = object(p, Vec3::new(0.0, 0.0, -10.0), 1.0);
    nan.position_range[1] = f32::NAN;
    let negative = object(p, Vec3::new(0.0, 0.0, -10.0), -1.0);
    let objects = vec![
        nan,
        negative,
        // Contains the camera.
        object(p, Vec3::ZERO, 3.0),
        // Behind it.
        object(p, Vec3::new(0.0, 0.0, 20.0), 2.0),
        // Straddles the near plane and reaches past the far end of the grid.
        object(p, Vec3::new(0.0, 0.0, -600.0), 700.0),
        // Infinite range: clamped, every froxel.
        object(
            ClusterableKind::Probe,
            Vec3::new(3.0, 0.0, -30.0),
            f32::INFINITY,
        ),
        // Range 0: nothing, and no warning.
        object(p, Vec3::new(0.0, 0.0, -5.0), 0.0),
    ];
    let s = settings([320, 180], "compute");
    let want = cpu_assign(&view, &s, &objects);
    let mut clusterer = Clusterer::new(s, &ClusteringSource::Code).unwrap();
    let got = clusterer.cluster_still(&view, &objects).unwrap();
    compare(&view, &got, &want, &objects, "bad objects");
    assert_eq!(got.counts.invalid, 2);
    assert!(
        clusterer
            .counters
            .warnings
            .iter()
            .any(|w| matches!(w, ClusteringWarning::InvalidObjects { count: 2, .. })),
        "{:?}",
        clusterer.counters.warnings
    );
    let froxels = want.grid.cluster_count;
    for froxel in 0..froxels {
        assert!(
            got.lists.list(froxel, 2).contains(&5),
            "the infinite probe misses froxel {froxel}"
        );
        assert!(
            !got.lists.list(froxel, 0).contains(&3),
            "the light behind the camera"
        );
    }
}

#[test]
fn zero_objects_give_empty_lists() {
    let view = perspective(Vec3::ZERO, Vec3::new(0.0, 0.0, -1.0), 1.2).view([320, 180], 0, None);
    for implementation in ["compute", "raster"] {
        let mut clusterer = Clusterer::new(
            settings([320, 180], implementation),
            &ClusteringSource::Code,
        )
        .unwrap();
        let got = clusterer.cluster_still(&view, &[]).unwrap();
        assert_eq!(got.counts.entries_needed, 0);
        assert!(got.lists.counts.iter().all(|&c| c == 0));
    }
}

#[test]
fn too_many_objects_and_an_empty_grid_are_typed_errors() {
    let view = perspective(Vec3::ZERO, Vec3::new(0.0, 0.0, -1.0), 1.2).view([320, 180], 0, None);
    let mut clusterer = Clusterer::new(
        ClusteringSettings::new([320, 180], 4),
        &ClusteringSource::Code,
    )
    .unwrap();
    let five = vec![object(ClusterableKind::PointLight, Vec3::new(0.0, 0.0, -5.0), 1.0); 5];
    match clusterer.frame(&view, &five) {
        Err(GraphError::Setting { message, .. }) => {
            assert!(
                message.contains("holds 4") && message.contains("`objects`"),
                "{message}"
            )
        }
        other => panic!("{:?}", other.err()),
    }
    for dims in [[0, 9, 24], [16, 0, 24], [16, 9, 0]] {
        let mut s = ClusteringSettings::new([320, 180], 4);
        s.grid.dims = dims;
        match Clusterer::new(s, &ClusteringSource::Code) {
            Err(GraphError::Setting { message, .. }) => {
                assert!(message.contains("at least 1"), "{message}")
            }
            other => panic!("{dims:?}: {:?}", other.err()),
        }
    }
}

#[test]
fn the_single_pass_scan_gives_the_same_lists() {
    let mut rng = Rng(0x5ca7_0000_0000_0001);
    let (view, objects) = random_scene(&mut rng, 1);
    let s = ClusteringSettings {
        scan: Some("decoupled_lookback".into()),
        ..settings([320, 180], "compute")
    };
    let want = cpu_assign(&view, &s, &objects);
    let mut clusterer = Clusterer::new(s, &ClusteringSource::Code).unwrap();
    let got = clusterer.cluster_still(&view, &objects).unwrap();
    compare(&view, &got, &want, &objects, "decoupled_lookback scan");
}

#[test]
fn one_command_buffer_per_frame_gives_the_same_lists() {
    let mut rng = Rng(0x0c0b_0000_0000_0001);
    let (view, objects) = random_scene(&mut rng, 0);
    let s = settings([320, 180], "raster");
    let want = cpu_assign(&view, &s, &objects);
    let mut clusterer = Clusterer::new(s, &ClusteringSource::Code).unwrap();
    clusterer.executor.one_command_buffer = true;
    let got = clusterer.cluster_still(&view, &objects).unwrap();
    compare(&view, &got, &want, &objects, "one command buffer");
}

/// The stages with several implementations come from the registry in the frame built in
/// code too: a name it does not hold is refused, naming the ones it does.
#[test]
fn an_implementation_the_registry_lacks_is_refused_naming_the_registered_ones() {
    for (implementation, scan, stage) in [
        ("quads", "scan_fan", "count_raster"),
        ("compute", "blelloch", "scan_fan"),
    ] {
        let s = ClusteringSettings {
            implementation: Some(implementation.into()),
            scan: Some(scan.into()),
            ..ClusteringSettings::new([320, 180], 16)
        };
        let Err(err) = meshlight_light_clustering::frame_graph::build(&s) else {
            panic!("{implementation}/{scan} built");
        };
        let text = err.to_string();
        assert!(text.contains(stage), "{text}");
        let registered = meshlight::registry().implementations(stage);
        assert!(
            registered.iter().all(|name| text.contains(name.as_str())),
            "{text}"
        );
    }
}
