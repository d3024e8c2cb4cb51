//! A glTF file kept as a scene: each mesh some node places is read once, in its own
//! space, and each node that places it becomes an instance with its world transform, so
//! a mesh used 500 times is stored (and baked) once. The cameras the scene's nodes carry
//! come with it.

use std::path::Path;

use glam::Mat4;
use gltf::json::validation::Checked;

use super::GltfFile;
use super::images::{SceneTexture, read_textures};
use super::materials::{SceneMaterial, read_materials};
use super::nodes::Placement;
use crate::error::SceneError;
use crate::load::LoadOptions;
use crate::mesh::Mesh;

/// A glTF file's default scene with its instancing kept.
#[derive(Debug, Clone)]
pub struct GltfScene {
    /// The file, as errors and names quote it.
    pub source: String,
    /// The meshes some node places, each read once, in its own space, in the order of
    /// their first instance.
    pub meshes: Vec<SceneMesh>,
    /// One per node that places a mesh with triangles, in the scene's depth-first order.
    pub instances: Vec<SceneInstance>,
    /// The cameras the scene's nodes carry, in the same order.
    pub cameras: Vec<SceneCamera>,
    /// The file's materials, which [`SceneMesh::materials`] index.
    pub materials: Vec<SceneMaterial>,
    /// The file's textures, which the materials' [`super::TextureRef`]s index, with
    /// the images the materials sample decoded.
    pub textures: Vec<SceneTexture>,
    /// What was read but cannot be drawn as the file asks (an image that does not
    /// decode, say), one line each; also logged as warnings.
    pub warnings: Vec<String>,
}

/// One mesh of a scene.
#[derive(Debug, Clone)]
pub struct SceneMesh {
    /// The glTF mesh's name, or `#index` for an unnamed one.
    pub name: String,
    /// Its triangle primitives merged (see [`super::load_gltf`] for what is kept), each
    /// triangle with its material slot ([`Mesh::materials`]).
    pub mesh: Mesh,
    /// The material behind each slot, in order of first use by the primitives: an
    /// index into [`GltfScene::materials`], or [`super::DEFAULT_MATERIAL`].
    pub materials: Vec<u32>,
}

/// One node placing a mesh.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SceneInstance {
    /// Index into [`GltfScene::meshes`].
    pub mesh: usize,
    /// Its world transform.
    pub transform: Mat4,
    /// The glTF node (`None` where a file without scenes places its meshes itself).
    pub node: Option<usize>,
}

/// A camera a node carries.
#[derive(Debug, Clone, PartialEq)]
pub struct SceneCamera {
    /// The glTF camera's name, or `#index`.
    pub name: String,
    /// The node's world transform: the camera looks down its -Z axis, +Y up. glTF
    /// asks renderers to ignore any scale in it.
    pub transform: Mat4,
    /// How it projects.
    pub projection: CameraProjection,
}

/// A glTF camera's projection, as the file gives it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum CameraProjection {
    /// A perspective camera.
    Perspective {
        /// Vertical field of view, radians.
        yfov: f32,
        /// The near plane's distance.
        znear: f32,
        /// Width over height, where the file fixes it (else the viewport's).
        aspect_ratio: Option<f32>,
    },
    /// An orthographic camera.
    Orthographic {
        /// Half the view's width, world units.
        xmag: f32,
        /// Half the view's height, world units.
        ymag: f32,
        /// The near plane's distance.
        znear: f32,
        /// The far plane's distance.
        zfar: f32,
    },
}

/// [`load_gltf_scene_with`]'s options: the default ones.
pub fn load_gltf_scene(path: &Path) -> Result<GltfScene, SceneError> {
    load_gltf_scene_with(path, &LoadOptions::default())
}

