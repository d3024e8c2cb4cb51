//! `resolve` on the GPU (lavapipe in CI) against `cpu`: a scene of a mesh with UVs
//! (spot) and one without (the procedural knot), rasterised into a visibility buffer by
//! the software rasteriser's CPU reference, resolved into depth, material depth and
//! every debug view; the same frame with no depth targets bound (colour alone, no render
//! program); a depth pyramid shown mip by mip; the same frame lit by clustered point and
//! spot lights and shown as the light-count view; then the errors.

use glam::{Mat4, Quat, Vec3};
use meshlight_gpu_scene::data::Limits;
use meshlight_gpu_scene::gpu::elements;
use meshlight_gpu_scene::{Camera, GpuScene, Material, SceneData, TextureId};
use meshlight_graph::*;
use meshlight_pass_populate::cpu::{ClusterLists, cpu_populate};
use meshlight_pass_resolve::settings::Settings;
use meshlight_pass_resolve::{
    COLOR_FORMAT, DEPTH_FORMAT, DebugView, OCCLUDED_PER_INSTANCE, PYRAMID_FORMAT, Resolve,
    SECOND_COUNTS, STREAM_ERRORS, cpu,
};
use meshlight_pass_z_slice::{ZSlice, cpu_z_slice};
use meshlight_scene::load::load_obj;
use meshlight_scene::procedural_mesh;
use meshlight_scene::texture::{Image, decode_image};
use meshlight_shaders::cpu::layout::{
    Cluster, ClusterGrid, ClusterableKind, ClusterableObject, TextureWrap, View,
};
use meshlight_shaders::cpu::occlusion::DepthPyramid;
use meshlight_shaders::cpu::visbuffer;
use std::collections::BTreeSet;
use std::path::Path;

const W: u32 = 64;
const H: u32 = 48;

const BUFFER_USAGE: wgpu::BufferUsages = wgpu::BufferUsages::STORAGE
    .union(wgpu::BufferUsages::COPY_DST)
    .union(wgpu::BufferUsages::COPY_SRC);
const DEPTH_USAGE: wgpu::TextureUsages =
    wgpu::TextureUsages::RENDER_ATTACHMENT.union(wgpu::TextureUsages::COPY_SRC);
const COLOR_USAGE: wgpu::TextureUsages =
    wgpu::TextureUsages::STORAGE_BINDING.union(wgpu::TextureUsages::COPY_SRC);

use meshlight_pass_resolve::shadows::{SHADOW_MAPS, SHADOWS_INPUT, ShadowFrame, ShadowParams};
use meshlight_testing::frames::{Imported, filled, import_filled, run_per_view_with};
use meshlight_testing::{gpu, parameter_message, params, read_texture, texture};

#[path = "../../sw_raster/tests/support/scenes.rs"]
mod scenes;
use scenes::add_mesh;

/// `mesh`'s bounding sphere moved to `at` with radius `radius`, turned and stretched.
fn place(scene: &SceneData, mesh: u32, at: Vec3, radius: f32, turn: Quat, stretch: Vec3) -> Mat4 {
    let [x, y, z, r] = scene.meshes[mesh as usize].bounding_sphere;
    Mat4::from_scale_rotation_translation(stretch * (radius / r), turn, at)
        * Mat4::from_translation(-Vec3::new(x, y, z))
}

/// What the pass reads: the scene, the camera, the slot buffer and the visibility
/// buffer the software rasteriser's reference draws from it.
struct Frame {
    scene: SceneData,
    view: View,
    raster_clusters: Vec<Cluster>,
    /// `raster_counts[0]`.
    software: u32,
    visbuffer: Vec<u64>,
    lights: Option<Lights>,
    /// A depth pyramid for the `pyramid` slot, finest mip first.
    pyramid: Option<Vec<cpu::PyramidMip>>,
    /// The `second_counts` and `occluded_per_instance` slots, for the `occlusion` view.
    second_counts: Option<Vec<u32>>,
    occluded_per_instance: Option<Vec<u32>>,
    /// The `stream_errors` slot, for the `residency` view.
    stream_errors: Option<Vec<f32>>,
    /// The sun's cascades: the frame input and the `shadow_maps` slot's words.
    shadows: Option<(ShadowParams, Vec<u32>)>,
}

/// Light clustering's output for the frame, from the CPU references of its stages.
struct Lights {
    objects: Vec<ClusterableObject>,
    grid: ClusterGrid,
    lists: ClusterLists,
}

impl Frame {
    fn cpu(&self) -> cpu::Frame<'_> {
        cpu::Frame {
            scene: &self.scene,
            view: &self.view,
            raster_clusters: &self.raster_clusters,
            software_clusters: self.software,
            visbuffer: &self.visbuffer,
            width: W,
            height: H,
            lights: self.lights.as_ref().map(|l| cpu::ClusteredLights {
                objects: &l.objects,
                grid: &l.grid,
                offsets: &l.lists.offsets,
                counts: &l.lists.counts,
                list: &l.lists.objects,
            }),
            pyramid: self.pyramid.as_deref(),
            second_counts: self.second_counts.as_deref(),
            occluded_per_instance: self.occluded_per_instance.as_deref(),
            stream_errors: self.stream_errors.as_deref(),
            shadows: self
                .shadows
                .as_ref()
                .map(|(params, maps)| ShadowFrame { params, maps }),
        }
    }

    /// Thirty coloured point lights and ten spot lights around the meshes, clustered on
    /// an 8 × 6 × 16 grid.
    fn light(&mut self) {
        let mut objects = Vec::new();
        for i in 0..40 {
            let a = i as f32 * 2.4;
            let p = Vec3::new(
                a.cos() * (0.5 + 0.04 * i as f32),
                0.9 - 0.05 * i as f32,
                a.sin() * 0.9 - 0.6,
            );
            let color = [
                0.5 + 0.5 * a.cos(),
                0.5 + 0.5 * (a + 2.1).cos(),
                0.5 + 0.5 * (a + 4.2).cos(),
                0.6,
            ];
            let spot = i % 4 == 3;
            let d = (Vec3::new(0.0, 0.0, -0.5) - p).normalize();
            let half_angle: f32 = 0.5;
            objects.push(ClusterableObject {
                position_range: [p.x, p.y, p.z, 0.6 + 0.05 * (i % 7) as f32],
                direction_cos_angle: [d.x, d.y, d.z, half_angle.cos()],
                color_intensity: color,
                kind: if spot {
                    ClusterableKind::SpotLight
                } else {
                    ClusterableKind::PointLight
                } as u32,
                sin_angle: half_angle.sin(),
                ..ClusterableObject::default()
            });
        }
        let z_slice = ZSlice {
            grid: meshlight_pass_z_slice::GridSettings {
                dims: [8, 6, 16],
                first_slice_end: 1.0,
                far: 100.0,
            },
            ..ZSlice::default()
        };
        let grid = z_slice.grid([W, H]);
        let slices = cpu_z_slice(&self.view, &grid, &objects, u32::MAX, 4, 65535);
        let (lists, _) = cpu_populate(&self.view, &grid, &objects, &slices.pairs, u32::MAX);
        assert!(
            lists.needed > 100,
            "the lights touch {} froxels",
            lists.needed
        );
        self.lights = Some(Lights {
            objects,
            grid,
            lists,
        });
    }
}

