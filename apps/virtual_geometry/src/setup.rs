//! The scene `meshlight render` and `meshlight view` draw, from the options they share:
//! the mesh and its copies on the field, the lights over it, the graph (built in code or
//! from a pipeline file) and the frame's settings. Both applications start from
//! [`setup`], so a window and a still of the same options draw the same frame.

use crate::frame_graph::GraphSource;
use crate::gltf_scene::{self, GltfSceneError};
use crate::scenes::{self, Paint};
use crate::settings::{FrameSettings, ShadowSettings};
use meshlight::gpu_scene::{Camera, SceneData, SceneDataError, data::Limits};
use meshlight::graph::{GpuAdapter, GraphError};
use meshlight::resolve::DebugView;
use meshlight::scene::MeshletAsset;
use meshlight::scene::SceneError;
use meshlight::scene::asset::format::SECTION_PAYLOAD;
use meshlight::scene::load::{GltfScene, ObjMaterial, load_gltf_scene};
use meshlight::shaders::cpu::layout::ClusterableObject;
use meshlight_light_clustering::ClusteringSettings;
use std::path::PathBuf;

/// Froxel-list entries per light of the field ([`scenes::field_lights`]) the clustering
/// starts with: the default scene's 256 lights fill 5,821 entries (about 23 froxels each,
/// whatever the viewport, as the grid's size is fixed); a frame that needs more still
/// grows the list.
pub const FIELD_ENTRIES_PER_LIGHT: u64 = 32;

/// The clustering [`setup`] asks for `lights` lights over a `viewport`: the lists of
/// [`ClusteringSettings::new`], the froxel lists started at [`FIELD_ENTRIES_PER_LIGHT`]
/// entries a light, so the default scene runs one frame rather than warning that its
/// lists grew. Public so that a bound on the light count (`meshlight render --lights`)
/// sizes the lists exactly as the frame will.
pub fn clustering_for(viewport: [u32; 2], lights: u64) -> ClusteringSettings {
    let mut clustering = ClusteringSettings::new(viewport, lights.max(1));
    clustering.entries = clustering
        .entries
        .max(lights.saturating_mul(FIELD_ENTRIES_PER_LIGHT));
    clustering
}

/// What to draw and at what size.
#[derive(Clone, Debug)]
pub struct SceneOptions {
    /// Mesh file (.obj, .gltf, .glb, .stl, or a baked .mlasset), or `procedural`.
    pub mesh: PathBuf,
    /// Tube segments of the procedural mesh (16 × segments² triangles).
    pub segments: u32,
    /// Copies of the mesh on the ground (1: one copy, framed by the camera, no lights).
    pub instances: u32,
    /// Point lights over the field; `None`: [`scenes::DEFAULT_LIGHTS`], or none with a
    /// pipeline file that clusters no lights.
    pub lights: Option<u32>,
    /// A pipeline file to render with instead of the graph built in code.
    pub pipeline: Option<PathBuf>,
    /// What the image shows; `None`: shaded, or the view a pipeline file's resolve names.
    pub view: Option<DebugView>,
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
    /// A glTF file is drawn as its scene (its meshes at its nodes); true bakes it as one
    /// mesh and places copies of it on the field, as for other mesh files.
    pub merge_gltf: bool,
    /// One of a glTF scene's cameras (in its node order); `None` frames the scene.
    pub camera: Option<usize>,
    /// Stream the meshes' pages through a GPU pool of this many MiB (see
    /// [`crate::streaming`]); `None`: every page resident.
    pub pool_mb: Option<u64>,
    /// Direction towards the sun; `None`: the pipeline's.
    pub sun: Option<glam::Vec3>,
    /// The sun's shadow.
    pub shadows: ShadowRequest,
}

/// The sun's shadow as a caller asks for it, before the scene is known.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ShadowRequest {
    /// Cascades, 0 to 4 (0: none); `None`: 4 where the pipeline has the shadow stage,
    /// else none.
    pub cascades: Option<u32>,
    /// Texels along each side of a cascade's map; `None`: [`default_resolution`] of the
    /// viewport.
    pub resolution: Option<u32>,
    /// How far shadows reach from the camera; `None`: [`crate::shadows::shadow_distance`].
    pub distance: Option<f32>,
    /// The split between uniform (0) and logarithmic (1).
    pub split_lambda: f32,
    /// How much larger than its slice a cascade's box is, so it is kept while the camera
    /// moves ([`meshlight::gpu_scene::cascades::CascadeSettings::hold`]).
    pub hold: f32,
    /// See [`ShadowSettings::depth_bias`].
    pub depth_bias: f32,
    /// See [`ShadowSettings::normal_bias`].
    pub normal_bias: f32,
    /// See [`ShadowSettings::lod_bias`].
    pub lod_bias: f32,
}

