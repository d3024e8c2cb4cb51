//! A glTF file drawn as its author made it: each mesh baked once (cached by its content),
//! each node that places it an instance at its world transform, framed by a camera of
//! the file's or one that sees the whole scene.

use crate::scenes::{Placed, point_light};
use crate::streaming::PageSource;
use glam::{Mat4, Vec3};
use meshlight::gpu_scene::view::Projection;
use meshlight::gpu_scene::{Camera, Material, MeshId, SceneData, SceneDataError, TextureId};
use meshlight::scene::SceneError;
use meshlight::scene::load::{
    AlphaMode, CameraProjection, GltfScene, SceneCamera, SceneMaterial, Wrap, load_gltf_scene,
};
use meshlight::scene::texture::Image;
use meshlight::shaders::cpu::layout::{
    ClusterableObject, MAP_BASE_COLOR, MAP_COUNT, MAP_EMISSIVE, MAP_METALLIC_ROUGHNESS, MAP_NORMAL,
    MAP_OCCLUSION, TextureWrap,
};
use std::collections::{BTreeMap, BTreeSet};
use std::path::Path;

/// Why a glTF scene cannot be drawn.
#[derive(Debug, thiserror::Error)]
pub enum GltfSceneError {
    /// The file, or one of its meshes.
    #[error(transparent)]
    Scene(#[from] SceneError),
    /// The scene does not fit the GPU buffers.
    #[error(transparent)]
    SceneData(#[from] SceneDataError),
    /// A camera asked for of a mesh that is not a glTF scene.
    #[error(
        "{mesh}: a camera index is only for a glTF scene (.gltf or .glb, not merged into one mesh); leave it out"
    )]
    NotAScene {
        /// The mesh argument.
        mesh: String,
    },
    /// A camera asked for that the file does not have.
    #[error(
        "{file}: camera {index} asked for, but its scene has {count} camera(s){}; leave the camera out to frame the whole scene",
        if *count > 0 { format!(" (0 to {})", count - 1) } else { String::new() }
    )]
    NoSuchCamera {
        /// The file.
        file: String,
        /// The camera asked for.
        index: usize,
        /// The cameras its scene's nodes carry.
        count: usize,
    },
}

/// Is `extension` (lower case) a glTF file's?
pub fn is_gltf(path: &Path) -> bool {
    path.extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| e.eq_ignore_ascii_case("gltf") || e.eq_ignore_ascii_case("glb"))
}

/// The glTF file at `path` as a scene in `data`: each mesh baked once (or found in the
/// asset cache by its content), each node placing it an instance. `camera` picks one of
/// the file's cameras (in the scene's node order); `None` frames the whole scene from
/// the front, above and to the right.
///
/// Each primitive is shaded with its material's metallic-roughness factors (glTF's
/// default material where it names none): the asset keeps each meshlet's material
/// slot, and the instance the first of its mesh's run of materials, with the material's
/// textures (base colour, metallic-roughness, normal, occlusion, emissive). A node whose
/// transform mirrors places a copy of its mesh with the winding reversed (baked once
/// too), since the rasterisers keep counter-clockwise faces.
pub fn gltf_scene(
    data: SceneData,
    path: &Path,
    camera: Option<usize>,
) -> Result<Placed, GltfSceneError> {
    let scene = load_gltf_scene(path)?;
    place(data, &scene, camera)
}