/// The test scene's textures: Spot's own (1024², sRGB, repeating), a normal map of
/// bumps, and small data and colour textures that clamp or mirror, so the filter, the
/// mip choice, the wrap modes and each map's use are compared with the reference.
struct Textures {
    spot: TextureId,
    bumps: TextureId,
    metal_rough: TextureId,
    occlusion: TextureId,
    glow: TextureId,
}

impl Textures {
    fn add(scene: &mut SceneData) -> Self {
        let path =
            Path::new(env!("CARGO_MANIFEST_DIR")).join("../../assets/meshes/spot_texture.png");
        let bytes = std::fs::read(&path).unwrap();
        let spot = decode_image(&bytes, "spot_texture.png").unwrap();
        let generated = |side: u32, f: &dyn Fn(u32, u32) -> [u8; 4]| {
            let mut image = Image::filled(side, side, [0; 4]);
            for y in 0..side {
                for x in 0..side {
                    let at = ((y * side + x) * 4) as usize;
                    image.rgba[at..at + 4].copy_from_slice(&f(x, y));
                }
            }
            image
        };
        let bumps = generated(64, &|x, y| {
            let a = x as f32 / 64.0 * std::f32::consts::TAU * 4.0;
            let b = y as f32 / 64.0 * std::f32::consts::TAU * 3.0;
            let n = Vec3::new(0.5 * a.sin(), 0.5 * b.cos(), 1.0).normalize();
            let e = |c: f32| ((c * 0.5 + 0.5) * 255.0).round() as u8;
            [e(n.x), e(n.y), e(n.z), 255]
        });
        let metal_rough = generated(32, &|x, y| [0, (x * 8) as u8, 255 - (y * 8) as u8, 255]);
        let occlusion = generated(16, &|x, y| [((x ^ y) * 16) as u8, 0, 0, 255]);
        let glow = generated(8, &|x, y| [(x * 32) as u8, (y * 32) as u8, 200, 255]);
        let repeat = [TextureWrap::Repeat; 2];
        let mut add = |image: &Image, srgb, wrap| scene.add_image(image, srgb, wrap).unwrap();
        Self {
            spot: add(&spot, true, repeat),
            bumps: add(&bumps, false, repeat),
            metal_rough: add(
                &metal_rough,
                false,
                [TextureWrap::Clamp, TextureWrap::Mirror],
            ),
            occlusion: add(
                &occlusion,
                false,
                [TextureWrap::Mirror, TextureWrap::Repeat],
            ),
            glow: add(&glow, true, [TextureWrap::Clamp; 2]),
        }
    }
}

