//! Packing several assets, instance validation, limits, and uploads of only what changed.

use glam::{Mat4, Vec3};
use meshlight_gpu_scene::data::Limits;
use meshlight_gpu_scene::{GpuScene, Material, MeshId, SceneData, SceneDataError};
use meshlight_scene::asset::format::NO_GROUP;
use meshlight_scene::{BuildOptions, MeshletAsset, build_asset, procedural_mesh};

fn asset(segments: u32) -> MeshletAsset {
    build_asset(
        &procedural_mesh(segments),
        &BuildOptions::default(),
        &mut |_| {},
    )
    .unwrap()
    .asset
}

#[test]
fn a_second_asset_is_rebased_onto_the_shared_arrays() {
    let (a, b) = (asset(6), asset(8));
    let mut data = SceneData::new(Limits::default());
    let ma = data.add_mesh("a", &a).unwrap();
    let mb = data.add_mesh("b", &b).unwrap();
    assert_eq!((ma, mb), (MeshId(0), MeshId(1)));
    let (na, ga, pa) = (
        a.meshlets().len(),
        a.groups().len(),
        a.payload().len() as u32,
    );
    assert_eq!(data.meshes[1].first_meshlet as usize, na);
    for (i, m) in b.meshlets().iter().enumerate() {
        let r = data.meshlets[na + i];
        assert_eq!(r.data_offset, m.data_offset + pa);
        for (got, was) in [
            (r.source_group, m.source_group),
            (r.parent_group, m.parent_group),
        ] {
            let want = if was == NO_GROUP {
                NO_GROUP
            } else {
                was + ga as u32
            };
            assert_eq!(got, want);
        }
        // The payload words the rebased offset points at are the asset's own.
        let at = r.data_offset as usize;
        assert_eq!(data.payload[at], b.payload()[m.data_offset as usize]);
    }
}

/// Each mesh's culling hierarchy lands in the shared buffers with its root in
/// `hierarchy_roots`, children and cluster ranges rebased, and its leaves listing that
/// mesh's meshlets (every one once) as indices into the shared meshlet array.
#[test]
fn hierarchies_are_rebased_onto_the_shared_arrays() {
    let (a, b) = (asset(6), asset(8));
    let mut data = SceneData::new(Limits::default());
    for (name, asset) in [("a", &a), ("b", &b)] {
        data.add_mesh(name, asset).unwrap();
    }
    assert_eq!(
        data.hierarchy_roots,
        vec![0, a.nodes().len() as u32],
        "each root at its mesh's first node"
    );
    assert_eq!(
        data.hierarchy_nodes.len(),
        a.nodes().len() + b.nodes().len()
    );
    assert_eq!(data.hierarchy_clusters.len(), data.meshlets.len());
    for (mesh, asset) in [&a, &b].into_iter().enumerate() {
        let first_meshlet = data.meshes[mesh].first_meshlet;
        let range = first_meshlet..first_meshlet + data.meshes[mesh].meshlet_count;
        let mut stack = vec![data.hierarchy_roots[mesh] as usize];
        let mut reached = Vec::new();
        let mut nodes = 0;
        while let Some(i) = stack.pop() {
            nodes += 1;
            let n = &data.hierarchy_nodes[i];
            if n.is_leaf() {
                reached.extend_from_slice(&data.hierarchy_clusters[n.clusters()]);
            } else {
                stack.extend(n.children());
            }
        }
        assert_eq!(nodes, asset.nodes().len(), "mesh {mesh}: nodes reached");
        reached.sort();
        assert_eq!(
            reached,
            range.collect::<Vec<u32>>(),
            "mesh {mesh}: meshlets reached"
        );
    }
}

#[test]
fn singular_and_nan_transforms_are_skipped_and_counted() {
    let mut data = SceneData::new(Limits::default());
    let mesh = data.add_mesh("a", &asset(6)).unwrap();
    let material = data
        .add_material(Material {
            base_color: [1.0; 3],
            ..Material::default()
        })
        .unwrap();
    let ok = data
        .add_instance(mesh, Mat4::from_translation(Vec3::X), material)
        .unwrap();
    assert!(ok.is_some());
    assert_eq!(
        data.add_instance(mesh, Mat4::from_scale(Vec3::new(1.0, 0.0, 1.0)), material),
        Ok(None)
    );
    let mut nan = Mat4::IDENTITY;
    nan.x_axis.x = f32::NAN;
    assert_eq!(data.add_instance(mesh, nan, material), Ok(None));
    assert_eq!(data.instances.len(), 1);
    assert_eq!(data.skipped_instances(), 2);
    assert_eq!(data.set_transform(ok.unwrap(), Mat4::ZERO), Ok(false));
    assert_eq!(data.skipped_instances(), 3);
    assert_eq!(
        data.add_instance(MeshId(7), Mat4::IDENTITY, material),
        Err(SceneDataError::UnknownMesh(7))
    );
}