impl Default for ShadowRequest {
    /// The defaults of [`ShadowSettings`], with the count and distance left to the
    /// pipeline and the scene.
    fn default() -> Self {
        let s = ShadowSettings::default();
        Self {
            cascades: None,
            resolution: None,
            distance: None,
            split_lambda: s.cascades.split_lambda,
            hold: s.cascades.hold,
            depth_bias: s.depth_bias,
            normal_bias: s.normal_bias,
            lod_bias: s.lod_bias,
        }
    }
}

/// A cascade's side for a viewport when none is given: the viewport's longer side (a
/// cascade then has about as many texels across as the screen has pixels), rounded up
/// to a multiple of 8, from 256 to 2048.
pub fn default_resolution(viewport: [u32; 2]) -> u32 {
    viewport[0]
        .max(viewport[1])
        .next_multiple_of(8)
        .clamp(256, 2048)
}

impl ShadowRequest {
    /// No shadow.
    pub fn off() -> Self {
        Self {
            cascades: Some(0),
            ..Self::default()
        }
    }

    /// Refuses a number out of range, naming it, before any work: a unit distance stands
    /// in for the scene's, which is not known yet.
    pub fn check(&self, viewport: [u32; 2]) -> Result<(), GraphError> {
        match self.cascades {
            Some(0) => Ok(()),
            count => self.with(count.unwrap_or(1), viewport, 1.0, 1.0).validate(),
        }
    }

    /// The settings for a scene seen from `camera` (`None`: no shadow). The distance
    /// not given is [`crate::shadows::shadow_distance`]'s, and casters are kept as far
    /// towards the sun as shadows reach from the camera (a slope or a tower beyond that
    /// shades nothing in view unless it is taller than the distance); a pipeline without
    /// the shadow stage draws none unless cascades are asked for (and then refuses,
    /// saying so).
    pub fn settings(
        &self,
        data: &SceneData,
        camera: &Camera,
        viewport: [u32; 2],
        has_stage: bool,
    ) -> Option<ShadowSettings> {
        let default_count = ShadowSettings::default().cascades.count;
        let count = self
            .cascades
            .unwrap_or(if has_stage { default_count } else { 0 });
        if count == 0 {
            return None;
        }
        let reach = crate::shadows::scene_reach(data, camera.position).max(1.0);
        let distance = (self.distance)
            .unwrap_or_else(|| crate::shadows::shadow_distance(data, camera, viewport).max(1.0));
        Some(self.with(count, viewport, distance, distance.min(reach)))
    }

    /// The settings with these numbers and the request's own.
    fn with(&self, count: u32, viewport: [u32; 2], distance: f32, reach: f32) -> ShadowSettings {
        ShadowSettings {
            cascades: meshlight::gpu_scene::cascades::CascadeSettings {
                count,
                resolution: self.resolution.unwrap_or(default_resolution(viewport)),
                distance: self.distance.unwrap_or(distance),
                split_lambda: self.split_lambda,
                caster_reach: reach,
                hold: self.hold,
            },
            depth_bias: self.depth_bias,
            normal_bias: self.normal_bias,
            lod_bias: self.lod_bias,
            cache: true,
            walk: crate::shadows::ShadowWalk::default(),
        }
    }
}

impl SceneOptions {
    /// The default scene at a given size.
    pub fn new(width: u32, height: u32) -> Self {
        Self {
            mesh: PathBuf::from("procedural"),
            segments: meshlight::scene::DEFAULT_SEGMENTS,
            instances: scenes::DEFAULT_INSTANCES,
            lights: None,
            pipeline: None,
            view: None,
            width,
            height,
            merge_gltf: false,
            camera: None,
            pool_mb: None,
            sun: None,
            shadows: ShadowRequest::default(),
        }
    }

    /// Whether the pipeline has the shadow stage (passes over the view set
    /// `cascades`): the shipped frame does; a file that cannot be read does not.
    pub fn graph_has_shadow_stage(&self) -> bool {
        match &self.pipeline {
            None => true,
            Some(path) => meshlight::graph::file::Pipeline::load(path)
                .is_ok_and(|p| p.passes.iter().any(crate::shadows::is_shadow)),
        }
    }