/// Spot (with UVs) twice, once stretched so normals need the inverse transpose, and the
/// knot (no UVs) behind, in three material slots along its tube (its instance takes the
/// last three of five materials); each instance draws one LOD level, so the `lod` view
/// has several. The first half of the slots count as software clusters.
fn frame() -> Frame {
    let spot_path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../assets/meshes/spot.obj");
    let mut spot = load_obj(&spot_path).unwrap();
    assert!(!spot.uvs.is_empty(), "spot.obj should have UVs");
    // Vertex colours over UVs (a pale tint) and without (the knot's bands), so the
    // payload's colour words are read after a UV block and right after the triangles.
    spot.colors = spot
        .positions
        .iter()
        .map(|p| [0.8 + 0.2 * (4.0 * p.y).sin(), 1.0, 0.85, 1.0])
        .collect();
    let mut scene = SceneData::new(Limits::default());
    let spot = add_mesh(&mut scene, "spot", &spot);
    let mut knot = procedural_mesh(12);
    knot.colors = knot
        .positions
        .iter()
        .map(|p| {
            let a = 3.0 * p.x + 2.0 * p.z;
            [0.5 + 0.5 * a.cos(), 0.5 + 0.5 * (a + 2.0).cos(), 0.6, 1.0]
        })
        .collect();
    let n = knot.triangle_count();
    knot.materials = (0..n).map(|t| (t * 3 / n) as u32).collect();
    let knot = add_mesh(&mut scene, "knot", &knot);
    assert_eq!(scene.mesh_material_count(knot), Some(3));
    // A checkered dielectric, a smooth metal, and the knot's slots: checkered, a
    // plain rough plastic, and a glowing one.
    let plain = |base_color| Material {
        base_color,
        checker: false,
        ..Material::default()
    };
    let textures = Textures::add(&mut scene);
    let materials = [
        Material {
            base_color: [0.9, 0.6, 0.4],
            maps: [Some(textures.spot), None, Some(textures.bumps), None, None],
            normal_scale: 0.8,
            ..Material::default()
        },
        Material {
            metallic: 1.0,
            roughness: 0.45,
            maps: [
                None,
                Some(textures.metal_rough),
                None,
                Some(textures.occlusion),
                Some(textures.glow),
            ],
            emissive: [0.5, 0.4, 0.3],
            occlusion_strength: 0.7,
            // Its maps tiled, turned and moved (KHR_texture_transform).
            uv_transform: meshlight_scene::load::texture_transform([0.25, -0.1], 0.7, [2.0, 1.5]),
            ..plain([0.95, 0.8, 0.4])
        },
        Material {
            base_color: [0.7, 0.7, 0.9],
            ..Material::default()
        },
        Material {
            roughness: 0.9,
            ..plain([0.3, 0.3, 0.8])
        },
        Material {
            emissive: [0.6, 0.3, 0.0],
            ..plain([0.9, 0.9, 0.2])
        },
    ]
    .map(|m| scene.add_material(m).unwrap());
    let instances = [
        (
            spot,
            place(
                &scene,
                spot.0,
                Vec3::new(-0.7, 0.0, 0.0),
                1.0,
                Quat::from_rotation_y(2.0),
                Vec3::ONE,
            ),
            materials[0],
            0,
        ),
        (
            spot,
            place(
                &scene,
                spot.0,
                Vec3::new(0.8, 0.0, 0.2),
                0.8,
                Quat::from_rotation_y(-1.3),
                Vec3::new(1.0, 1.6, 0.7),
            ),
            materials[1],
            1,
        ),
        (
            knot,
            place(
                &scene,
                knot.0,
                Vec3::new(0.0, 0.4, -2.0),
                1.4,
                Quat::from_rotation_x(0.4),
                Vec3::ONE,
            ),
            materials[2],
            0,
        ),
    ];
    let mut raster_clusters = Vec::new();
    for (mesh, transform, material, level) in instances {
        let id = scene
            .add_instance(mesh, transform, material)
            .unwrap()
            .unwrap();
        let instance = scene.instances[id.0 as usize];
        let first = instance.first_meshlet;
        for m in first..first + instance.meshlet_count {
            if scene.meshlets[m as usize].level() == level {
                raster_clusters.push(Cluster {
                    instance: id.0,
                    meshlet: m,
                });
            }
        }
    }
    let camera = Camera::perspective(
        Vec3::new(0.1, 0.6, 2.7),
        Vec3::new(0.0, 0.1, -0.5),
        0.9,
        0.1,
    );
    let view = camera.view([W, H], 0, None);
    let visbuffer = meshlight_pass_sw_raster::cpu::rasterize(&scene, &view, &raster_clusters, W, H);
    let software = raster_clusters.len() as u32 / 2;
    Frame {
        scene,
        view,
        raster_clusters,
        software,
        visbuffer,
        lights: None,
        pyramid: None,
        second_counts: None,
        occluded_per_instance: None,
        stream_errors: None,
        shadows: None,
    }
}

/// What the pass wrote; a depth target only where it was bound.
struct Resolved {
    depth: Option<Vec<f32>>,
    material_depth: Option<Vec<f32>>,
    color: Vec<[u8; 4]>,
    /// The compiled frame, to see what the pass declared.
    plan: Plan,
}

/// Which optional targets the graph binds.
#[derive(Clone, Copy)]
struct Targets {
    depth: bool,
    material_depth: bool,
}

const BOTH: Targets = Targets {
    depth: true,
    material_depth: true,
};
const NONE: Targets = Targets {
    depth: false,
    material_depth: false,
};

/// Runs `pass` over `frame` with `view` as the frame's camera and both depth targets
/// bound, and reads the targets back.
fn run_with_view(frame: &mut Frame, pass: Resolve, view: &View) -> Result<Resolved> {
    run_with(frame, pass, view, BOTH)
}

