//! The shadow LOD rule: a cascade's view is orthographic with a texel's world size as
//! its pixel, so the cut an object is drawn with in a cascade depends only on that
//! cascade, never on where the camera stands or on the camera's own cut. A static
//! object's shadow changes level only when the object changes cascade.

use glam::{Mat4, Vec3};
use meshlight_gpu_scene::cascades::{CascadeSettings, cascades};
use meshlight_gpu_scene::{Camera, SceneData, data::Limits};
use meshlight_shaders::cpu::layout::View;
use meshlight_shaders::cpu::lod::lod_cut;

/// Which of the mesh's meshlets are in its LOD cut seen through `view`, at the origin.
fn cut(data: &SceneData, view: &View) -> Vec<bool> {
    let identity = Mat4::IDENTITY.to_cols_array_2d();
    data.meshlets
        .iter()
        .map(|m| {
            let (own, own_error) = data.own_lod(m);
            let (parent, parent_error) = data.parent_lod(m);
            lod_cut(
                view,
                &identity,
                1.0,
                own,
                own_error,
                parent,
                parent_error,
                1.0,
            )
            .0
        })
        .collect()
}

#[test]
fn a_cascades_cut_depends_on_the_cascade_not_on_the_camera() {
    let mut data = SceneData::new(Limits::default());
    data.add_mesh("bunny", meshlight_testing::meshes::bunny())
        .unwrap();
    let settings = CascadeSettings {
        count: 3,
        resolution: 512,
        distance: 40.0,
        ..CascadeSettings::default()
    };
    let light = Vec3::new(-0.4, 0.9, 0.2);
    let mut rng = meshlight_testing::Rng(3);
    let mut shadow_cuts: Vec<Vec<Vec<bool>>> = vec![Vec::new(); 3];
    let mut camera_cuts = Vec::new();
    for _ in 0..12 {
        let eye = Vec3::new(
            rng.range(-6.0, 6.0),
            rng.range(0.5, 4.0),
            rng.range(2.0, 12.0),
        );
        let camera = Camera::perspective(eye, Vec3::ZERO, 1.0, 0.1);
        camera_cuts.push(cut(&data, &camera.view([640, 360], 0, None)));
        let cascades = cascades(&camera, [640, 360], light, &settings, 0).unwrap();
        for (k, c) in cascades.iter().enumerate() {
            assert_eq!(c.view.orthographic, 1);
            shadow_cuts[k].push(cut(&data, &c.view));
        }
    }
    for (k, cuts) in shadow_cuts.iter().enumerate() {
        assert!(
            cuts.windows(2).all(|w| w[0] == w[1]),
            "cascade {k}'s cut changed as the camera moved"
        );
    }
    // The cascades draw different levels (nearer ones finer), and the camera's own
    // cut does follow the camera: the rule is the cascade's, not an accident.
    assert_ne!(
        shadow_cuts[0][0], shadow_cuts[2][0],
        "every cascade drew one cut"
    );
    assert!(
        camera_cuts.windows(2).any(|w| w[0] != w[1]),
        "the camera's cut never changed"
    );
}
