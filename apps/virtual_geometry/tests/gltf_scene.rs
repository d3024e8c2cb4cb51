//! A glTF file drawn as its scene (lavapipe): a mesh placed by several nodes is baked
//! once and drawn at every node's world transform (the same image as the scene placed by
//! hand), a mirroring node draws the mesh's outside, and the scene's cameras are offered.

use glam::{Mat4, Vec3};
use meshlight::gpu_scene::data::Limits;
use meshlight::gpu_scene::{Material, SceneData};
use meshlight::scene::BuildOptions;
use meshlight::scene::cache;
use meshlight::scene::load::load_gltf_scene;
use meshlight_testing::gltf_writer::{GltfWriter, Node, Primitive, json};
use meshlight_virtual_geometry::gltf_scene::{GltfSceneError, file_camera, gltf_scene, place};
use meshlight_virtual_geometry::{FrameSettings, GraphSource, Renderer};
use std::path::{Path, PathBuf};

const W: u32 = 192;
const H: u32 = 128;

/// A UV sphere of radius 1, symmetric under x → −x (an even number of segments), with
/// its normals.
fn sphere(rings: u32, segments: u32) -> Primitive {
    let mut positions = Vec::new();
    for r in 0..=rings {
        let theta = std::f32::consts::PI * r as f32 / rings as f32;
        for s in 0..segments {
            let phi = std::f32::consts::TAU * s as f32 / segments as f32;
            positions.push([
                theta.sin() * phi.cos(),
                theta.cos(),
                theta.sin() * phi.sin(),
            ]);
        }
    }
    let at = |r: u32, s: u32| r * segments + s % segments;
    let mut indices = Vec::new();
    for r in 0..rings {
        for s in 0..segments {
            let (a, b, c, d) = (at(r, s), at(r, s + 1), at(r + 1, s), at(r + 1, s + 1));
            // Counter-clockwise seen from outside.
            indices.extend_from_slice(&[a, b, c, b, d, c]);
        }
    }
    Primitive {
        normals: Some(positions.clone()),
        positions,
        indices,
        ..Primitive::default()
    }
}

/// A cube of side 1 around the origin, faces counter-clockwise from outside.
fn cube() -> Primitive {
    let mut positions = Vec::new();
    let mut normals = Vec::new();
    let mut indices = Vec::new();
    for axis in 0..3 {
        for sign in [-1.0f32, 1.0] {
            let mut n = [0.0; 3];
            n[axis] = sign;
            let (u, v) = ((axis + 1) % 3, (axis + 2) % 3);
            let base = positions.len() as u32;
            for (du, dv) in [(-0.5, -0.5), (0.5, -0.5), (0.5, 0.5), (-0.5, 0.5)] {
                let mut p = [0.0; 3];
                p[axis] = 0.5 * sign;
                p[u] = du;
                p[v] = dv;
                positions.push(p);
                normals.push(n);
            }
            if sign > 0.0 {
                indices.extend_from_slice(&[base, base + 1, base + 2, base, base + 2, base + 3]);
            } else {
                indices.extend_from_slice(&[base, base + 2, base + 1, base, base + 3, base + 2]);
            }
        }
    }
    Primitive {
        positions,
        normals: Some(normals),
        indices,
        ..Primitive::default()
    }
}

/// The ball's placements, as the file's node tree composes them, with the one that
/// mirrors; and the block's.
fn ball_transforms() -> [(Mat4, bool); 4] {
    [
        (Mat4::IDENTITY, false),
        (Mat4::from_translation(Vec3::new(3.0, 0.0, 0.0)), true),
        (Mat4::from_translation(Vec3::new(0.0, 3.0, 0.0)), false),
        (
            Mat4::from_scale_rotation_translation(
                Vec3::splat(0.5),
                glam::Quat::IDENTITY,
                Vec3::new(3.0, 3.0, 0.0),
            ),
            false,
        ),
    ]
}
const BLOCK_AT: Vec3 = Vec3::new(-3.0, 1.5, 0.0);