/// Runs `pass` with the depth targets `targets` names bound (and the frame's pyramid,
/// if it has one), and reads back what was bound.
fn run_with(
    frame: &mut Frame,
    mut pass: Resolve,
    view: &View,
    targets: Targets,
) -> Result<Resolved> {
    // As the renderer sets it: on when a mesh has vertex colours, which the reference
    // then multiplies by.
    pass.vertex_colors = frame
        .scene
        .meshes
        .iter()
        .any(|m| m.flags & meshlight_shaders::cpu::layout::MESH_FLAG_COLORS != 0);
    let gpu = gpu();
    let scene = GpuScene::new(&gpu, &mut frame.scene);
    let slots = frame.raster_clusters.len() as u64;
    let mut g = GraphBuilder::new();
    scene.import(&mut g);
    // Words past the first are other counters of the slot buffer; the pass reads word 0.
    let count_words = [frame.software, 7, 0, slots as u32];
    // Every resource below is imported under its slot's name, which binds it.
    let Imported { imports, .. } = import_filled(
        &mut g,
        &gpu,
        [
            filled("raster_clusters", elements::CLUSTER, &frame.raster_clusters),
            filled("raster_counts", Element::U32, &count_words),
            filled("visbuffer", Element::U64, &frame.visbuffer),
        ],
        scene.imports(),
    );
    for (name, wanted) in [
        ("depth", targets.depth),
        ("material_depth", targets.material_depth),
    ] {
        if wanted {
            g.import_texture(name, TextureDesc::d2(DEPTH_FORMAT, W, H), DEPTH_USAGE);
        }
    }
    let pyramid = frame.pyramid.as_ref();
    if let Some(mips) = pyramid {
        let desc = TextureDesc::d2(PYRAMID_FORMAT, mips[0].width, mips[0].height)
            .with_mips(mips.len() as u32);
        g.import_texture("pyramid", desc, PYRAMID_USAGE);
    }
    g.import_texture("color", TextureDesc::d2(COLOR_FORMAT, W, H), COLOR_USAGE);
    let mut light_buffers: Vec<(&str, Vec<u8>)> = match &frame.lights {
        Some(l) => vec![
            ("objects", bytemuck::cast_slice(&l.objects).to_vec()),
            ("cluster_grid", bytemuck::bytes_of(&l.grid).to_vec()),
            (
                "cluster_offsets",
                bytemuck::cast_slice(&l.lists.offsets).to_vec(),
            ),
            (
                "cluster_counts",
                bytemuck::cast_slice(&l.lists.counts).to_vec(),
            ),
            // A zero-length binding is not allowed.
            (
                "cluster_objects",
                bytemuck::cast_slice(&[l.lists.objects.as_slice(), &[0]].concat()).to_vec(),
            ),
        ],
        None => Vec::new(),
    };
    // The occlusion view's records travel the same way: plain u32 buffers.
    for (name, words) in [
        (SECOND_COUNTS, &frame.second_counts),
        (OCCLUDED_PER_INSTANCE, &frame.occluded_per_instance),
    ] {
        if let Some(words) = words {
            light_buffers.push((name, bytemuck::cast_slice(words).to_vec()));
        }
    }
    if let Some(errors) = &frame.stream_errors {
        light_buffers.push((STREAM_ERRORS, bytemuck::cast_slice(errors).to_vec()));
    }
    if let Some((_, maps)) = &frame.shadows {
        light_buffers.push((SHADOW_MAPS, bytemuck::cast_slice(maps).to_vec()));
    }
    for (name, bytes) in &light_buffers {
        let element = match *name {
            "objects" => Element::named("ClusterableObject", 64),
            "cluster_grid" => Element::named("ClusterGrid", 48),
            STREAM_ERRORS => Element::F32,
            _ => Element::U32,
        };
        let count = bytes.len() as u64 / u64::from(element.size);
        g.import_buffer(name, BufferDesc::array(element, count), BUFFER_USAGE);
    }
    g.add_pass("resolve", pass, Bindings::new())?;
    let compiled = g.compile(&CompileOptions::for_gpu(&gpu))?;
    let textures = [
        texture(
            &gpu,
            "depth",
            &TextureDesc::d2(DEPTH_FORMAT, W, H),
            DEPTH_USAGE,
        ),
        texture(
            &gpu,
            "material_depth",
            &TextureDesc::d2(DEPTH_FORMAT, W, H),
            DEPTH_USAGE,
        ),
        texture(
            &gpu,
            "color",
            &TextureDesc::d2(COLOR_FORMAT, W, H),
            COLOR_USAGE,
        ),
    ];
    let light_data: Vec<(&str, wgpu::Buffer)> = light_buffers
        .iter()
        .map(|(name, bytes)| (*name, gpu.buffer_with_data(name, bytes, BUFFER_USAGE)))
        .collect();
    let pyramid_texture = pyramid.map(|mips| upload_pyramid(&gpu, mips));
    let mut imports = imports.texture("color", &textures[2]);
    if targets.depth {
        imports = imports.texture("depth", &textures[0]);
    }
    if targets.material_depth {
        imports = imports.texture("material_depth", &textures[1]);
    }
    if let Some(t) = &pyramid_texture {
        imports = imports.texture("pyramid", t);
    }
    for (name, buffer) in &light_data {
        imports = imports.buffer(name, buffer);
    }
    let mut exec = Executor::new(gpu);
    let shadow_input: Vec<(&str, &[u8])> = match &frame.shadows {
        Some((params, _)) => vec![(SHADOWS_INPUT, bytemuck::bytes_of(params))],
        None => Vec::new(),
    };
    let mut frames = run_per_view_with(
        &mut exec,
        &compiled,
        &imports,
        &[*view],
        &shadow_input,
        |exec| {
            let depth_of = |wanted: bool, texture: &wgpu::Texture| {
                wanted.then(|| {
                    let bytes = read_texture(&exec.gpu, texture, wgpu::TextureAspect::DepthOnly);
                    bytemuck::pod_collect_to_vec::<u8, f32>(&bytes)
                })
            };
            Ok(Resolved {
                depth: depth_of(targets.depth, &textures[0]),
                material_depth: depth_of(targets.material_depth, &textures[1]),
                color: bytemuck::pod_collect_to_vec(&read_texture(
                    &exec.gpu,
                    &textures[2],
                    wgpu::TextureAspect::All,
                )),
                plan: compiled.plan.clone(),
            })
        },
    )?;
    Ok(frames.remove(0))
}

const PYRAMID_USAGE: wgpu::TextureUsages =
    wgpu::TextureUsages::TEXTURE_BINDING.union(wgpu::TextureUsages::COPY_DST);

/// An R32Float texture holding `mips`.
fn upload_pyramid(gpu: &GpuContext, mips: &[cpu::PyramidMip]) -> wgpu::Texture {
    let desc = TextureDesc {
        mip_levels: mips.len() as u32,
        ..TextureDesc::d2(PYRAMID_FORMAT, mips[0].width, mips[0].height)
    };
    let texture = texture(gpu, "pyramid", &desc, PYRAMID_USAGE);
    for (level, mip) in mips.iter().enumerate() {
        gpu.queue.write_texture(
            wgpu::TexelCopyTextureInfo {
                texture: &texture,
                mip_level: level as u32,
                origin: wgpu::Origin3d::ZERO,
                aspect: wgpu::TextureAspect::All,
            },
            bytemuck::cast_slice(&mip.texels),
            wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(mip.width * 4),
                rows_per_image: Some(mip.height),
            },
            wgpu::Extent3d {
                width: mip.width,
                height: mip.height,
                depth_or_array_layers: 1,
            },
        );
    }
    texture
}

/// The first `levels` levels of the CPU pyramid of the `W × H` image `depth`, as the mips
/// of a texture hold them (at `W × H` the rule's rounded-up level sizes are the mip
/// chain's rounded-down ones).
fn min_pyramid(depth: &[f32], levels: usize) -> Vec<cpu::PyramidMip> {
    DepthPyramid::from_depth(W, H, depth)
        .levels
        .into_iter()
        .take(levels)
        .map(|(width, height, texels)| cpu::PyramidMip {
            width,
            height,
            texels,
        })
        .collect()
}

fn run(frame: &mut Frame, pass: Resolve) -> Resolved {
    let view = frame.view;
    run_with_view(frame, pass, &view).unwrap_or_else(|e| panic!("{e}"))
}

/// The first pixel where two float targets differ in their bits.
fn first_difference(got: &[f32], want: &[f32]) -> Option<(usize, f32, f32)> {
    got.iter()
        .zip(want)
        .enumerate()
        .find(|(_, (g, w))| g.to_bits() != w.to_bits())
        .map(|(i, (g, w))| (i, *g, *w))
}