#[test]
fn more_instances_than_the_buffer_holds_is_an_error_naming_the_limit() {
    let limits = Limits {
        max_instances: 2,
        ..Limits::default()
    };
    let mut data = SceneData::new(limits);
    let mesh = data.add_mesh("a", &asset(6)).unwrap();
    let material = data
        .add_material(Material {
            base_color: [1.0; 3],
            ..Material::default()
        })
        .unwrap();
    for _ in 0..2 {
        data.add_instance(mesh, Mat4::IDENTITY, material).unwrap();
    }
    let err = data
        .add_instance(mesh, Mat4::IDENTITY, material)
        .unwrap_err();
    assert!(
        matches!(err, SceneDataError::Limit { limit: 2, .. }),
        "{err:?}"
    );
    assert!(err.to_string().contains("limit of 2"), "{err}");
}

/// One mesh placed ten times along x (instance i at x = i), with one material.
fn ten_in_a_row(data: &mut SceneData) -> (MeshId, u32, Vec<meshlight_gpu_scene::InstanceId>) {
    let mesh = data.add_mesh("a", &asset(6)).unwrap();
    let material = data
        .add_material(Material {
            base_color: [1.0; 3],
            ..Material::default()
        })
        .unwrap();
    let ids = (0..10)
        .map(|i| {
            data.add_instance(mesh, Mat4::from_translation(Vec3::X * i as f32), material)
                .unwrap()
                .unwrap()
        })
        .collect();
    (mesh, material, ids)
}

#[test]
fn uploads_write_only_what_changed() {
    let gpu = meshlight_testing::gpu();
    let mut data = SceneData::new(Limits::default());
    let (mesh, material, ids) = ten_in_a_row(&mut data);
    let mut scene = GpuScene::new(&gpu, &mut data);
    assert_eq!(scene.upload(&gpu, &mut data).bytes, 0, "nothing changed");
    data.set_transform(ids[3], Mat4::from_translation(Vec3::Y))
        .unwrap();
    data.set_transform(ids[4], Mat4::from_translation(Vec3::Y))
        .unwrap();
    let instance = size_of::<meshlight_shaders::cpu::layout::Instance>() as u64;
    let stats = scene.upload(&gpu, &mut data);
    assert_eq!((stats.bytes, stats.created), (2 * instance, 0));
    // The GPU copy holds the new transform and the previous one.
    let buffer = scene.buffer("instances").unwrap();
    let bytes = gpu.read_buffer(buffer, 3 * instance, instance).unwrap();
    let got: meshlight_shaders::cpu::layout::Instance = bytemuck::pod_read_unaligned(&bytes);
    assert_eq!(
        got.world_from_local,
        Mat4::from_translation(Vec3::Y).to_cols_array_2d()
    );
    assert_eq!(
        got.previous_world_from_local,
        Mat4::from_translation(Vec3::X * 3.0).to_cols_array_2d()
    );
    // A new instance outgrows the buffer: it is recreated.
    data.add_instance(mesh, Mat4::IDENTITY, material).unwrap();
    assert_eq!(scene.upload(&gpu, &mut data).created, 1);
}