fn write_file(dir: &Path) -> PathBuf {
    let mut w = GltfWriter::new();
    let ball = w.mesh("ball", &[sphere(16, 32)]);
    let block = w.mesh("block", &[cube()]);
    let camera = w.perspective_camera("front", 0.9, 0.1);
    let a = w.node(Node {
        mesh: Some(ball),
        ..Node::default()
    });
    let mirrored = w.node(Node {
        mesh: Some(ball),
        translation: Some([3.0, 0.0, 0.0]),
        scale: Some([-1.0, 1.0, 1.0]),
        ..Node::default()
    });
    let child = w.node(Node {
        mesh: Some(ball),
        ..Node::default()
    });
    let parent = w.node(Node {
        translation: Some([0.0, 3.0, 0.0]),
        children: vec![child],
        ..Node::default()
    });
    let small = w.node(Node {
        mesh: Some(ball),
        translation: Some([3.0, 3.0, 0.0]),
        scale: Some([0.5; 3]),
        ..Node::default()
    });
    let b = w.node(Node {
        mesh: Some(block),
        translation: Some(BLOCK_AT.to_array()),
        ..Node::default()
    });
    let eye = w.node(Node {
        camera: Some(camera),
        translation: Some([1.0, 1.5, 12.0]),
        ..Node::default()
    });
    w.scene(&[a, mirrored, parent, small, b, eye]);
    let path = dir.join("balls.glb");
    std::fs::write(&path, w.glb()).unwrap();
    path
}

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("meshlight-vg-{}-{name}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn render(data: SceneData, camera: &meshlight::gpu_scene::Camera) -> Vec<u8> {
    let mut r = Renderer::new(data, FrameSettings::new(W, H), &GraphSource::Shipped)
        .unwrap_or_else(|e| panic!("{e}"));
    r.render_still(camera)
        .unwrap_or_else(|e| panic!("{e}"))
        .rgba
}

#[test]
fn a_mesh_placed_by_many_nodes_is_baked_once_and_drawn_at_each_nodes_transform() {
    let path = write_file(&scratch("balls"));
    let placed = gltf_scene(SceneData::new(Limits::default()), &path, None).unwrap();
    let names: Vec<_> = (0..placed.data.meshes.len())
        .map(|m| {
            placed
                .data
                .mesh_name(meshlight::gpu_scene::MeshId(m as u32))
                .unwrap()
                .to_string()
        })
        .collect();
    // The ball once, its mirrored winding once, the block once: five instances.
    assert_eq!(names, ["ball", "ball (mirrored)", "block"]);
    assert_eq!(placed.data.instances.len(), 5);

    // The same scene placed by hand: the ball's asset (the sphere is symmetric, so the
    // mirrored node draws what an unmirrored one there draws) and the block's, at the
    // transforms the node tree composes, in the same colours.
    let scene = load_gltf_scene(&path).unwrap();
    let bake = |m: usize| {
        cache::load_or_bake_mesh(
            &scene.meshes[m].mesh,
            &BuildOptions::default(),
            &cache::cache_dir(),
            &mut |_| {},
        )
        .unwrap()
        .0
    };
    let mut expected = SceneData::new(Limits::default());
    for m in &placed.data.materials {
        let [r, g, b, _] = m.base_color;
        expected.add_material(Material {
            base_color: [r, g, b],
        });
    }
    let ball = expected.add_mesh("ball", &bake(0)).unwrap();
    let block = expected.add_mesh("block", &bake(1)).unwrap();
    let colour = |i: usize| placed.data.instances[i].material;
    let mut placed_at = Vec::new();
    for (k, (transform, mirrored)) in ball_transforms().into_iter().enumerate() {
        let i = placed
            .data
            .instances
            .iter()
            .position(|inst| {
                Mat4::from_cols_array_2d(&inst.world_from_local).abs_diff_eq(
                    if mirrored {
                        transform * Mat4::from_scale(Vec3::new(-1.0, 1.0, 1.0))
                    } else {
                        transform
                    },
                    1e-6,
                )
            })
            .unwrap_or_else(|| panic!("no instance at the ball's placement {k}"));
        placed_at.push(i);
        expected
            .add_instance(ball, transform, colour(i))
            .unwrap()
            .unwrap();
    }
    expected
        .add_instance(block, Mat4::from_translation(BLOCK_AT), colour(4))
        .unwrap()
        .unwrap();
    placed_at.sort();
    assert_eq!(
        placed_at,
        [0, 1, 2, 3],
        "the balls come first, in node order"
    );

    let got = render(placed.data.clone(), &placed.camera);
    let want = render(expected, &placed.camera);
    let differ = got
        .chunks(4)
        .zip(want.chunks(4))
        .filter(|(a, b)| a.iter().zip(*b).any(|(x, y)| x.abs_diff(*y) > 8))
        .count();
    eprintln!("{differ} of {} pixels differ", W * H);
    // The mirrored ball's own bake may pick another LOD cut at its edges (9 pixels on
    // lavapipe); a ball drawn inside out (back faces) differs over most of its disc
    // (404 pixels).
    assert!(
        differ * 400 < W as usize * H as usize,
        "{differ} of {} pixels differ from the scene placed by hand",
        W * H
    );
}