/// [`gltf_scene`] for a scene already loaded.
pub fn place(
    mut data: SceneData,
    scene: &GltfScene,
    camera: Option<usize>,
) -> Result<Placed, GltfSceneError> {
    let chosen = camera
        .map(|index| {
            scene
                .cameras
                .get(index)
                .ok_or_else(|| GltfSceneError::NoSuchCamera {
                    file: scene.source.clone(),
                    index,
                    count: scene.cameras.len(),
                })
        })
        .transpose()?;
    let materials = mesh_materials(&mut data, scene)?;
    // (mesh, mirrored) → the GPU scene's mesh and its bounds, baked on first use.
    let mut baked: BTreeMap<(usize, bool), (MeshId, [Vec3; 2])> = BTreeMap::new();
    let mut sources = Vec::new();
    let (mut low, mut high) = (Vec3::splat(f32::MAX), Vec3::splat(f32::MIN));
    for instance in &scene.instances {
        let mirrored = instance.transform.determinant() < 0.0;
        let key = (instance.mesh, mirrored);
        let (mesh, [lo, hi]) = match baked.get(&key) {
            Some(&known) => known,
            None => {
                let source = &scene.meshes[instance.mesh];
                let mut mesh = source.mesh.clone();
                let mut name = source.name.clone();
                if mirrored {
                    for t in mesh.indices.chunks_exact_mut(3) {
                        t.swap(1, 2);
                    }
                    name.push_str(" (mirrored)");
                }
                // A streamed scene opens the cached file's resident part and reads its
                // pages from there.
                let streamed = data.streaming().is_some();
                let asset = crate::scenes::cached_mesh(&mesh, streamed)?;
                let id = data.add_mesh(&name, &asset)?;
                if streamed {
                    sources.push(PageSource::of(&std::sync::Arc::new(asset.clone()))?);
                }
                let h = asset.header();
                let known = (id, [Vec3::from(h.bounds_min), Vec3::from(h.bounds_max)]);
                baked.insert(key, known);
                known
            }
        };
        if data
            .add_instance(mesh, instance.transform, materials[instance.mesh])?
            .is_some()
        {
            for corner in 0..8 {
                let c = Vec3::new(
                    if corner & 1 == 0 { lo.x } else { hi.x },
                    if corner & 2 == 0 { lo.y } else { hi.y },
                    if corner & 4 == 0 { lo.z } else { hi.z },
                );
                let w = instance.transform.transform_point3(c);
                low = low.min(w);
                high = high.max(w);
            }
        }
    }
    let camera = match chosen {
        Some(c) => file_camera(c),
        None => framing_camera(low, high),
    };
    Ok(Placed {
        data,
        camera,
        sources,
    })
}

/// Per mesh of `scene`, the first of the materials of `data` its slots are drawn in:
/// one GPU material per slot, consecutive, with its glTF material's factors and
/// textures (glTF's default material where a primitive names none), and no
/// checkerboard. Meshes with the same materials share one run.
fn mesh_materials(data: &mut SceneData, scene: &GltfScene) -> Result<Vec<u32>, SceneDataError> {
    let mut textures = SceneTextures::default();
    let mut runs: BTreeMap<&[u32], u32> = BTreeMap::new();
    let mut firsts = Vec::with_capacity(scene.meshes.len());
    let mut blended = BTreeSet::new();
    let mut mixed_transforms = BTreeSet::new();
    for m in &scene.meshes {
        if let Some(&first) = runs.get(m.materials.as_slice()) {
            firsts.push(first);
            continue;
        }
        let first = data.materials.len() as u32;
        for &slot in &m.materials {
            let default = SceneMaterial::default();
            let source = scene.materials.get(slot as usize).unwrap_or(&default);
            let alpha_cutoff = match source.alpha {
                AlphaMode::Opaque => None,
                AlphaMode::Mask { cutoff } => Some(cutoff),
                AlphaMode::Blend => {
                    blended.insert(source.name.clone());
                    None
                }
            };
            let [r, g, b, alpha] = source.base_color;
            let mut maps = [None; MAP_COUNT];
            for (map, texture, srgb) in [
                (MAP_BASE_COLOR, source.base_color_texture, true),
                (
                    MAP_METALLIC_ROUGHNESS,
                    source.metallic_roughness_texture,
                    false,
                ),
                (MAP_NORMAL, source.normal_texture, false),
                (MAP_OCCLUSION, source.occlusion_texture, false),
                (MAP_EMISSIVE, source.emissive_texture, true),
            ] {
                if let Some(t) = texture {
                    maps[map] = textures.get(data, scene, t.texture, srgb)?;
                }
            }
            let (uv_transform, mixed) = source.uv_transform();
            if mixed {
                mixed_transforms.insert(source.name.clone());
            }
            data.add_material(Material {
                base_color: [r, g, b],
                metallic: source.metallic,
                roughness: source.roughness,
                emissive: source.emissive,
                checker: false,
                maps,
                normal_scale: source.normal_scale,
                occlusion_strength: source.occlusion_strength,
                uv_transform,
                double_sided: source.double_sided,
                alpha,
                alpha_cutoff,
            })?;
        }
        runs.insert(&m.materials, first);
        firsts.push(first);
    }
    if !mixed_transforms.is_empty() {
        log::warn!(
            "{}: material(s) {} give their textures different KHR_texture_transforms; \
             meshlight samples all of a material's textures through one, so they are drawn \
             with the base colour texture's (or the first textured map's)",
            scene.source,
            mixed_transforms.into_iter().collect::<Vec<_>>().join(", ")
        );
    }
    if !blended.is_empty() {
        log::warn!(
            "{}: material(s) {} blend (alphaMode BLEND); meshlight draws them opaque (a \
             visibility buffer keeps one surface a pixel); MASK materials are cut out",
            scene.source,
            blended.into_iter().collect::<Vec<_>>().join(", ")
        );
    }
    Ok(firsts)
}