/// How `got` differs from `f` shaded by the reference with `settings`: see
/// [`color_differences`].
fn reference_differences(
    got: &[[u8; 4]],
    f: &Frame,
    settings: &Settings,
    tolerance: u8,
) -> (usize, u8) {
    color_differences(got, &cpu::shade(&f.cpu(), settings), tolerance)
}

/// Pixels whose largest channel difference exceeds `tolerance`, and the largest one.
fn color_differences(got: &[[u8; 4]], want: &[[u8; 4]], tolerance: u8) -> (usize, u8) {
    assert_eq!(got.len(), want.len());
    let mut over = 0;
    let mut largest = 0;
    for (g, w) in got.iter().zip(want) {
        let d = (0..4).map(|k| g[k].abs_diff(w[k])).max().unwrap();
        largest = largest.max(d);
        if d > tolerance {
            over += 1;
        }
    }
    (over, largest)
}

#[test]
fn depth_material_depth_and_every_view_match_the_reference() {
    let mut f = frame();
    let covered = f
        .visbuffer
        .iter()
        .filter(|&&v| v != visbuffer::EMPTY)
        .count();
    let pixels = (W * H) as usize;
    assert!(
        covered > pixels / 4 && covered < pixels * 19 / 20,
        "the scene should cover part of the screen, covers {covered} of {pixels}"
    );

    let depth = cpu::depth(&f.visbuffer, W, H);
    let material_depth = cpu::material_depth(&f.scene, &f.raster_clusters, &f.visbuffer);
    let materials: BTreeSet<u32> = material_depth.iter().map(|d| d.to_bits()).collect();
    assert!(
        materials.len() >= 6,
        "empty, spot's two materials and the knot's three: {materials:?}"
    );

    // Views that need slots this frame does not bind have tests of their own.
    let needs_more = |v: &DebugView| {
        v.needs_lights() || v.needs_pyramid() || v.needs_occlusion_records() || v.needs_shadows()
    };
    for view in DebugView::ALL.into_iter().filter(|v| !needs_more(v)) {
        let got = run(&mut f, Resolve::new(W, H).with_view(view));
        // Depth and material depth do not depend on the view: check them every time.
        let plan = &got.plan.passes[0];
        let render: Vec<_> = plan
            .programs
            .iter()
            .filter(|p| p.kind == "render")
            .collect();
        assert_eq!(render.len(), 2, "{view}: {:?}", plan.programs);
        if let Some((i, g, w)) = first_difference(got.depth.as_ref().unwrap(), &depth) {
            panic!("{view}: depth at pixel {i} is {g}, the reference {w}");
        }
        let got_material = got.material_depth.as_ref().unwrap();
        if let Some((i, g, w)) = first_difference(got_material, &material_depth) {
            panic!("{view}: material depth at pixel {i} is {g}, the reference {w}");
        }
        let want = cpu::shade(
            &f.cpu(),
            &Settings {
                view,
                ..Settings::default()
            },
        );
        let distinct: BTreeSet<[u8; 4]> = want.iter().copied().collect();
        let (tolerance, share) = match view {
            DebugView::Shaded => (2, 0.99),
            // Filtered texels and normalised normals: float rounding may differ by a step.
            DebugView::Depth | DebugView::Normal | DebugView::BaseColor | DebugView::Uv => (1, 1.0),
            // A tint times the shaded brightness, which may round a step apart.
            DebugView::Residency => (1, 1.0),
            _ => (0, 1.0),
        };
        let (over, largest) = color_differences(&got.color, &want, tolerance);
        eprintln!(
            "{view}: {} distinct colours, {over} pixels differ by more than {tolerance}, largest difference {largest}",
            distinct.len()
        );
        assert!(
            (pixels - over) as f64 >= share * pixels as f64,
            "{view}: {over} of {pixels} pixels differ from the reference by more than {tolerance} (largest {largest})"
        );
        assert!(
            got.color.iter().all(|c| c[3] == 255),
            "{view}: alpha must be 1"
        );
        // Every view shows something that tells pixels apart, so a constant image fails.
        let least = match view {
            DebugView::Raster | DebugView::Lod => 3,
            // Empty, spot's two materials and the knot's three slots.
            DebugView::Material => 6,
            // Empty, the knot's level 0 (no UVs), and Spot's texture at a few levels.
            DebugView::Mip => 4,
            DebugView::Depth => 10,
            _ => 20,
        };
        assert!(
            distinct.len() >= least,
            "{view}: only {} distinct colours in the reference",
            distinct.len()
        );
    }
}

#[test]
fn without_depth_targets_only_the_shading_dispatch_runs_and_the_colour_is_the_same() {
    let mut f = frame();
    let view = f.view;
    let pixels = (W * H) as usize;
    let depth = cpu::depth(&f.visbuffer, W, H);
    let material_depth = cpu::material_depth(&f.scene, &f.raster_clusters, &f.visbuffer);
    for view_mode in [DebugView::Shaded, DebugView::Clusters, DebugView::Depth] {
        let pass = Resolve::new(W, H).with_view(view_mode);
        let both = run_with(&mut f, pass, &view, BOTH).unwrap_or_else(|e| panic!("{e}"));
        let none = Targets {
            depth: false,
            material_depth: false,
        };
        let bare = run_with(&mut f, pass, &view, none).unwrap_or_else(|e| panic!("{e}"));
        // Colour alone: one compute program, no render program, nothing else declared.
        let programs = &bare.plan.passes[0].programs;
        let kinds: Vec<_> = programs.iter().map(|p| (p.name.as_str(), p.kind)).collect();
        assert_eq!(kinds, [("shade", "compute")], "{view_mode}");
        assert!(bare.depth.is_none() && bare.material_depth.is_none());
        // The same image as with the targets, and the reference's.
        assert_eq!(bare.color, both.color, "{view_mode}");
        let settings = Settings {
            view: view_mode,
            ..Settings::default()
        };
        let (over, largest) = reference_differences(&bare.color, &f, &settings, 2);
        assert!(
            over * 100 <= pixels,
            "{view_mode}: {over} pixels differ by more than 2 (largest {largest})"
        );
    }
    // One target alone: its own fullscreen pass, exact, and not the other's.
    for (targets, name) in [
        (
            Targets {
                depth: true,
                material_depth: false,
            },
            "depth",
        ),
        (
            Targets {
                depth: false,
                material_depth: true,
            },
            "material_depth",
        ),
    ] {
        let got =
            run_with(&mut f, Resolve::new(W, H), &view, targets).unwrap_or_else(|e| panic!("{e}"));
        let render: Vec<_> = got.plan.passes[0]
            .programs
            .iter()
            .filter(|p| p.kind == "render")
            .map(|p| p.name.as_str())
            .collect();
        assert_eq!(render, [name]);
        let (values, want) = match name {
            "depth" => (got.depth.unwrap(), &depth),
            _ => (got.material_depth.unwrap(), &material_depth),
        };
        assert_eq!(first_difference(&values, want), None, "{name}");
    }
}