    /// Whether the mesh argument is drawn as a glTF scene rather than copies of one mesh.
    pub fn is_gltf_scene(&self) -> bool {
        gltf_scene::is_gltf(&self.mesh) && !self.merge_gltf
    }

    /// Whether the graph clusters lights: the shipped frame does, a pipeline file does
    /// when it has the clustering's passes (one that cannot be read does not; loading
    /// it says why).
    pub fn graph_clusters_lights(&self) -> bool {
        self.pipeline.as_deref().is_none_or(|path| {
            meshlight::graph::file::Pipeline::load(path)
                .is_ok_and(|p| p.has_stage(meshlight::z_slice::STAGE))
        })
    }

    /// The lights asked for, explicitly or by default.
    pub fn lights_asked(&self) -> u32 {
        match (self.lights, self.graph_clusters_lights()) {
            (Some(n), _) => n,
            (None, true) => scenes::DEFAULT_LIGHTS,
            (None, false) => 0,
        }
    }

    /// Refuses, before any mesh is baked or adapter asked for, a pipeline file that
    /// cannot be read, and lights asked of a file that clusters none.
    pub fn check_pipeline(&self) -> Result<(), GraphError> {
        let Some(path) = &self.pipeline else {
            return Ok(());
        };
        meshlight::graph::file::Pipeline::load(path)?;
        let lights = self.lights_asked();
        if lights > 0 && self.instances > 1 && !self.graph_clusters_lights() {
            return Err(GraphError::PipelineFile {
                file: path.display().to_string(),
                message: format!(
                    "--lights {lights}: the file clusters no lights (it has no `z_slice` pass); render with --lights 0 (its default), or add the light clustering's passes as pipelines/virtual_geometry.toml does"
                ),
            });
        }
        Ok(())
    }
}

/// Everything a renderer of the scene is made from.
pub struct SceneSetup {
    /// The GPU scene: meshes, instances, materials.
    pub data: SceneData,
    /// The camera that frames it.
    pub camera: Camera,
    /// The frame's settings: size, view, clustering; callers may change the rest.
    pub settings: FrameSettings,
    /// The lights over the field (none for a single copy).
    pub lights: Vec<ClusterableObject>,
    /// The graph: built in code or read from the pipeline file.
    pub source: GraphSource,
    /// Where each mesh's pages are read from, when the scene streams (give them to
    /// [`crate::Renderer::start_streaming`]); empty when it does not.
    pub sources: Vec<crate::streaming::PageSource>,
}