/// The scene's textures uploaded into `data` as they are first used
/// ([`SceneData::add_image`]), once per colour space each is sampled in.
#[derive(Default)]
struct SceneTextures {
    uploaded: BTreeMap<(usize, bool), Option<TextureId>>,
}

impl SceneTextures {
    fn get(
        &mut self,
        data: &mut SceneData,
        scene: &GltfScene,
        texture: usize,
        srgb: bool,
    ) -> Result<Option<TextureId>, SceneDataError> {
        if let Some(&id) = self.uploaded.get(&(texture, srgb)) {
            return Ok(id);
        }
        // An image that did not decode was reported when the file was read; the
        // material keeps its factor.
        let id = match scene
            .textures
            .get(texture)
            .and_then(|t| Some((t, t.image.as_ref()?)))
        {
            Some((t, image)) => Some(upload(data, image, srgb, t.wrap)?),
            None => None,
        };
        self.uploaded.insert((texture, srgb), id);
        Ok(id)
    }
}

/// `image` added to `data` as a texture ([`SceneData::add_image`]) with glTF's wrap
/// modes.
pub fn upload(
    data: &mut SceneData,
    image: &Image,
    srgb: bool,
    wrap: [Wrap; 2],
) -> Result<TextureId, SceneDataError> {
    let wrap = wrap.map(|w| match w {
        Wrap::Repeat => TextureWrap::Repeat,
        Wrap::ClampToEdge => TextureWrap::Clamp,
        Wrap::MirroredRepeat => TextureWrap::Mirror,
    });
    data.add_image(image, srgb, wrap)
}

/// The camera a glTF node carries: at the node's origin, looking down its -Z axis with
/// its +Y up (any scale in the node ignored, as glTF asks). A perspective camera's
/// aspect ratio is the viewport's, not the file's.
pub fn file_camera(c: &SceneCamera) -> Camera {
    let position = c.transform.w_axis.truncate();
    let forward = -c.transform.z_axis.truncate().normalize_or(Vec3::NEG_Z);
    let up = c.transform.y_axis.truncate().normalize_or(Vec3::Y);
    let projection = match c.projection {
        CameraProjection::Perspective { yfov, znear, .. } => Projection::Perspective {
            fov_y: yfov,
            near: znear,
        },
        CameraProjection::Orthographic {
            ymag, znear, zfar, ..
        } => Projection::Orthographic {
            height: 2.0 * ymag,
            near: znear,
            far: zfar,
        },
    };
    Camera {
        position,
        target: position + forward,
        up,
        projection,
    }
}

/// A camera that sees the box `low..high` whole: from the front (+Z), above and to the
/// right, 40° high, standing back so the box's bounding sphere fits.
pub fn framing_camera(low: Vec3, high: Vec3) -> Camera {
    if low.x > high.x {
        // Nothing placed: the sky, from the origin.
        return Camera::perspective(
            Vec3::new(0.0, 0.0, 5.0),
            Vec3::ZERO,
            40f32.to_radians(),
            0.01,
        );
    }
    let centre = (low + high) * 0.5;
    let radius = ((high - low).length() * 0.5).max(1e-4);
    let fov = 40f32.to_radians();
    let distance = radius / (fov * 0.5).sin() * 1.05;
    Camera::perspective(
        centre + Vec3::new(0.45, 0.45, 1.0).normalize() * distance,
        centre,
        fov,
        distance * 0.002,
    )
}

/// `count` point lights over a scene's instances, spread evenly over them in order, each
/// hovering a little above its instance and reaching about three of its radii.
pub fn scene_lights(placed: &Placed, count: u32) -> Vec<ClusterableObject> {
    let instances = &placed.data.instances;
    if instances.is_empty() || count == 0 {
        return Vec::new();
    }
    (0..count)
        .map(|i| {
            let instance = &instances[(i as usize * instances.len()) / count as usize];
            let m = Mat4::from_cols_array_2d(&instance.world_from_local);
            let s = placed.data.meshes[instance.mesh as usize].bounding_sphere;
            let scale = [m.x_axis, m.y_axis, m.z_axis]
                .map(|a| a.truncate().length())
                .into_iter()
                .fold(0.0f32, f32::max);
            let radius = (s[3] * scale).max(1e-4);
            let p = m.transform_point3(Vec3::new(s[0], s[1], s[2])) + Vec3::Y * radius * 1.2;
            // Hues around the colour wheel, in order.
            point_light(p, radius * 3.0, radius, i as f32 * 2.399_963)
        })
        .collect()
}