#[test]
fn the_pyramid_view_shows_each_mip_of_a_bound_pyramid_like_the_reference() {
    let mut f = frame();
    let view = f.view;
    let depth = cpu::depth(&f.visbuffer, W, H);
    let mips = min_pyramid(&depth, 4);
    assert_eq!(
        mips.iter().map(|m| (m.width, m.height)).collect::<Vec<_>>(),
        [(32, 24), (16, 12), (8, 6), (4, 3)]
    );
    f.pyramid = Some(mips);
    let mut images = Vec::new();
    for mip in 0..4 {
        let mut pass = Resolve::new(W, H).with_view(DebugView::Pyramid);
        pass.settings.pyramid_mip = mip;
        let got = run_with(&mut f, pass, &view, BOTH).unwrap_or_else(|e| panic!("{e}"));
        let (over, largest) = reference_differences(&got.color, &f, &pass.settings, 1);
        assert_eq!(over, 0, "mip {mip}: largest difference {largest}");
        // A pixel shows the texel covering it: blocks of 2^(mip+1) pixels are one grey.
        let block = 2u32 << mip;
        let at = |x: u32, y: u32| got.color[(y * W + x) as usize];
        for y in 0..H {
            for x in 0..W {
                assert_eq!(at(x, y), at(x / block * block, y / block * block));
            }
        }
        images.push(got.color);
    }
    // Coarser mips are darker (min depth) and differ from the finer ones.
    let brightness = |img: &[[u8; 4]]| img.iter().map(|c| c[0] as u64).sum::<u64>();
    for k in 1..images.len() {
        assert!(
            brightness(&images[k]) < brightness(&images[k - 1]),
            "mip {k}"
        );
    }
    // A mip past the chain is a record error naming its length; the view without a
    // pyramid a setup error naming the slot.
    let mut pass = Resolve::new(W, H).with_view(DebugView::Pyramid);
    pass.settings.pyramid_mip = 4;
    match run_with(&mut f, pass, &view, BOTH) {
        Err(GraphError::Record { message, .. } | GraphError::Parameter { message, .. }) => {
            assert!(
                message.contains("`pyramid_mip` = 4") && message.contains("4 mips"),
                "{message}"
            )
        }
        other => panic!("{:?}", other.err()),
    }
    f.pyramid = None;
    let pass = Resolve::new(W, H).with_view(DebugView::Pyramid);
    match run_with(&mut f, pass, &view, BOTH) {
        Err(GraphError::Parameter { message, .. }) => {
            assert!(message.contains("`pyramid` slot"), "{message}")
        }
        other => panic!("{:?}", other.err()),
    }
}

/// The share of `color`'s covered pixels whose strongest channel is `channel`.
fn dominant(color: &[[u8; 4]], visbuffer: &[u64], channel: usize) -> usize {
    color
        .iter()
        .zip(visbuffer)
        .filter(|(c, v)| {
            **v != visbuffer::EMPTY && (0..3).all(|k| k == channel || c[channel] > c[k])
        })
        .count()
}

#[test]
fn the_occlusion_view_colours_by_pass_and_culled_share_like_the_reference() {
    let mut f = frame();
    let view = f.view;
    let slots = f.raster_clusters.len() as u32;
    let pass = Resolve::new(W, H).with_view(DebugView::Occlusion);
    let covered = f
        .visbuffer
        .iter()
        .filter(|&&v| v != visbuffer::EMPTY)
        .count();
    // Without the records every covered pixel is first-pass green, untinted.
    let plain = run_with(&mut f, pass, &view, BOTH).unwrap_or_else(|e| panic!("{e}"));
    let (over, largest) = reference_differences(&plain.color, &f, &pass.settings, 2);
    assert!(
        over * 100 <= covered,
        "no records: {over} pixels differ (largest {largest})"
    );
    assert_eq!(dominant(&plain.color, &f.visbuffer, 1), covered);

    // Slots [slots/4, slots/2) as the second pass's: `[7]` its first software slot,
    // `[3]` one past its last hardware slot. Instance 0 none culled, 1 half, 2 all.
    let mut counts = vec![0u32; 12];
    counts[7] = slots / 4;
    counts[3] = slots / 2;
    f.second_counts = Some(counts);
    f.occluded_per_instance = Some(vec![10, 0, 10, 5, 4, 4]);
    let got = run_with(&mut f, pass, &view, BOTH).unwrap_or_else(|e| panic!("{e}"));
    let (over, largest) = reference_differences(&got.color, &f, &pass.settings, 2);
    assert!(
        over * 100 <= covered,
        "{over} of {covered} pixels differ (largest {largest})"
    );
    // Each meaning is on screen: first pass (green), second pass (blue), culled (red).
    let second: usize = f
        .visbuffer
        .iter()
        .filter(|&&v| v != visbuffer::EMPTY)
        .filter(|&&v| cpu::drawn_by_second_pass(f.second_counts.as_deref(), visbuffer::cluster(v)))
        .count();
    assert!(
        second > 0 && second < covered,
        "{second} of {covered} second-pass pixels"
    );
    for (channel, name) in [(0, "red"), (1, "green"), (2, "blue")] {
        let n = dominant(&got.color, &f.visbuffer, channel);
        eprintln!("{name}: {n} of {covered} pixels");
        assert!(n > covered / 50, "only {n} {name} pixels of {covered}");
    }
    // Pixels of the wholly culled instance are redder than untinted ones, so a shader
    // that ignores the counters fails.
    let redness = |c: &[u8; 4]| c[0] as i32 - c[1] as i32;
    for (i, v) in f.visbuffer.iter().enumerate() {
        if *v != visbuffer::EMPTY
            && f.raster_clusters[visbuffer::cluster(*v) as usize].instance == 2
            && got.color[i] != [0, 0, 0, 255]
        {
            assert!(
                redness(&got.color[i]) > redness(&plain.color[i]),
                "pixel {i}"
            );
        }
    }
}