/// With a binding of 4 instances, 10 take two buffers: `instances` holds 0..4 and
/// `instances_high` 4..10; a changed transform is written into the buffer that holds it.
#[test]
fn instances_past_one_binding_continue_in_the_second_buffer() {
    let gpu = meshlight_testing::gpu();
    let limits = Limits {
        instances_per_binding: 4,
        max_instances: 11,
        ..Limits::default()
    };
    let mut data = SceneData::new(limits);
    let (mesh, material, ids) = ten_in_a_row(&mut data);
    assert_eq!((data.instance_split(), data.instances_split()), (4, true));
    let mut scene = GpuScene::new(&gpu, &mut data);
    assert!(scene.instances_split());
    let instance = size_of::<meshlight_shaders::cpu::layout::Instance>() as u64;
    // The translation column of instance `at` of buffer `name` as uploaded.
    let translation_is = |scene: &GpuScene, name: &str, at: u64, want: [f32; 4]| {
        let bytes = gpu
            .read_buffer(scene.buffer(name).unwrap(), at * instance, instance)
            .unwrap();
        let got: meshlight_shaders::cpu::layout::Instance = bytemuck::pod_read_unaligned(&bytes);
        assert_eq!(got.world_from_local[3], want, "{name}[{at}]");
    };
    assert_eq!(scene.buffer("instances").unwrap().size(), 4 * instance);
    assert_eq!(scene.buffer("instances_high").unwrap().size(), 6 * instance);
    translation_is(&scene, "instances", 3, [3.0, 0.0, 0.0, 1.0]);
    translation_is(&scene, "instances_high", 0, [4.0, 0.0, 0.0, 1.0]);
    data.set_transform(ids[3], Mat4::from_translation(Vec3::Y))
        .unwrap();
    data.set_transform(ids[6], Mat4::from_translation(Vec3::Z))
        .unwrap();
    // Instances 3..7 are dirty: one in the first buffer, three in the second.
    let stats = scene.upload(&gpu, &mut data);
    assert_eq!((stats.bytes, stats.created), (4 * instance, 0));
    translation_is(&scene, "instances", 3, [0.0, 1.0, 0.0, 1.0]);
    translation_is(&scene, "instances_high", 2, [0.0, 0.0, 1.0, 1.0]);
    // One more instance outgrows the second buffer only.
    data.add_instance(mesh, Mat4::IDENTITY, material).unwrap();
    assert_eq!(scene.upload(&gpu, &mut data).created, 1);
    assert_eq!(scene.buffer("instances").unwrap().size(), 4 * instance);
    assert_eq!(scene.buffer("instances_high").unwrap().size(), 7 * instance);
}

/// An asset `inspect` rejects (sound in structure, not as a DAG) is refused by the GPU
/// scene with inspect's finding; a verified one is accepted without a second check.
#[test]
fn an_asset_inspect_rejects_never_reaches_the_gpu_scene() {
    let built = build_asset(&procedural_mesh(12), &BuildOptions::default(), &mut |_| {}).unwrap();
    let broken = meshlight_scene::damaged::error_below_child(&built).unwrap();
    let mut data = SceneData::new(Limits::default());
    let err = data.add_mesh("broken", &broken).unwrap_err();
    match &err {
        SceneDataError::InvalidAsset { name, reason } => {
            assert_eq!(name, "broken");
            assert!(reason.contains("below child"), "{reason}");
        }
        other => panic!("{other:?}"),
    }
    assert!(data.meshes.is_empty(), "nothing of it was added");
    let verified = built.asset.verified(std::path::Path::new("good")).unwrap();
    assert!(verified.is_verified());
    assert_eq!(data.add_mesh("good", &verified).unwrap(), MeshId(0));
}

/// A MASK material is recorded with its flag, cutoff and alpha factor (clamped to 0..1);
/// a cutoff or texture transform that is not finite is refused, naming the value.
#[test]
fn mask_materials_are_recorded_and_non_finite_values_refused() {
    use meshlight_shaders::cpu::layout::MATERIAL_FLAG_MASK;
    let mut data = SceneData::new(Limits::default());
    let masked = data
        .add_material(Material {
            alpha: 1.5,
            alpha_cutoff: Some(0.3),
            ..Material::default()
        })
        .unwrap();
    let opaque = data.add_material(Material::default()).unwrap();
    let m = data.materials[masked as usize];
    assert!(m.flags & MATERIAL_FLAG_MASK != 0);
    assert_eq!((m.alpha_cutoff, m.base_color[3]), (0.3, 1.0));
    assert_eq!(
        data.materials[opaque as usize].flags & MATERIAL_FLAG_MASK,
        0
    );
    let err = data
        .add_material(Material {
            alpha_cutoff: Some(f32::NAN),
            ..Material::default()
        })
        .unwrap_err();
    assert!(
        matches!(err, SceneDataError::NonFiniteAlphaCutoff { .. }),
        "{err:?}"
    );
    assert!(err.to_string().contains("alpha_cutoff is NaN"), "{err}");
    let mut uv_transform = meshlight_gpu_scene::IDENTITY_UV;
    uv_transform[1][2] = f32::INFINITY;
    let err = data
        .add_material(Material {
            uv_transform,
            ..Material::default()
        })
        .unwrap_err();
    assert!(
        matches!(err, SceneDataError::NonFiniteUvTransform { .. }),
        "{err:?}"
    );
    assert!(err.to_string().contains("inf"), "{err}");
    assert_eq!(data.materials.len(), 2, "a refused material adds nothing");
}