/// Reads the glTF or GLB file at `path` as a scene. `options.max_triangles` bounds the
/// triangles of the distinct meshes placed (what would be baked), checked from the
/// accessors' declared counts before anything is read; instances cost no triangles, and
/// the node tree may place at most [`super::nodes::MAX_NODE_INSTANCES`] of them.
pub fn load_gltf_scene_with(path: &Path, options: &LoadOptions) -> Result<GltfScene, SceneError> {
    let mut file = GltfFile::open(path)?;
    let placed = file.placements(None)?;
    let materials = read_materials(&file)?;
    let root = file.root();

    // The distinct meshes placed, in the order of their first placement, and what they
    // declare: bounded before any is read.
    let declared = file.mesh_triangles()?;
    let mut slot: Vec<Option<usize>> = vec![None; root.meshes.len()];
    let mut used = Vec::new();
    for p in &placed {
        if let Some(m) = p.mesh
            && slot[m].is_none()
        {
            slot[m] = Some(used.len());
            used.push(m);
        }
    }
    let total = used
        .iter()
        .fold(0u64, |a, &m| a.saturating_add(declared[m]));
    Mesh::check_limits(&path.display().to_string(), 0, total)?;
    if total > options.max_triangles {
        return Err(super::over_budget(path, total, options.max_triangles));
    }

    let buffers = file.buffers()?;
    let (textures, warnings) = read_textures(&file, &buffers, &materials, options)?;
    // Each used mesh read once; one without triangles places nothing.
    let mut read: Vec<Option<usize>> = vec![None; used.len()];
    let mut meshes = Vec::new();
    for (k, &m) in used.iter().enumerate() {
        if let Some((mesh, materials)) = file.read_mesh(&buffers, m)? {
            read[k] = Some(meshes.len());
            meshes.push(SceneMesh {
                name: file.mesh_name(m),
                mesh,
                materials,
            });
        }
    }
    let mut instances = Vec::new();
    let mut cameras = Vec::new();
    for &Placement {
        node,
        mesh,
        camera,
        transform,
    } in &placed
    {
        if let Some(mesh) = mesh.and_then(|m| slot[m]).and_then(|k| read[k]) {
            instances.push(SceneInstance {
                mesh,
                transform,
                node,
            });
        }
        if let Some(c) = camera {
            cameras.push(scene_camera(&file, c, transform)?);
        }
    }
    Ok(GltfScene {
        source: path.display().to_string(),
        meshes,
        instances,
        cameras,
        materials,
        textures,
        warnings,
    })
}

/// Camera `c` placed at `transform`, its numbers checked: a camera that cannot project
/// is an error naming it, not a black frame.
fn scene_camera(file: &GltfFile, c: usize, transform: Mat4) -> Result<SceneCamera, SceneError> {
    let root = file.root();
    let camera = root.cameras.get(c).ok_or_else(|| {
        file.err(format!(
            "a node carries camera {c}, but the file has only {} cameras",
            root.cameras.len()
        ))
    })?;
    let name = camera.name.clone().unwrap_or_else(|| format!("#{c}"));
    let bad = |what: &str| {
        file.err(format!(
            "camera {name:?}: {what}; fix the camera or leave it out (the scene is framed \
             without it)"
        ))
    };
    let positive = |v: f32| v.is_finite() && v > 0.0;
    let projection = match (&camera.type_, &camera.perspective, &camera.orthographic) {
        (Checked::Valid(gltf::json::camera::Type::Perspective), Some(p), _) => {
            if !(positive(p.yfov) && p.yfov < std::f32::consts::PI) {
                return Err(bad(&format!(
                    "its yfov is {}, not an angle between 0 and π radians",
                    p.yfov
                )));
            }
            if !positive(p.znear) {
                return Err(bad(&format!("its znear is {}, not above 0", p.znear)));
            }
            if let Some(a) = p.aspect_ratio.filter(|&a| !positive(a)) {
                return Err(bad(&format!("its aspectRatio is {a}, not above 0")));
            }
            CameraProjection::Perspective {
                yfov: p.yfov,
                znear: p.znear,
                aspect_ratio: p.aspect_ratio,
            }
        }
        (Checked::Valid(gltf::json::camera::Type::Orthographic), _, Some(o)) => {
            if !(positive(o.xmag) && positive(o.ymag)) {
                return Err(bad(&format!(
                    "its xmag and ymag are {} and {}, not both above 0",
                    o.xmag, o.ymag
                )));
            }
            if !(o.znear.is_finite() && o.znear >= 0.0 && o.zfar.is_finite() && o.zfar > o.znear) {
                return Err(bad(&format!(
                    "its znear and zfar are {} and {}; give 0 ≤ znear < zfar",
                    o.znear, o.zfar
                )));
            }
            CameraProjection::Orthographic {
                xmag: o.xmag,
                ymag: o.ymag,
                znear: o.znear,
                zfar: o.zfar,
            }
        }
        _ => {
            return Err(bad(
                "its type is not \"perspective\" or \"orthographic\" with that object given",
            ));
        }
    };
    Ok(SceneCamera {
        name,
        transform,
        projection,
    })
}