/// The `residency` view: with no `stream_errors` bound every covered pixel is at the
/// wanted level (green); with missing errors of several sizes on the meshlets' source
/// groups, the pixels take the reference's colours, each meaning on screen.
#[test]
fn the_residency_view_colours_missing_levels_like_the_reference() {
    let mut f = frame();
    let view = f.view;
    let pass = Resolve::new(W, H).with_view(DebugView::Residency);
    let covered = f
        .visbuffer
        .iter()
        .filter(|&&v| v != visbuffer::EMPTY)
        .count();
    let plain = run_with(&mut f, pass, &view, BOTH).unwrap_or_else(|e| panic!("{e}"));
    let (over, largest) = reference_differences(&plain.color, &f, &pass.settings, 2);
    assert!(
        over * 100 <= covered,
        "unbound: {over} pixels differ (largest {largest})"
    );
    assert_eq!(
        dominant(&plain.color, &f.visbuffer, 1),
        covered,
        "all green"
    );
    // Every group's page missing, its error spread over four orders of magnitude, so
    // each of the four colours is drawn somewhere.
    let groups = f.scene.groups.len();
    f.stream_errors = Some(
        (0..groups)
            .map(|g| match g % 5 {
                0 => 0.0,
                k => 1e-4 * 10f32.powi(k as i32),
            })
            .collect(),
    );
    let got = run_with(&mut f, pass, &view, BOTH).unwrap_or_else(|e| panic!("{e}"));
    let (over, largest) = reference_differences(&got.color, &f, &pass.settings, 2);
    assert!(
        over * 100 <= covered,
        "{over} of {covered} pixels differ (largest {largest})"
    );
    let mut seen = [0usize; 4];
    for v in f.visbuffer.iter().filter(|&&v| v != visbuffer::EMPTY) {
        let cluster = f.raster_clusters[visbuffer::cluster(*v) as usize];
        let levels = cpu::levels_missing(
            &f.scene,
            &view,
            f.stream_errors.as_deref(),
            &cluster,
            pass.settings.lod_threshold_px,
        );
        seen[levels as usize] += 1;
    }
    eprintln!("pixels at 0, 1, 2, 3+ levels missing: {seen:?}");
    assert!(seen.iter().all(|&n| n > 0), "{seen:?}");
}

#[test]
fn the_shaded_view_follows_the_settings_from_params() {
    let mut f = frame();
    let text = format!(
        "width = {W}\nheight = {H}\nview = \"shaded\"\nchecker_scale = 3.5\n\
         light_direction = [0.6, 0.2, 0.8]\nlight_color = [1.2, 0.9, 0.6]\nambient_color = [0.05, 0.1, 0.2]"
    );
    let params = params(&text);
    let mut registry = file::Registry::new();
    meshlight_pass_resolve::register(&mut registry);
    let pass = Resolve::from_params(&params).unwrap();
    assert!(registry.build("resolve", "compute", &params).is_ok());
    let settings = pass.settings;
    let got = run(&mut f, pass);
    let want = cpu::shade(&f.cpu(), &settings);
    let defaults = cpu::shade(&f.cpu(), &Settings::default());
    let pixels = (W * H) as usize;
    let (over, largest) = color_differences(&got.color, &want, 2);
    assert!(
        over * 100 <= pixels,
        "{over} of {pixels} pixels differ from the reference by more than 2 (largest {largest})"
    );
    // The settings matter: the default light gives a different image.
    let (changed, _) = color_differences(&want, &defaults, 2);
    assert!(changed > pixels / 10, "only {changed} pixels changed");
}

#[test]
fn a_viewport_other_than_the_params_is_a_record_error() {
    let mut f = frame();
    let camera = Camera::perspective(Vec3::new(0.3, 1.2, 4.0), Vec3::ZERO, 0.9, 0.1);
    let wrong = camera.view([W, H + 1], 0, None);
    match run_with_view(&mut f, Resolve::new(W, H), &wrong) {
        Err(GraphError::Record { message, .. }) => assert!(
            message.contains("viewport") && message.contains(&format!("{W} × {H}")),
            "{message}"
        ),
        Err(other) => panic!("not a record error: {other}"),
        Ok(_) => panic!("a viewport of {W} × {} ran", H + 1),
    }
}

#[test]
fn bad_params_are_refused_with_what_to_change() {
    let mut registry = file::Registry::new();
    meshlight_pass_resolve::register(&mut registry);
    let build = |text: &str| parameter_message(registry.build("resolve", "compute", &params(text)));
    let m = build("width = 0\nheight = 48");
    assert!(m.contains("`width`") && m.contains("> 0"), "{m}");
    let m = build("height = 48");
    assert!(m.contains("`width`"), "{m}");
    let m = build("width = 64\nheight = 48\nview = \"normals\"");
    for v in DebugView::ALL {
        assert!(m.contains(v.name()), "{m} does not name `{v}`");
    }
    assert!(m.contains("`normals`"), "{m}");
    let m = build("width = 64\nheight = 48\ncheker_scale = 2");
    assert!(m.contains("`cheker_scale`"), "{m}");
}

