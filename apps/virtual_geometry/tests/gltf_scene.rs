//! A glTF file drawn as its scene (lavapipe): a mesh placed by several nodes is baked
//! once and drawn at every node's world transform (the same image as the scene placed by
//! hand), a mirroring node draws the mesh's outside, and the scene's cameras are offered.

use glam::{Mat4, Vec3};
use meshlight::gpu_scene::data::Limits;
use meshlight::gpu_scene::{Material, MeshId, SceneData};
use meshlight::scene::BuildOptions;
use meshlight::scene::cache;
use meshlight::scene::load::load_gltf_scene;
use meshlight_testing::gltf_writer::{GltfWriter, Node, Primitive, json, png_bytes};
use meshlight_virtual_geometry::gltf_scene::{GltfSceneError, file_camera, gltf_scene, place};
use meshlight_virtual_geometry::scenes::Placed;
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
    // The same materials, factor for factor.
    for m in &placed.data.materials {
        let [r, g, b, _] = m.base_color;
        let [er, eg, eb, _] = m.emissive;
        expected
            .add_material(Material {
                base_color: [r, g, b],
                metallic: m.metallic,
                roughness: m.roughness,
                emissive: [er, eg, eb],
                checker: m.flags & meshlight::shaders::cpu::layout::MATERIAL_FLAG_CHECKER != 0,
                ..Material::default()
            })
            .unwrap();
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

/// Each primitive is drawn in its glTF material's base colour: a mesh of two materials
/// takes a run of two GPU materials in its primitives' order, meshes of the same
/// materials share a run, and a mesh without a material is white.
#[test]
fn meshes_take_a_run_of_their_primitives_materials() {
    let mut w = GltfWriter::new();
    let red = w.material(json!({"name": "red",
        "pbrMetallicRoughness": {"baseColorFactor": [0.9, 0.1, 0.1, 1.0]}}));
    let blue = w.material(json!({"name": "blue",
        "pbrMetallicRoughness": {"baseColorFactor": [0.1, 0.2, 0.9, 1.0]}}));
    let with = |material: Option<usize>, p: Primitive| Primitive { material, ..p };
    let ball = w.mesh("ball", &[with(Some(red), sphere(8, 16))]);
    let mixed = w.mesh(
        "mixed",
        &[with(Some(blue), cube()), with(Some(red), sphere(8, 16))],
    );
    let plain = w.mesh("plain", &[cube()]);
    let another_ball = w.mesh("another ball", &[with(Some(red), sphere(6, 12))]);
    let nodes = [ball, mixed, plain, another_ball].map(|mesh| {
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
    let data = &placed.data;
    let colour = |i: usize, slot: u32| {
        data.materials[(data.instances[i].material + slot) as usize].base_color
    };
    let slots = |i: usize| data.mesh_material_count(MeshId(data.instances[i].mesh));
    assert_eq!(colour(0, 0), [0.9, 0.1, 0.1, 1.0]);
    assert_eq!(slots(1), Some(2));
    assert_eq!(colour(1, 0), [0.1, 0.2, 0.9, 1.0]);
    assert_eq!(colour(1, 1), [0.9, 0.1, 0.1, 1.0]);
    assert_eq!(colour(2, 0), [1.0, 1.0, 1.0, 1.0]);
    assert_eq!(data.instances[3].material, data.instances[0].material);
    // Runs: [red], [blue, red], [white].
    assert_eq!(data.materials.len(), 4);
    // Each of the mixed mesh's meshlets is the cube's (slot 0, 12 triangles in all)
    // or the sphere's (slot 1).
    let mesh = data.meshes[data.instances[1].mesh as usize];
    let range = mesh.first_meshlet as usize..(mesh.first_meshlet + mesh.meshlet_count) as usize;
    let cube_triangles: u32 = data.meshlets[range]
        .iter()
        .filter(|m| m.level() == 0 && m.material() == 0)
        .map(|m| m.triangle_count())
        .sum();
    assert_eq!(cube_triangles, 12);
}

/// `w`'s scene of one mesh `name` of `primitives` on one node, written as a GLB and
/// placed in a new scene.
fn one_mesh_scene(mut w: GltfWriter, name: &str, primitives: &[Primitive]) -> Placed {
    let mesh = w.mesh(name, primitives);
    let node = w.node(Node {
        mesh: Some(mesh),
        ..Node::default()
    });
    w.scene(&[node]);
    let path = scratch(name).join(format!("{name}.glb"));
    std::fs::write(&path, w.glb()).unwrap();
    gltf_scene(SceneData::new(Limits::default()), &path, None).unwrap()
}

/// A strip of five unit quads, each a primitive of its own material, in one mesh: one
/// asset, and the `material` view shows each quad in the colour of its own material
/// (the instance's first material plus the quad's slot).
#[test]
fn the_material_view_shows_each_primitive_in_its_own_material() {
    let mut w = GltfWriter::new();
    let primitives: Vec<Primitive> = (0..5)
        .map(|k| {
            let x = k as f32;
            let material = w.material(json!({"name": format!("m{k}"),
                "pbrMetallicRoughness": {"baseColorFactor": [0.2 * x, 0.5, 1.0 - 0.2 * x, 1.0]}}));
            Primitive {
                positions: vec![
                    [x, 0.0, 0.0],
                    [x + 1.0, 0.0, 0.0],
                    [x + 1.0, 1.0, 0.0],
                    [x, 1.0, 0.0],
                ],
                normals: Some(vec![[0.0, 0.0, 1.0]; 4]),
                colors: None,
                uvs: None,
                indices: vec![0, 1, 2, 0, 2, 3],
                material: Some(material),
            }
        })
        .collect();
    let placed = one_mesh_scene(w, "strip", &primitives);
    assert_eq!(
        placed.data.meshes.len(),
        1,
        "one asset for the five materials"
    );
    let first = placed.data.instances[0].material;
    let camera = meshlight::gpu_scene::Camera::perspective(
        Vec3::new(2.5, 0.5, 4.0),
        Vec3::new(2.5, 0.5, 0.0),
        1.0,
        0.1,
    );
    let mut settings = FrameSettings::new(W, H);
    settings.view = Some(meshlight::resolve::DebugView::Material);
    let mut r = Renderer::new(placed.data.clone(), settings, &GraphSource::Shipped)
        .unwrap_or_else(|e| panic!("{e}"));
    let image = r
        .render_still(&camera)
        .unwrap_or_else(|e| panic!("{e}"))
        .rgba;
    let view_projection = camera.projection_matrix([W, H]) * camera.view_matrix();
    let mut seen = Vec::new();
    for k in 0..5u32 {
        let clip = view_projection * glam::Vec4::new(k as f32 + 0.5, 0.5, 0.0, 1.0);
        let ndc = clip.truncate() / clip.w;
        let x = ((ndc.x + 1.0) * 0.5 * W as f32) as usize;
        let y = ((1.0 - ndc.y) * 0.5 * H as f32) as usize;
        let at = (y * W as usize + x) * 4;
        let got = [image[at], image[at + 1], image[at + 2]];
        let want = meshlight::resolve::cpu::id_color(first + k);
        assert_eq!(got, want, "quad {k} at pixel ({x}, {y})");
        seen.push(got);
    }
    seen.dedup();
    assert_eq!(seen.len(), 5, "five distinct colours: {seen:?}");
}

/// The colour of the pixel of `image` (W × H, RGBA) that shows the point (x, 0, 0)
/// through `camera`.
fn pixel_on_x_axis(image: &[u8], camera: &meshlight::gpu_scene::Camera, x: f32) -> [u8; 3] {
    let view_projection = camera.projection_matrix([W, H]) * camera.view_matrix();
    let clip = view_projection * glam::Vec4::new(x, 0.0, 0.0, 1.0);
    let ndc = clip.truncate() / clip.w;
    let px = ((ndc.x + 1.0) * 0.5 * W as f32) as usize;
    let py = ((1.0 - ndc.y) * 0.5 * H as f32) as usize;
    let at = (py * W as usize + px) * 4;
    [image[at], image[at + 1], image[at + 2]]
}

/// A quad facing +z at depth `z`, from x0 to x0 + width and y −0.75 to 0.75, with
/// its normals and no attributes else.
fn facing_z_quad(x0: f32, z: f32, width: f32) -> Primitive {
    Primitive {
        positions: vec![
            [x0, -0.75, z],
            [x0 + width, -0.75, z],
            [x0 + width, 0.75, z],
            [x0, 0.75, z],
        ],
        normals: Some(vec![[0.0, 0.0, 1.0]; 4]),
        indices: vec![0, 1, 2, 0, 2, 3],
        ..Primitive::default()
    }
}

/// `placed` drawn in `view` from (0, 0, 4) looking at the origin, as a function from x
/// to the colour of the pixel that shows (x, 0, 0).
fn x_axis_pixels(placed: &Placed, view: meshlight::resolve::DebugView) -> impl Fn(f32) -> [u8; 3] {
    let mut settings = FrameSettings::new(W, H);
    settings.view = Some(view);
    let mut r = Renderer::new(placed.data.clone(), settings, &GraphSource::Shipped)
        .unwrap_or_else(|e| panic!("{e}"));
    let camera =
        meshlight::gpu_scene::Camera::perspective(Vec3::new(0.0, 0.0, 4.0), Vec3::ZERO, 1.0, 0.1);
    let image = r
        .render_still(&camera)
        .unwrap_or_else(|e| panic!("{e}"))
        .rgba;
    move |x| pixel_on_x_axis(&image, &camera, x)
}

/// glTF's `doubleSided`: two quads facing +z, seen from behind. The double-sided one is
/// drawn, its shading normal reversed to face the eye (the `normal` view's blue is
/// z · 0.5 + 0.5: 0 for −z); the one-sided one is culled, so its pixel shows the sky the
/// gap between them shows. From the front both are drawn with the normal +z.
#[test]
fn a_double_sided_material_is_drawn_from_behind_with_its_normal_reversed() {
    let mut w = GltfWriter::new();
    let quad = |w: &mut GltfWriter, x0: f32, double_sided: bool| {
        let material = w.material(json!({"doubleSided": double_sided}));
        Primitive {
            positions: vec![
                [x0, -0.75, 0.0],
                [x0 + 1.5, -0.75, 0.0],
                [x0 + 1.5, 0.75, 0.0],
                [x0, 0.75, 0.0],
            ],
            normals: Some(vec![[0.0, 0.0, 1.0]; 4]),
            colors: None,
            uvs: None,
            indices: vec![0, 1, 2, 0, 2, 3],
            material: Some(material),
        }
    };
    let two_sided = quad(&mut w, -2.0, true);
    let one_sided = quad(&mut w, 0.5, false);
    let placed = one_mesh_scene(w, "quads", &[two_sided, one_sided]);
    let mut settings = FrameSettings::new(W, H);
    settings.view = Some(meshlight::resolve::DebugView::Normal);
    let mut r = Renderer::new(placed.data.clone(), settings, &GraphSource::Shipped)
        .unwrap_or_else(|e| panic!("{e}"));
    for (eye, behind) in [
        (Vec3::new(0.0, 0.0, -4.0), true),
        (Vec3::new(0.0, 0.0, 4.0), false),
    ] {
        let camera = meshlight::gpu_scene::Camera::perspective(eye, Vec3::ZERO, 1.0, 0.1);
        let image = r
            .render_still(&camera)
            .unwrap_or_else(|e| panic!("{e}"))
            .rgba;
        let pixel = |x: f32| pixel_on_x_axis(&image, &camera, x);
        let (two, one, gap) = (pixel(-1.25), pixel(1.25), pixel(0.0));
        if behind {
            assert!(
                two[2] < 8,
                "from behind, the double-sided quad's normal is {two:?}"
            );
            assert_eq!(one, gap, "from behind, the one-sided quad is not drawn");
        } else {
            assert!(
                two[2] > 247 && one[2] > 247,
                "from the front: {two:?}, {one:?}"
            );
            assert_ne!(one, gap);
        }
    }
}

/// glTF's `alphaMode` MASK, drawn through the shipped frame: before an opaque quad, a
/// MASK quad whose base colour texture is opaque on its left and clear on its right
/// (clamped, so alpha falls from 1 to 0 across the middle) is cut where the alpha is
/// below the cutoff, and a MASK quad whose factor's alpha is under the cutoff is cut
/// whole: the `material` view shows the quad behind there. A BLEND quad is drawn opaque.
#[test]
fn a_mask_material_is_cut_out_where_its_alpha_is_below_the_cutoff() {
    let mut w = GltfWriter::new();
    let png = png_bytes(2, 1, &[255, 255, 255, 255, 255, 255, 255, 0]);
    let image = w.image_bytes(&png, "image/png");
    let clamp = json!({"wrapS": 33071, "wrapT": 33071});
    let half_clear = w.texture(image, Some(clamp));
    let quad = |w: &mut GltfWriter, x0: f32, z: f32, width: f32, material| {
        let material = w.material(material);
        Primitive {
            uvs: Some(vec![[0.0, 1.0], [1.0, 1.0], [1.0, 0.0], [0.0, 0.0]]),
            material: Some(material),
            ..facing_z_quad(x0, z, width)
        }
    };
    let textured = quad(
        &mut w,
        -2.0,
        0.0,
        1.5,
        json!({"alphaMode": "MASK", "alphaCutoff": 0.5,
               "pbrMetallicRoughness": {"baseColorTexture": {"index": half_clear}}}),
    );
    let faint = quad(
        &mut w,
        0.25,
        0.0,
        0.75,
        json!({"alphaMode": "MASK", "pbrMetallicRoughness": {"baseColorFactor": [1, 1, 1, 0.3]}}),
    );
    let blend = quad(
        &mut w,
        1.25,
        0.0,
        0.75,
        json!({"alphaMode": "BLEND", "pbrMetallicRoughness": {"baseColorFactor": [1, 1, 1, 0.3]}}),
    );
    let behind = quad(&mut w, -2.5, -0.5, 5.0, json!({}));
    let placed = one_mesh_scene(w, "cut-outs", &[textured, faint, blend, behind]);
    let pixel = x_axis_pixels(&placed, meshlight::resolve::DebugView::Material);
    // Between the quads only the one behind is drawn.
    let back = pixel(0.0);
    let colors = |slot: u32| {
        let first = placed.data.instances[0].material;
        meshlight::resolve::cpu::id_color(first + slot)
    };
    assert_eq!(back, colors(3), "the quad behind");
    // The textured quad: u = 0.2 opaque, u = 0.8 clear.
    assert_eq!(
        pixel(-2.0 + 1.5 * 0.2),
        colors(0),
        "opaque texels are drawn"
    );
    assert_eq!(pixel(-2.0 + 1.5 * 0.8), back, "clear texels are cut out");
    assert_eq!(
        pixel(0.25 + 0.375),
        back,
        "a factor below the cutoff cuts the quad whole"
    );
    assert_eq!(pixel(1.25 + 0.375), colors(2), "BLEND is drawn opaque");
}

/// glTF's `COLOR_0` multiplies the base colour and alpha: in the `base-color` view a red-
/// and a blue-coloured quad of one white material show their vertex colours; a MASK
/// quad whose vertex alpha is 0 is cut out by the rasterisers (what lies behind shows),
/// as is the half of one whose alpha runs from 1 to 0 across it.
#[test]
fn vertex_colours_tint_the_base_colour_and_their_alpha_cuts_mask_materials() {
    use meshlight_testing::gltf_writer::Colors;
    let mut w = GltfWriter::new();
    let white = w.material(json!({"pbrMetallicRoughness": {"baseColorFactor": [1, 1, 1, 1]}}));
    let mask = w.material(json!({"alphaMode": "MASK", "alphaCutoff": 0.5}));
    let grey = w.material(json!({"pbrMetallicRoughness": {"baseColorFactor": [0.2, 0.2, 0.2, 1]}}));
    let quad = |x0: f32, z: f32, width: f32, material, colors: [[u8; 4]; 4]| Primitive {
        colors: Some(Colors::Rgba8(colors.to_vec())),
        material: Some(material),
        ..facing_z_quad(x0, z, width)
    };
    let red = quad(-2.0, 0.0, 0.75, white, [[255, 0, 0, 255]; 4]);
    let blue = quad(-1.0, 0.0, 0.75, white, [[0, 0, 255, 255]; 4]);
    let clear = quad(0.0, 0.0, 0.75, mask, [[255, 255, 255, 0]; 4]);
    let fading = quad(
        1.0,
        0.0,
        1.0,
        mask,
        [
            [255, 255, 255, 255],
            [255, 255, 255, 0],
            [255, 255, 255, 0],
            [255, 255, 255, 255],
        ],
    );
    let behind = quad(-2.5, -0.5, 5.0, grey, [[255; 4]; 4]);
    let placed = one_mesh_scene(w, "coloured", &[red, blue, clear, fading, behind]);
    let pixel = x_axis_pixels(&placed, meshlight::resolve::DebugView::BaseColor);
    let back = pixel(-0.125);
    assert!(
        back[0] == back[1] && back[1] == back[2] && back[0] > 20 && back[0] < 160,
        "the grey quad behind: {back:?}"
    );
    let [r0, g0, b0] = pixel(-2.0 + 0.375);
    assert!(
        r0 > 200 && g0 < 10 && b0 < 10,
        "the red quad: {:?}",
        [r0, g0, b0]
    );
    let [r1, g1, b1] = pixel(-1.0 + 0.375);
    assert!(
        r1 < 10 && g1 < 10 && b1 > 200,
        "the blue quad: {:?}",
        [r1, g1, b1]
    );
    assert_eq!(
        pixel(0.375),
        back,
        "a vertex alpha of 0 cuts a MASK quad out"
    );
    let opaque = pixel(1.0 + 0.2);
    assert!(
        opaque.iter().all(|&c| c > 200),
        "the fading quad's opaque side: {opaque:?}"
    );
    assert_eq!(pixel(1.0 + 0.8), back, "and its clear side is cut out");
}

/// A glTF scene drawn streamed: each mesh's cached file is opened for its resident part
/// and its pages are read from that file; once streaming has settled, the image is the
/// resident one.
#[test]
fn a_streamed_gltf_scene_reads_its_meshes_pages_from_their_cached_files() {
    use meshlight_virtual_geometry::streaming::PageSource;
    let path = write_file(&scratch("balls-streamed"));
    let resident = gltf_scene(SceneData::new(Limits::default()), &path, None).unwrap();
    let mut streamed = gltf_scene(SceneData::streamed(Limits::default()), &path, None).unwrap();
    assert_eq!(streamed.sources.len(), streamed.data.meshes.len());
    for source in &streamed.sources {
        assert!(
            matches!(source, PageSource::File { .. }),
            "a mesh streams from memory"
        );
    }
    streamed.data.reserve_pool(8 << 20).unwrap();
    let want = render(resident.data, &resident.camera);
    let mut r = Renderer::new(
        streamed.data,
        FrameSettings::new(W, H),
        &GraphSource::Shipped,
    )
    .unwrap_or_else(|e| panic!("{e}"));
    r.start_streaming(streamed.sources, meshlight::stream::Budget::default(), 2)
        .unwrap();
    r.settle_streaming(&streamed.camera, 400).unwrap();
    let got = r.render_still(&streamed.camera).unwrap().rgba;
    assert!(
        got == want,
        "the settled streamed image differs from the resident one"
    );
    let stats = r.streaming.as_ref().unwrap().stats();
    assert!(
        stats.loaded_total > 0 && stats.failed_total == 0,
        "{stats:?}"
    );
}