/// What stops a scene from being set up.
#[derive(Debug, thiserror::Error)]
pub enum SetupError {
    /// The adapter or the pipeline file.
    #[error(transparent)]
    Graph(#[from] GraphError),
    /// The mesh.
    #[error(transparent)]
    Scene(#[from] SceneError),
    /// The scene does not fit the GPU buffers.
    #[error(transparent)]
    SceneData(#[from] SceneDataError),
    /// A glTF scene.
    #[error(transparent)]
    GltfScene(#[from] GltfSceneError),
}

/// What the mesh argument gave: a glTF scene, or one mesh to place copies of.
enum Loaded {
    Scene(GltfScene),
    /// A directory of baked assets, each drawn once where it was baked.
    Library(Vec<(String, MeshletAsset)>),
    /// The asset, and an OBJ's own materials where its `.mtl` gives some.
    Copies(MeshletAsset, Option<Vec<ObjMaterial>>),
}

/// The pool to stream through: `--pool-mb`'s, or for baked assets whose payload is more
/// than one binding holds on this adapter, [`crate::streaming::default_pool_bytes`]
/// (said in a warning); `None`: every page resident.
fn pool_bytes(o: &SceneOptions, loaded: &Loaded, limits: &Limits) -> Option<u64> {
    if let Some(mb) = o.pool_mb {
        return Some(mb << 20);
    }
    let payload = |a: &MeshletAsset| u64::from(a.header().sections[SECTION_PAYLOAD].words);
    let words: u64 = match loaded {
        Loaded::Library(assets) => assets.iter().map(|(_, a)| payload(a)).sum(),
        Loaded::Copies(asset, _) if asset.page_file().is_some() => payload(asset),
        _ => return None,
    };
    let pool = crate::streaming::pool_for_payload(words, limits)?;
    log::warn!(
        "{}: {:.2} GB of geometry is more than one binding holds on this adapter ({:.2} GB): \
         streaming it through a {} MiB pool (`--pool-mb` chooses the size)",
        o.mesh.display(),
        words as f64 * 4e-9,
        f64::from(limits.max_payload_words) * 4e-9,
        pool >> 20
    );
    Some(pool)
}

/// Checks the pipeline file, loads (or bakes) the mesh, places its copies and lights on
/// the field (or a glTF file's meshes at its nodes), sized for the adapter the frame will
/// run on, and fills the frame settings.
pub fn setup(o: &SceneOptions) -> Result<SceneSetup, SetupError> {
    o.check_pipeline()?;
    o.shadows.check([o.width, o.height])?;
    if o.camera.is_some() && !o.is_gltf_scene() {
        return Err(GltfSceneError::NotAScene {
            mesh: o.mesh.display().to_string(),
        }
        .into());
    }
    // Read (and baked) before the adapter is asked for, so a bad file costs nothing.
    // Baked assets are opened for streaming (their resident parts only) until the
    // adapter says whether they fit whole.
    let mut loaded = match o.is_gltf_scene() {
        true => Loaded::Scene(load_gltf_scene(&o.mesh)?),
        false if o.mesh.is_dir() => Loaded::Library(scenes::load_library(&o.mesh, true)?),
        false => match scenes::open_obj_with_materials(&o.mesh, o.pool_mb.is_some())? {
            Some((asset, materials)) => Loaded::Copies(asset, Some(materials)),
            // A mesh baked on first use streams only when asked to: its size is known
            // only once baked.
            None => {
                let baked = o.mesh.extension().is_some_and(|e| e == "mlasset");
                let streamed = baked || o.pool_mb.is_some();
                Loaded::Copies(scenes::open_asset(&o.mesh, o.segments, streamed)?, None)
            }
        },
    };
    // The scene's buffers are bound whole: sized for the adapter the frame will run on.
    let adapter = GpuAdapter::select()?;
    let limits = Limits::for_device(&adapter.adapter.limits());
    drop(adapter);
    let pool = pool_bytes(o, &loaded, &limits);
    if pool.is_none() {
        // Resident: every asset opened for streaming is read whole after all.
        match &mut loaded {
            Loaded::Library(assets) => *assets = scenes::load_library(&o.mesh, false)?,
            Loaded::Copies(asset, _) if asset.page_file().is_some() => {
                *asset = scenes::open_asset(&o.mesh, o.segments, false)?;
            }
            _ => {}
        }
    }
    let mut data = match pool {
        Some(_) => SceneData::streamed(limits),
        None => SceneData::new(limits),
    };
    let mut placed = match &loaded {
        Loaded::Scene(scene) => gltf_scene::place(data, scene, o.camera)?,
        Loaded::Library(assets) => scenes::library(data, assets)?,
        Loaded::Copies(asset, materials) => {
            let paint = match materials {
                Some(m) => Paint::Own(vec![scenes::add_obj_materials(&mut data, m)?]),
                None => Paint::Palette,
            };
            match o.instances {
                1 => scenes::single_painted(data, asset, paint)?,
                n => scenes::field_painted(data, asset, n, paint)?,
            }
        }
    };
    if let Some(bytes) = pool {
        placed.data.reserve_pool(bytes)?;
    }
    let mut settings = FrameSettings::new(o.width, o.height);
    // A view given wins over a pipeline file's; none given leaves the file's.
    settings.view = o.view;
    settings.sun_direction = o.sun;
    settings.shadows = o.shadows.settings(
        &placed.data,
        &placed.camera,
        [o.width, o.height],
        o.graph_has_shadow_stage(),
    );
    if let Some(shadows) = &settings.shadows {
        shadows.validate()?;
    }
    let lights = match (&loaded, o.lights) {
        // A scene is lit by the sun and the sky unless lights are asked for.
        (Loaded::Scene(_), Some(n)) => gltf_scene::scene_lights(&placed, n),
        (Loaded::Scene(_), None) => Vec::new(),
        (Loaded::Library(_), _) => Vec::new(),
        (Loaded::Copies(..), _) if o.instances > 1 => {
            scenes::field_lights(&placed, o.lights_asked())
        }
        (Loaded::Copies(..), _) => Vec::new(),
    };
    if !lights.is_empty() || o.view.is_some_and(|v| v.needs_lights()) {
        settings.clustering = Some(clustering_for([o.width, o.height], lights.len() as u64));
    }
    let source = match &o.pipeline {
        Some(path) => GraphSource::File(path.clone()),
        None => GraphSource::Shipped,
    };
    Ok(SceneSetup {
        data: placed.data,
        camera: placed.camera,
        settings,
        lights,
        source,
        sources: placed.sources,
    })
}