#[test]
fn the_files_cameras_are_offered_and_a_missing_one_is_an_error() {
    let path = write_file(&scratch("camera"));
    let placed = gltf_scene(SceneData::new(Limits::default()), &path, Some(0)).unwrap();
    assert_eq!(placed.camera.position, Vec3::new(1.0, 1.5, 12.0));
    assert_eq!(placed.camera.target, Vec3::new(1.0, 1.5, 11.0));
    let scene = load_gltf_scene(&path).unwrap();
    assert_eq!(placed.camera, file_camera(&scene.cameras[0]));
    match place(SceneData::new(Limits::default()), &scene, Some(1)) {
        Err(
            e @ GltfSceneError::NoSuchCamera {
                index: 1, count: 1, ..
            },
        ) => {
            assert!(e.to_string().contains("(0 to 0)"), "{e}");
        }
        other => panic!("expected NoSuchCamera, got {:?}", other.err()),
    }
    // The framing camera sees every instance whole: each one's bounding sphere projects
    // inside the image.
    let framed = gltf_scene(SceneData::new(Limits::default()), &path, None).unwrap();
    let clip = framed.camera.projection_matrix([W, H]) * framed.camera.view_matrix();
    for inst in &framed.data.instances {
        let m = Mat4::from_cols_array_2d(&inst.world_from_local);
        let s = framed.data.meshes[inst.mesh as usize].bounding_sphere;
        let centre = m.transform_point3(Vec3::new(s[0], s[1], s[2]));
        let r = s[3] * m.x_axis.truncate().length();
        for d in [
            Vec3::X,
            Vec3::NEG_X,
            Vec3::Y,
            Vec3::NEG_Y,
            Vec3::Z,
            Vec3::NEG_Z,
        ] {
            let p = clip.project_point3(centre + d * r);
            assert!(
                p.x.abs() <= 1.0 && p.y.abs() <= 1.0,
                "{centre} + {d} r projects to {p}, outside the image"
            );
        }
    }
}

/// Each mesh is drawn in its glTF material's base colour; one of several materials takes
/// the one covering most triangles; a mesh without a material is white.
#[test]
fn meshes_take_their_materials_base_colour() {
    let mut w = GltfWriter::new();
    let red = w.material(json!({"name": "red",
        "pbrMetallicRoughness": {"baseColorFactor": [0.9, 0.1, 0.1, 1.0]}}));
    let blue = w.material(json!({"name": "blue",
        "pbrMetallicRoughness": {"baseColorFactor": [0.1, 0.2, 0.9, 1.0]}}));
    let with = |material: Option<usize>, p: Primitive| Primitive { material, ..p };
    let ball = w.mesh("ball", &[with(Some(red), sphere(8, 16))]);
    // The cube's 12 triangles are blue, the small sphere's 256 red: red covers most.
    let mixed = w.mesh(
        "mixed",
        &[with(Some(blue), cube()), with(Some(red), sphere(8, 16))],
    );
    let plain = w.mesh("plain", &[cube()]);
    let nodes = [ball, mixed, plain].map(|mesh| {
        w.node(Node {
            mesh: Some(mesh),
            translation: Some([mesh as f32 * 3.0, 0.0, 0.0]),
            ..Node::default()
        })
    });
    w.scene(&nodes);
    let path = scratch("materials").join("materials.glb");
    std::fs::write(&path, w.glb()).unwrap();
    let placed = gltf_scene(SceneData::new(Limits::default()), &path, None).unwrap();
    let colour =
        |i: usize| placed.data.materials[placed.data.instances[i].material as usize].base_color;
    assert_eq!(colour(0), [0.9, 0.1, 0.1, 1.0]);
    assert_eq!(colour(1), [0.9, 0.1, 0.1, 1.0]);
    assert_eq!(colour(2), [1.0, 1.0, 1.0, 1.0]);
    // One GPU material per glTF material used, and the default.
    assert_eq!(placed.data.materials.len(), 2);
}