#[test]
fn clustered_lights_shade_and_count_like_the_reference() {
    let mut f = frame();
    let unlit = run(&mut f, Resolve::new(W, H));
    f.light();
    let pixels = (W * H) as usize;
    for view in [DebugView::Shaded, DebugView::LightCount] {
        let got = run(&mut f, Resolve::new(W, H).with_view(view));
        let settings = Settings {
            view,
            ..Settings::default()
        };
        // A pixel whose depth lies on a slice boundary may read the neighbouring froxel.
        let (over, largest) = reference_differences(&got.color, &f, &settings, 2);
        eprintln!("{view}: {over} pixels differ by more than 2, largest {largest}");
        assert!(
            over * 100 <= pixels,
            "{view}: {over} of {pixels} pixels differ from the reference by more than 2/255"
        );
        let distinct: BTreeSet<[u8; 4]> = got.color.iter().copied().collect();
        assert!(distinct.len() >= 4, "{view}: {} colours", distinct.len());
    }
    // The lights change the image.
    let lit = run(&mut f, Resolve::new(W, H));
    let (brighter, _) = color_differences(&lit.color, &unlit.color, 8);
    assert!(
        brighter * 10 >= pixels,
        "only {brighter} pixels changed under the lights"
    );
}

#[test]
fn the_light_count_view_without_clustering_is_an_error() {
    let mut f = frame();
    let view = f.view;
    match run_with_view(
        &mut f,
        Resolve::new(W, H).with_view(DebugView::LightCount),
        &view,
    ) {
        Err(GraphError::Parameter { message, .. }) => {
            assert!(
                message.contains("light-count") && message.contains("light_clustering.toml"),
                "{message}"
            )
        }
        other => panic!("{:?}", other.err()),
    }
}

/// The sun's shadow: two 64² cascades of the frame's own clusters, drawn by the depth-only
/// rasteriser's reference from each cascade's view, shade the frame and colour the
/// `shadow` view as the reference does; some pixels are in shadow and both cascades are
/// read.
#[test]
fn the_sun_is_shadowed_through_two_cascades_like_the_reference() {
    use meshlight_gpu_scene::cascades::{CascadeSettings, cascades};
    let mut f = frame();
    let view = f.view;
    let camera = Camera::perspective(
        Vec3::new(0.1, 0.6, 2.7),
        Vec3::new(0.0, 0.1, -0.5),
        0.9,
        0.1,
    );
    assert_eq!(
        camera.view([W, H], 0, None).view_projection,
        view.view_projection
    );
    let settings = Settings {
        light_direction: Vec3::new(-0.6, 0.7, 0.5),
        ..Settings::default()
    };
    let cascade_settings = CascadeSettings {
        count: 2,
        resolution: 64,
        // Uniform splits: the spots (about 2.7 away) in the first, the knot in the second.
        distance: 6.0,
        split_lambda: 0.0,
        caster_reach: 4.0,
        // Fitted to the slices.
        hold: 0.0,
    };
    let list = cascades(
        &camera,
        [W, H],
        settings.light_direction,
        &cascade_settings,
        0,
    )
    .unwrap();
    let mut maps = Vec::new();
    for c in &list {
        let drawn =
            meshlight_pass_sw_raster::cpu::rasterize(&f.scene, &c.view, &f.raster_clusters, 64, 64);
        maps.extend(drawn.iter().map(|&v| (v >> 32) as u32));
    }
    let params = ShadowParams::new(&list, 64, 1.0, 1.0);
    f.shadows = Some((params, maps));
    let covered = f
        .visbuffer
        .iter()
        .filter(|&&v| v != visbuffer::EMPTY)
        .count();
    let mut pass = Resolve::new(W, H);
    pass.settings = settings;
    let got = run_with(&mut f, pass, &view, NONE).unwrap_or_else(|e| panic!("{e}"));
    let (over, largest) = reference_differences(&got.color, &f, &pass.settings, 2);
    assert!(
        over * 100 <= covered,
        "{over} of {covered} pixels differ (largest {largest})"
    );
    // The shadow darkens some of what the sun lit.
    let shadowed = cpu::shade(&f.cpu(), &settings);
    let sunlit = {
        let mut plain = f.cpu();
        plain.shadows = None;
        cpu::shade(&plain, &settings)
    };
    let darker = shadowed
        .iter()
        .zip(&sunlit)
        .filter(|(a, b)| u32::from(a[0]) + 8 < u32::from(b[0]))
        .count();
    assert!(darker > 40, "only {darker} pixels are darker in shadow");
    // The `shadow` view: both cascades' colours, the reference's values.
    let pass = Resolve {
        settings: Settings {
            view: DebugView::Shadow,
            ..settings
        },
        ..pass
    };
    let got = run_with(&mut f, pass, &view, NONE).unwrap_or_else(|e| panic!("{e}"));
    let (over, largest) = reference_differences(&got.color, &f, &pass.settings, 2);
    assert!(
        over * 100 <= covered,
        "shadow view: {over} of {covered} pixels differ (largest {largest})"
    );
    let (params, _) = f.shadows.as_ref().unwrap();
    let mut per_cascade = [0usize; 3];
    for y in 0..H {
        for x in 0..W {
            let v = f.visbuffer[(y * W + x) as usize];
            if v == visbuffer::EMPTY {
                continue;
            }
            let p = cpu::pixel_surface(
                &f.cpu(),
                8.0,
                v,
                glam::Vec2::new(x as f32 + 0.5, y as f32 + 0.5),
            );
            let k = meshlight_pass_resolve::shadows::cascade_index(params, &view, p.world);
            per_cascade[k as usize] += 1;
        }
    }
    eprintln!("pixels per cascade (0, 1, past): {per_cascade:?}");
    assert!(
        per_cascade[0] > 50 && per_cascade[1] > 50,
        "{per_cascade:?}"
    );
}

#[test]
fn the_shadow_view_without_shadow_maps_is_an_error() {
    let mut f = frame();
    let view = f.view;
    let e = run_with(
        &mut f,
        Resolve::new(W, H).with_view(DebugView::Shadow),
        &view,
        NONE,
    )
    .err()
    .map(|e| e.to_string())
    .unwrap_or_default();
    assert!(e.contains("`shadow_maps`"), "{e}");
}
