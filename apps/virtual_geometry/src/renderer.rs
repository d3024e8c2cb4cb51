//! The frame loop: the graph compiled for the adapter, the scene uploaded, one
//! `execute_frame` per camera, the counters taken back without waiting, and the
//! candidate list and raster slots grown when a frame reports it dropped clusters. With
//! `FrameSettings::clustering`, the renderer's lights are uploaded and clustered every
//! frame, and the clustering's lists grow the same way.

use super::adaptive_occlusion::{Adaptive, FramePlan, OcclusionPolicy, SecondPass};
use super::counts::{
    CLUSTER_COUNT_READBACK, FrameCounts, HIERARCHY_COUNTS_READBACK, HierarchyCounts,
    RASTER_COUNTS_READBACK, SECOND_COUNTS_READBACK, SECOND_HIERARCHY_COUNTS_READBACK,
    SECOND_WALK_COUNT_READBACK,
};
use super::frame_graph::{
    CLUSTERS_PARAM, DEPTH, Frame, GraphSource, HOST_TARGET, MAX_SLOTS, SECOND_COUNTS, SLOTS_PARAM,
    frame,
};
use super::settings::FrameSettings;
use super::streaming::{PageSource, Streaming};
use glam::Mat4;
use meshlight::gpu_scene::data::Limits;
use meshlight::gpu_scene::{Camera, GpuScene, SceneData};
use meshlight::graph::file::Pipeline;
use meshlight::graph::{
    AdapterClass, CompileOptions, CompiledGraph, Executor, FrameData, FrameStats, GpuAdapter,
    GpuContext, GraphError, Imports, Result, experimental_features, feature_names,
};
use meshlight::resolve::DebugView;
use meshlight::shaders::cpu::layout::ClusterableObject;
use meshlight::stream::Budget;
use meshlight_light_clustering::clusterer::Counters;
use meshlight_light_clustering::frame_graph::OBJECT_USAGE;
pub use meshlight_light_clustering::growth::Growth;
use meshlight_light_clustering::growth::{Want, grow, param_value};
use std::collections::BTreeMap;

/// How many frames [`Renderer::render_still`] runs, at most, to reach a frame that
/// dropped nothing: each overflowing frame grows the lists to what it asked for, so one
/// grow per list suffices unless the view changes.
pub const MAX_STILL_FRAMES: u32 = 4;

/// Frames in a row with nothing to stream that [`Renderer::settle_streaming`] waits for:
/// more than the requests' readback latency, so a page asked for has had time to show.
pub const SETTLED_FRAMES: u32 = 2 * super::streaming::REQUESTS_LATENCY + 2;

/// A finished image.
pub struct Still {
    /// Image width in pixels.
    pub width: u32,
    /// Image height in pixels.
    pub height: u32,
    /// RGBA8, rows top to bottom.
    pub rgba: Vec<u8>,
    /// The frame's statistics, with GPU timings where the adapter has timestamps.
    pub stats: FrameStats,
    /// The frame's counters: clusters considered, drawn by each rasteriser, dropped.
    pub counts: FrameCounts,
    /// Frames run to get there (more than 1 when a list had to grow).
    pub frames: u32,
}

/// The virtual-geometry renderer: the frame compiled for a device (its own, or a host's),
/// the scene on the GPU, and the frame loop that reads the counters back and grows the
/// lists without waiting.
pub struct Renderer {
    /// The scene. Moving instances and changing materials is uploaded by the next
    /// frame; a scene that outgrows its buffers (more meshes or instances) needs a new
    /// renderer, whose graph is sized for it.
    pub data: SceneData,
    /// What the frame was built with.
    pub settings: FrameSettings,
    /// What the frame's `resolve` shows (the settings' view, or the pipeline's own).
    pub view: DebugView,
    /// The pipeline the frame was built from, as the settings left it.
    pub pipeline: Pipeline,
    /// The frame, compiled for the device.
    pub compiled: CompiledGraph,
    /// The device and what runs on it (resources, pipelines, timings, readbacks).
    pub executor: Executor,
    scene: GpuScene,
    /// The largest list a binding can hold, in elements of 8 bytes.
    max_elements: u64,
    frame_index: u32,
    previous_view_projection: Option<Mat4>,
    /// The next frame's camera does not follow from the last (see [`Renderer::camera_cut`]).
    cut: bool,
    /// The graph culls in two passes and reads the second pass's counters back.
    two_pass: bool,
    /// `fill` walks the culling hierarchy and its counters come back.
    walks_hierarchy: bool,
    /// A second walk (from the nodes the first found hidden) and its counters.
    walks_twice: bool,
    /// Whether frames test occlusion now ([`FrameSettings::occlusion_policy`]).
    occlusion: Adaptive,
    /// What a frame leaves out when it does not test (`None`: it always tests).
    second_pass: Option<SecondPass>,
    /// What each submitted frame ran, until its counters are in.
    frame_plans: BTreeMap<u64, FramePlan>,
    /// What the last frame ran.
    last_plan: FramePlan,
    /// Instances moved through [`Renderer::set_transform`] since the last frame.
    moved: Vec<meshlight::gpu_scene::InstanceId>,
    /// Counters by frame, until both readbacks of a frame are in.
    pending: BTreeMap<u64, PendingCounts>,
    latest: Option<FrameCounts>,
    /// Every grow of the candidate list and the raster slots so far.
    pub growths: Vec<Growth>,
    /// The adapter's name, for reports.
    pub adapter: String,
    /// The lights the frame clusters and shades with (with `settings.clustering`; at
    /// most its `objects`). Uploaded by every frame.
    pub lights: Vec<ClusterableObject>,
    light_buffers: Option<LightBuffers>,
    /// The clustering's counters, growths and warnings.
    pub clustering: Counters,
    /// Textures of the caller's given to every frame (see [`Renderer::import_texture`]).
    imported_textures: Vec<(String, wgpu::Texture)>,
    /// A streamed scene's streaming (see [`Renderer::start_streaming`]).
    pub streaming: Option<Streaming>,
    /// The shadow cascades the frame draws (0 without shadows).
    cascades: u32,
    /// The newest counters of each shadow cascade that have come back.
    pub shadow_counts: Vec<super::shadows::CascadeCounts>,
    /// The cascades' maps and what each holds.
    shadow_cache: super::shadows::ShadowCache,
    /// Cascades drawn by the last frame (the others kept their maps).
    pub cascades_drawn: u32,
    /// Towards the sun, as the frame's resolve has it (read when the frame is built).
    sun: glam::Vec3,
}

/// The imported object list of the light clustering and its count.
struct LightBuffers {
    objects: wgpu::Buffer,
    object_count: wgpu::Buffer,
}

#[derive(Default)]
struct PendingCounts {
    cluster_count: Option<Vec<u8>>,
    raster_counts: Option<Vec<u8>>,
    second: Option<Vec<u8>>,
    hierarchy: Option<Vec<u8>>,
    second_walk: Option<Vec<u8>>,
    second_walk_list: Option<Vec<u8>>,
}

impl Renderer {
    /// Selects the adapter ([`meshlight::graph::AdapterOptions::from_env`]), builds the
    /// frame and compiles it for that adapter (which decides the device's features),
    /// opens the device and uploads the scene.
    pub fn new(data: SceneData, settings: FrameSettings, source: &GraphSource) -> Result<Self> {
        let adapter = GpuAdapter::select()?;
        settings.check_viewport(adapter.adapter.limits().max_texture_dimension_2d)?;
        let Frame {
            graph,
            pipeline,
            view,
        } = frame(source, &data, &settings)?;
        let compiled = graph.compile(&CompileOptions::for_adapter(&adapter))?;
        let gpu = adapter.open(compiled.plan.enabled_features)?;
        Ok(Self::on(gpu, data, settings, (pipeline, view), compiled))
    }

    /// A renderer on a host application's device ([`GpuContext::from_host`]): it creates
    /// its buffers, textures and pipelines there, records and submits on the host's
    /// queue, and opens no device or surface of its own. The device must have the
    /// features [`Self::required_features`] gives for its adapter; without them the
    /// error lists what to request.
    pub fn with_gpu(
        gpu: GpuContext,
        data: SceneData,
        settings: FrameSettings,
        source: &GraphSource,
    ) -> Result<Self> {
        settings.check_viewport(gpu.device.limits().max_texture_dimension_2d)?;
        let Frame {
            graph,
            pipeline,
            view,
        } = frame(source, &data, &settings)?;
        let compiled = match graph.compile(&CompileOptions::for_gpu(&gpu)) {
            Ok(compiled) => compiled,
            Err(GraphError::MissingFeature { .. }) => {
                let wanted = Self::required_features(&gpu.adapter, &settings)?;
                return Err(GraphError::DeviceLacksFeatures {
                    features: feature_names(wanted - gpu.features),
                    instead: "create the device with these among its `required_features`: `Renderer::required_features(&adapter, &settings)` gives them all".into(),
                });
            }
            Err(e) => return Err(e),
        };
        Ok(Self::on(gpu, data, settings, (pipeline, view), compiled))
    }

    /// The features the frame uses on `adapter` with `settings`: what a host requests
    /// when it creates the device it hands to [`Self::with_gpu`]. Planned without wgpu's
    /// experimental features (mesh shaders), which need the host's own opt-in; a device
    /// that has them lets `auto` pick them.
    pub fn required_features(
        adapter: &wgpu::Adapter,
        settings: &FrameSettings,
    ) -> Result<wgpu::Features> {
        let limits = adapter.limits();
        let data = SceneData::new(Limits::for_device(&limits));
        let frame = frame(&GraphSource::Shipped, &data, settings)?;
        let options = CompileOptions {
            adapter_features: adapter.features() - experimental_features(),
            limits,
            class: AdapterClass::of(&adapter.get_info()),
        };
        Ok(frame.graph.compile(&options)?.plan.enabled_features)
    }

    /// The limits to create a host's device with: the adapter's own. The scene's buffers
    /// are sized to the device's limits, so larger ones hold larger scenes; a device
    /// whose limits a frame exceeds is refused when the frame compiles, naming the limit.
    pub fn required_limits(adapter: &wgpu::Adapter) -> wgpu::Limits {
        adapter.limits()
    }

    /// The renderer on an open device, for a compiled frame.
    fn on(
        gpu: GpuContext,
        mut data: SceneData,
        settings: FrameSettings,
        (pipeline, view): (Pipeline, DebugView),
        compiled: CompiledGraph,
    ) -> Self {
        let limits = gpu.device.limits();
        let name = gpu.info.name.clone();
        let scene = GpuScene::new(&gpu, &mut data);
        let max_elements = limits
            .max_storage_buffer_binding_size
            .min(limits.max_buffer_size)
            / 8;
        let light_buffers = settings.clustering.as_ref().map(|c| LightBuffers {
            objects: gpu.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("objects"),
                size: c.objects.max(1) * size_of::<ClusterableObject>() as u64,
                usage: OBJECT_USAGE,
                mapped_at_creation: false,
            }),
            object_count: gpu.buffer_with_data("object_count", &[0; 4], OBJECT_USAGE),
        });
        let mut renderer = Self {
            data,
            settings,
            view,
            pipeline,
            two_pass: false,
            walks_hierarchy: false,
            walks_twice: false,
            occlusion: Adaptive::new(OcclusionPolicy::ALWAYS),
            second_pass: None,
            frame_plans: BTreeMap::new(),
            last_plan: FramePlan::FULL,
            cut: false,
            moved: Vec::new(),
            compiled,
            executor: Executor::new(gpu),
            scene,
            max_elements,
            frame_index: 0,
            previous_view_projection: None,
            pending: BTreeMap::new(),
            latest: None,
            growths: Vec::new(),
            adapter: name,
            lights: Vec::new(),
            light_buffers,
            clustering: Counters::new(max_elements * 2),
            imported_textures: Vec::new(),
            streaming: None,
            cascades: 0,
            shadow_counts: Vec::new(),
            shadow_cache: Default::default(),
            cascades_drawn: 0,
            sun: glam::Vec3::ZERO,
        };
        renderer.note_readbacks();
        renderer
    }

    /// Starts streaming a streamed scene's pages (`SceneData::streamed`): mesh `i`'s from
    /// `sources[i]`, within `budget`, read by `threads` threads. Until then, and for a
    /// scene that does not stream, frames are refused / unaffected.
    pub fn start_streaming(
        &mut self,
        sources: Vec<PageSource>,
        budget: Budget,
        threads: usize,
    ) -> Result<()> {
        let streaming = Streaming::new(&self.executor.gpu, &self.data, sources, budget, threads)?;
        self.streaming = Some(streaming);
        Ok(())
    }

    /// Frames of `camera` until streaming has settled: for [`SETTLED_FRAMES`] frames in a
    /// row no page the view wants is missing, being read or waiting to be installed.
    /// At most `max_frames`; returns the frames it took to get there, the quiet ones not
    /// counted (0 for a scene that does not stream).
    /// A still of a streamed scene renders after this, so that it shows what the pool
    /// holds for the view rather than the first frames' coarse cut.
    pub fn settle_streaming(&mut self, camera: &Camera, max_frames: u32) -> Result<u32> {
        if self.streaming.is_none() {
            return Ok(0);
        }
        let mut quiet = 0;
        for frame in 1..=max_frames {
            let submitted = self.frame(camera)?.frame;
            // Never more than the readback ring ahead of the GPU.
            if frame % 4 == 0 {
                meshlight::still::finish(&mut self.executor, submitted)?;
            }
            let s = self.streaming.as_ref().expect("checked above").stats();
            let busy = s.frame.requested > 0 || s.frame.in_flight > 0 || s.frame.installed > 0;
            // The first frames' requests are still on their way back.
            let heard = frame > super::streaming::REQUESTS_LATENCY + 1;
            quiet = if busy || !heard { 0 } else { quiet + 1 };
            if quiet == SETTLED_FRAMES {
                // The first of the quiet frames: when streaming had nothing left to do.
                return Ok(frame + 1 - SETTLED_FRAMES);
            }
        }
        log::warn!(
            "streaming had not settled after {max_frames} frames: {:?}",
            self.streaming.as_ref().map(|s| s.stats())
        );
        Ok(max_frames)
    }

    /// What the renderer keeps of a newly built frame: which counters come back, the
    /// shadow cascades (their maps made anew) and the sun they follow.
    fn note_readbacks(&mut self) {
        let has = |name: &str| {
            self.compiled
                .plan
                .pass_index(&format!("readback:{name}"))
                .is_some()
        };
        self.two_pass = has(SECOND_COUNTS_READBACK);
        self.walks_hierarchy = has(HIERARCHY_COUNTS_READBACK);
        self.walks_twice = has(SECOND_WALK_COUNT_READBACK);
        self.note_second_pass();
        self.cascades = match self.settings.shadows {
            Some(_) => (self.pipeline.views.get(super::shadows::CASCADES)).map_or(0, |&n| n),
            None => 0,
        };
        self.shadow_counts.clear();
        self.sun = self.sun_direction();
        let resolution = self.settings.shadows.map_or(0, |s| s.cascades.resolution);
        self.shadow_cache.reset(
            &self.executor.gpu,
            self.cascades,
            resolution,
            &self.pipeline,
        );
    }

    /// What a frame that does not test occlusion leaves out, and the policy that decides:
    /// the settings' where the frame's second pass can be left out on its own, else
    /// testing every frame. The `occlusion` view reads the second pass's counters every
    /// frame, so it tests every frame.
    fn note_second_pass(&mut self) {
        self.second_pass = match SecondPass::of(&self.compiled.plan, &self.pipeline) {
            _ if !self.two_pass || self.view.needs_occlusion_records() => None,
            Ok(pass) => Some(pass),
            Err(why) => {
                log::info!("occlusion is tested every frame: {why}");
                None
            }
        };
        let policy = match self.second_pass {
            Some(_) => self.settings.occlusion_policy,
            None => OcclusionPolicy::ALWAYS,
        };
        self.occlusion = Adaptive::new(policy);
    }

    /// Whether the frames test occlusion now: `false` while a two-pass frame leaves its
    /// second pass out because occlusion culled too little to pay
    /// ([`FrameSettings::occlusion_policy`]).
    pub fn tests_occlusion(&self) -> bool {
        self.two_pass && self.occlusion.testing()
    }

    /// Whether the frame culls in two passes (its graph has a second culling pass), so
    /// that it may test occlusion.
    pub fn culls_in_two_passes(&self) -> bool {
        self.two_pass
    }

    /// What the last frame ran of a two-pass frame (the whole of it in a one-pass frame).
    pub fn last_frame_plan(&self) -> FramePlan {
        self.last_plan
    }

    /// The shadow cascades' maps (`cascades × resolution²` reverse-Z depth bits, cascade
    /// after cascade), as the last frame left them; `None` without shadows.
    pub fn shadow_maps(&self) -> Option<&wgpu::Buffer> {
        self.shadow_cache.maps()
    }

    /// The direction towards the sun: the first `resolve` pass's `light_direction`, or
    /// the resolve's default.
    pub fn sun_direction(&self) -> glam::Vec3 {
        let default = meshlight::resolve::settings::Settings::default().light_direction;
        (self.pipeline.passes_of(meshlight::resolve::STAGE).next())
            .and_then(|r| r.param("light_direction"))
            .and_then(|v| v.as_array())
            .and_then(|a| {
                let f: Vec<f32> = a
                    .iter()
                    .filter_map(|x| x.as_float().or(x.as_integer().map(|i| i as f64)))
                    .map(|x| x as f32)
                    .collect();
                (f.len() == 3).then(|| glam::Vec3::new(f[0], f[1], f[2]))
            })
            .unwrap_or(default)
    }

    /// Records and submits one frame seen by `camera`; never waits for the GPU. Counters
    /// of earlier frames that have come back are taken, and a list that overflowed is
    /// grown for the next frame.
    pub fn frame(&mut self, camera: &Camera) -> Result<FrameStats> {
        self.run_frame(camera, Imports::new())
    }

    /// [`Self::frame`] into a host's targets (the renderer made with
    /// [`FrameSettings::host`]): the image drawn into `color` (the texture of the format
    /// the settings named, at the frame's size, with `RENDER_ATTACHMENT`), and with a
    /// depth target, the scene's reverse-Z depth into `depth` (`Depth32Float`), ready
    /// for the host's own geometry to be drawn over with `LoadOp::Load` and a
    /// `Greater` depth test. Submitted on the host's queue before this returns, so
    /// whatever the host submits next sees it.
    pub fn draw(
        &mut self,
        camera: &Camera,
        color: &wgpu::Texture,
        depth: Option<&wgpu::Texture>,
    ) -> Result<FrameStats> {
        let Some(host) = self.settings.host else {
            return Err(GraphError::Setting {
                setting: "FrameSettings::host".into(),
                message: "the renderer was made without host targets; set `FrameSettings::host` to the formats of the textures `draw` is given".into(),
            });
        };
        if host.depth != depth.is_some() {
            return Err(GraphError::Setting {
                setting: "FrameSettings::host.depth".into(),
                message: format!(
                    "the renderer was made {} a host depth target but `draw` was given {}; give a depth texture exactly when `host.depth` is set",
                    if host.depth { "with" } else { "without" },
                    if depth.is_some() { "one" } else { "none" }
                ),
            });
        }
        let mut imports = Imports::new().texture(HOST_TARGET, color);
        if let Some(depth) = depth {
            imports = imports.texture(DEPTH, depth);
        }
        self.run_frame(camera, imports)
    }

    fn run_frame(&mut self, camera: &Camera, extra: Imports) -> Result<FrameStats> {
        let viewport = [self.settings.width, self.settings.height];
        let mut view = camera.view(viewport, self.frame_index, self.previous_view_projection);
        self.previous_view_projection = Some(Mat4::from_cols_array_2d(&view.view_projection));
        match &mut self.streaming {
            Some(streaming) => {
                streaming.before_frame(
                    &mut self.executor,
                    &mut self.data,
                    u64::from(self.frame_index) + 1,
                )?;
                // Pool pressure coarsens the cut: errors look smaller by its scale.
                view.lod_scale /= streaming.lod_scale();
            }
            None if self.data.streaming().is_some() => {
                return Err(GraphError::Setting {
                    setting: "streaming".into(),
                    message: "the scene streams, but no page source was given: call `Renderer::start_streaming` before the first frame".into(),
                });
            }
            None => {}
        }
        let shadows = match self.settings.shadows.filter(|_| self.cascades > 0) {
            Some(settings) => Some(super::shadows::ShadowFrame::new(
                camera,
                viewport,
                self.sun,
                &settings,
                self.frame_index,
                self.streaming.as_ref().map_or(1.0, |s| s.lod_scale()),
            )?),
            None => None,
        };
        self.frame_index = self.frame_index.wrapping_add(1);
        let upload = std::time::Instant::now();
        let uploaded = self.scene.upload(&self.executor.gpu, &mut self.data);
        if let Some(streaming) = &mut self.streaming {
            streaming.add_upload_time(upload.elapsed());
        }
        let plan = self.occlusion.next_frame(std::mem::take(&mut self.cut));
        let cut = u32::from(!plan.test);
        let mut frame = FrameData::new()
            .with(meshlight::gpu_scene::names::VIEW, bytemuck::bytes_of(&view))
            .with(meshlight::cull_lod::CAMERA_CUT_INPUT, &cut.to_le_bytes());
        if let Some(shadows) = &shadows {
            frame = shadows.add_to(frame);
            // Anything the GPU scene took this frame (a transform, a material, pages
            // installed or evicted) may change a shadow.
            let streamed = self.streaming.as_ref().is_some_and(|s| {
                let f = s.stats().frame;
                f.installed > 0 || f.evicted > 0
            });
            let changed = uploaded.bytes > 0 || streamed;
            let cache = self.settings.shadows.is_some_and(|s| s.cache);
            self.cascades_drawn = self
                .shadow_cache
                .skip_unchanged(shadows, changed, cache, &view, &mut frame);
        }
        if let Some(second) = &self.second_pass {
            if !plan.second {
                for name in &second.passes {
                    frame.skip(name);
                }
            }
            if !plan.pyramid {
                frame.skip(&second.pyramid);
            }
        }
        let mut imports = self.scene.imports().merge(extra);
        if let Some(streaming) = &self.streaming {
            imports = streaming.imports(imports);
        }
        if let Some(b) = &self.light_buffers {
            let limit = self.settings.clustering.as_ref().map_or(0, |c| c.objects);
            if self.lights.len() as u64 > limit {
                return Err(GraphError::Setting {
                    setting: "FrameSettings::clustering.objects".into(),
                    message: format!(
                        "{} lights, but the object buffer holds {limit}; raise `FrameSettings::clustering.objects` (`--lights` sizes it) or use fewer",
                        self.lights.len()
                    ),
                });
            }
            let queue = &self.executor.gpu.queue;
            if !self.lights.is_empty() {
                queue.write_buffer(&b.objects, 0, bytemuck::cast_slice(&self.lights));
            }
            queue.write_buffer(
                &b.object_count,
                0,
                &(self.lights.len() as u32).to_le_bytes(),
            );
            imports = imports
                .buffer("objects", &b.objects)
                .buffer("object_count", &b.object_count);
        }
        for (name, texture) in &self.imported_textures {
            imports = imports.texture(name, texture);
        }
        if let Some(maps) = self.shadow_cache.maps() {
            imports = imports.buffer(meshlight::resolve::shadows::SHADOW_MAPS, maps);
        }
        let stats = self
            .executor
            .execute_frame(&self.compiled, &imports, &frame)?;
        self.last_plan = plan;
        self.frame_plans.insert(stats.frame, plan);
        self.settle_previous_transforms();
        self.take_counts()?;
        Ok(stats)
    }

    /// Tells the next frame that its camera does not continue the last one's (a jump, a
    /// new shot): its first culling pass then tests nothing against last frame's depth.
    pub fn camera_cut(&mut self) {
        self.cut = true;
    }

    /// Moves an instance (see `SceneData::set_transform`) and remembers it, so that
    /// after the next frame its previous transform becomes the one that frame drew it
    /// with. Moving it through `data` directly works too, but its previous transform then
    /// stays where it was before, and the first culling pass of later frames projects it
    /// there: never a wrong image (the second pass re-tests with the current transform),
    /// only work moved to the second pass.
    pub fn set_transform(
        &mut self,
        id: meshlight::gpu_scene::InstanceId,
        world_from_local: Mat4,
    ) -> std::result::Result<bool, meshlight::gpu_scene::SceneDataError> {
        let moved = self.data.set_transform(id, world_from_local)?;
        if moved {
            self.moved.push(id);
        }
        Ok(moved)
    }

    /// After a frame, the instances moved before it get the transform it drew them with
    /// as their previous one (uploaded by the next frame).
    fn settle_previous_transforms(&mut self) {
        for id in std::mem::take(&mut self.moved) {
            let now = &self.data.instances[id.0 as usize].world_from_local;
            let now = Mat4::from_cols_array_2d(now);
            // The transform was drawable when it was set, so this cannot be refused.
            let _ = self.data.set_transform(id, now);
        }
    }

    /// The clusters the last frame rasterised, read back from the GPU's slot list: both
    /// rasterisers' slots of the first culling pass, and of the second where the frame
    /// has one. Waits for the GPU (a debug readback, for tests and tools that check the
    /// drawn cut, e.g. with `meshlight::stream::cut::check`); needs a renderer made
    /// with [`FrameSettings::keep_visibility`]. With occlusion on, the clusters the
    /// second pass culled are not among them.
    pub fn drawn_clusters(&mut self) -> Result<Vec<meshlight::shaders::cpu::layout::Cluster>> {
        let words = |r: &mut Self, name: &str| -> Result<Vec<u32>> {
            Ok(bytemuck::pod_collect_to_vec(&r.executor.read_buffer(name)?))
        };
        let slots: Vec<meshlight::shaders::cpu::layout::Cluster> =
            bytemuck::pod_collect_to_vec(&self.executor.read_buffer("raster_clusters")?);
        let mut drawn = Vec::new();
        // Per pass: software slots from [7] up, [0] of them; hardware ones from [3]
        // down, [1] of them (`cull_lod`'s counters; [7] is 0 without occlusion).
        let mut take = |counts: &[u32]| {
            let software = counts[7] as usize..(counts[7] + counts[0]) as usize;
            let hardware = counts[3].saturating_sub(counts[1]) as usize..counts[3] as usize;
            for range in [software, hardware] {
                drawn.extend_from_slice(slots.get(range).unwrap_or_default());
            }
        };
        let mut first = words(self, "raster_counts")?;
        // `prepare` zeroes words 0..8 in every mode.
        first.resize(first.len().max(8), 0);
        take(&first);
        if self.two_pass && self.last_plan.second {
            take(&words(self, SECOND_COUNTS)?);
        }
        Ok(drawn)
    }

    /// The newest frame whose counters are back.
    pub fn latest_counts(&self) -> Option<FrameCounts> {
        self.latest
    }

    /// Renders until a frame drops no cluster (at most [`MAX_STILL_FRAMES`]), waiting for
    /// each, and returns that frame's image, statistics and counters. The `occlusion`
    /// view of a two-pass frame first renders one frame more when nothing was rendered
    /// yet, so the image shows what the frame culls against its own history rather than
    /// a first frame, which has none.
    pub fn render_still(&mut self, camera: &Camera) -> Result<Still> {
        if self.two_pass && self.view.needs_occlusion_records() && self.frame_index == 0 {
            let submitted = self.frame(camera)?.frame;
            meshlight::still::finish(&mut self.executor, submitted)?;
            self.take_counts()?;
        }
        let mut attempt = 0;
        loop {
            attempt += 1;
            let submitted = self.frame(camera)?.frame;
            let stats = meshlight::still::finish(&mut self.executor, submitted)?;
            self.take_counts()?;
            let counts = meshlight::still::counters_of(self.latest, |c| c.frame, submitted)?;
            let lights_lost = self.settings.clustering.is_some()
                && self
                    .clustering
                    .latest
                    .is_none_or(|c| c.frame != submitted || c.overflowed());
            if !(counts.overflowed() || lights_lost) || attempt == MAX_STILL_FRAMES {
                if counts.overflowed() {
                    log::error!(
                        "frame {submitted} still drops clusters after {attempt} frames: {counts:?}"
                    );
                }
                let rgba = self.executor.read_texture("color")?;
                return Ok(Still {
                    width: self.settings.width,
                    height: self.settings.height,
                    rgba,
                    stats,
                    counts,
                    frames: attempt,
                });
            }
        }
    }

    /// Takes every readback that has come back; grows the lists for frames that
    /// overflowed.
    fn take_counts(&mut self) -> Result<()> {
        if self.settings.clustering.is_some() {
            self.clustering
                .take(&mut self.executor, &mut self.compiled)?;
        }
        let mut names = vec![CLUSTER_COUNT_READBACK, RASTER_COUNTS_READBACK];
        if self.two_pass {
            names.push(SECOND_COUNTS_READBACK);
        }
        if self.walks_hierarchy {
            names.push(HIERARCHY_COUNTS_READBACK);
        }
        if self.walks_twice {
            names.extend([SECOND_HIERARCHY_COUNTS_READBACK, SECOND_WALK_COUNT_READBACK]);
        }
        // A frame leaves its second pass's readbacks out while it does not test
        // occlusion, so they may not have run yet.
        names.retain(|n| self.executor.readback_has_run(n));
        for name in names {
            while let Some(r) = self.executor.take_readback(name)? {
                let entry = self.pending.entry(r.frame).or_default();
                let part = match name {
                    CLUSTER_COUNT_READBACK => &mut entry.cluster_count,
                    RASTER_COUNTS_READBACK => &mut entry.raster_counts,
                    HIERARCHY_COUNTS_READBACK => &mut entry.hierarchy,
                    SECOND_HIERARCHY_COUNTS_READBACK => &mut entry.second_walk,
                    SECOND_WALK_COUNT_READBACK => &mut entry.second_walk_list,
                    _ => &mut entry.second,
                };
                *part = Some(r.bytes);
            }
        }
        let (walks, plans) = (self.walks_hierarchy, &self.frame_plans);
        // A frame that left its second pass out has none of its counters.
        let second = |frame: &u64| plans.get(frame).is_none_or(|p| p.second);
        let two_pass = |frame: &u64| self.two_pass && second(frame);
        let twice = |frame: &u64| self.walks_twice && second(frame);
        let complete: Vec<u64> = self
            .pending
            .iter()
            .filter(|(f, p)| {
                p.cluster_count.is_some()
                    && p.raster_counts.is_some()
                    && (p.second.is_some() || !two_pass(f))
                    && (p.hierarchy.is_some() || !walks)
                    && (p.second_walk.is_some() && p.second_walk_list.is_some() || !twice(f))
            })
            .map(|(f, _)| *f)
            .collect();
        for frame in complete {
            let p = self.pending.remove(&frame).expect("listed above");
            let short = || GraphError::Readback(format!("frame {frame}'s counters are short"));
            let mut counts = FrameCounts::from_words(
                frame,
                p.cluster_count.as_deref().unwrap_or_default(),
                p.raster_counts.as_deref().unwrap_or_default(),
                p.second.as_deref(),
            )
            .ok_or_else(short)?;
            if let Some(bytes) = &p.hierarchy {
                let mut h = HierarchyCounts::from_words(bytes).ok_or_else(short)?;
                if let (Some(c), Some(l)) = (&p.second_walk, &p.second_walk_list) {
                    h = h.with_second(c, l).ok_or_else(short)?;
                }
                counts.hierarchy = Some(h);
            }
            if let Some(plan) = self.frame_plans.remove(&frame) {
                self.occlusion.observe(plan, &counts);
            }
            self.grow_for(&counts)?;
            if self.latest.is_none_or(|l| l.frame < frame) {
                self.latest = Some(counts);
            }
        }
        // A frame whose other half never comes (dropped by a full ring) is forgotten.
        while self.pending.len() > 16 {
            self.pending.pop_first();
        }
        while self.frame_plans.len() > 64 {
            self.frame_plans.pop_first();
        }
        self.take_shadow_counts()
    }

    /// Takes each cascade's counters that have come back, and grows the shared lists
    /// for a cascade that overflowed them.
    fn take_shadow_counts(&mut self) -> Result<()> {
        use super::shadows::{
            CANDIDATES_PARAM, CLUSTER_COUNTS, CascadeCounts, RASTER_COUNTS, view_name,
        };
        if self.cascades == 0 {
            return Ok(());
        }
        let mut fill = None;
        while let Some(r) = self.executor.take_readback(CLUSTER_COUNTS)? {
            fill = Some(r);
        }
        let Some(fill) = fill else {
            return Ok(());
        };
        for k in 0..self.cascades {
            let mut cull = None;
            while let Some(r) = self.executor.take_readback(&view_name(RASTER_COUNTS, k))? {
                cull = Some(r);
            }
            let Some(cull) = cull else {
                continue;
            };
            let counts = CascadeCounts::from_words(k, cull.frame, &cull.bytes, &fill.bytes)
                .ok_or_else(|| GraphError::Readback(format!("cascade {k}'s counters are short")))?;
            // The lists lie side by side, one a cascade (and the camera's when it walks
            // them): each as long as the longest asks.
            let lists = super::shadows::list_count(&self.pipeline, self.cascades);
            let cascades = u64::from(lists);
            for (param, wanted, limit, flag) in [
                (
                    CANDIDATES_PARAM,
                    u64::from(counts.candidates_requested) * cascades,
                    self.max_elements,
                    "--clusters",
                ),
                (
                    SLOTS_PARAM,
                    u64::from(counts.visible),
                    self.max_elements.min(MAX_SLOTS),
                    "--slots",
                ),
            ] {
                let want = Want {
                    frame: counts.frame,
                    param,
                    wanted,
                    limit,
                    when_full: "shadow casters are dropped (raise the shadow LOD bias or shorten the shadow distance)",
                    also_set_by: flag,
                };
                self.growths.extend(grow(&mut self.compiled, want)?);
            }
            match self.shadow_counts.iter_mut().find(|c| c.cascade == k) {
                Some(c) => *c = counts,
                None => self.shadow_counts.push(counts),
            }
        }
        Ok(())
    }

    /// Raises `clusters` or `slots` to the next power of two above what `counts` asked
    /// for, when it asked for more than the list holds.
    fn grow_for(&mut self, counts: &FrameCounts) -> Result<()> {
        let wants = [
            (
                CLUSTERS_PARAM,
                // The second walk's list is sized by the same parameter.
                (counts.clusters_requested as u64).max(
                    counts
                        .hierarchy
                        .and_then(|h| h.second)
                        .map_or(0, |w| w.clusters_requested as u64),
                ),
                self.max_elements,
                "--clusters",
            ),
            (
                SLOTS_PARAM,
                counts.visible as u64,
                self.max_elements.min(MAX_SLOTS),
                "--slots",
            ),
        ];
        for (param, wanted, limit, flag) in wants {
            let want = Want {
                frame: counts.frame,
                param,
                wanted,
                limit,
                when_full: "clusters are dropped (raise the LOD threshold or draw fewer instances)",
                also_set_by: flag,
            };
            self.growths.extend(grow(&mut self.compiled, want)?);
        }
        Ok(())
    }

    /// The current value of a size parameter.
    pub fn param(&self, name: &str) -> u64 {
        param_value(&self.compiled, name)
    }

    /// The LOD threshold and the software/hardware split the first culling pass uses,
    /// in pixels (an `auto` split resolved for the adapter's class).
    pub fn thresholds(&self) -> (f32, f32) {
        let defaults = meshlight::cull_lod::Thresholds::default();
        let cull = self.pipeline.passes_of(meshlight::cull_lod::STAGE).next();
        let number = |key: &str| {
            cull.and_then(|c| c.param(key)).and_then(|v| match v {
                toml::Value::Float(f) => Some(*f as f32),
                toml::Value::Integer(i) => Some(*i as f32),
                _ => None,
            })
        };
        let auto = cull.and_then(|c| c.param_str("sw_threshold_px")) == Some("auto");
        let sw = if auto {
            meshlight::cull_lod::sw_threshold_on(self.compiled.plan.class).0
        } else {
            number("sw_threshold_px").unwrap_or(defaults.sw_threshold_px)
        };
        (
            number("lod_threshold_px").unwrap_or(defaults.lod_threshold_px),
            sw,
        )
    }
}

/// Changing the frame while it runs: a window resized, an implementation or a threshold
/// chosen, a pipeline file edited. The device, the scene and the pipelines already made
/// stay; only the graph is built and compiled again.
impl Renderer {
    /// Builds the graph from `source` with `settings` (`extend` may add passes and
    /// resources of the caller's, e.g. a copy of `color` into a window's texture) and
    /// compiles it for the open device. On any error the renderer keeps its current
    /// graph, so a caller can show the error and go on rendering. The lists keep the sizes
    /// they grew to; the next frame is a camera cut (the history belongs to the old graph).
    pub fn rebuild(
        &mut self,
        source: &GraphSource,
        mut settings: FrameSettings,
        extend: &dyn Fn(&mut meshlight::graph::GraphBuilder, &FrameSettings) -> Result<()>,
    ) -> Result<()> {
        let gpu = &self.executor.gpu;
        settings.check_viewport(gpu.device.limits().max_texture_dimension_2d)?;
        // The lists keep what they grew to.
        for (size, param) in [
            (&mut settings.clusters, CLUSTERS_PARAM),
            (&mut settings.slots, SLOTS_PARAM),
        ] {
            if let Some(now) = self.compiled.param(param) {
                *size = Some(size.map_or(now, |asked| asked.max(now)));
            }
        }
        let frame = frame(source, &self.data, &settings)?;
        let mut graph = frame.graph;
        extend(&mut graph, &settings)?;
        let compiled = graph.compile(&CompileOptions::for_gpu(gpu))?;
        let missing = compiled.plan.enabled_features - gpu.features;
        if !missing.is_empty() {
            return Err(GraphError::DeviceLacksFeatures {
                features: feature_names(missing),
                instead:
                    "the device was opened for the first graph; start with this choice instead"
                        .into(),
            });
        }
        self.compiled = compiled;
        self.settings = settings;
        self.view = frame.view;
        self.pipeline = frame.pipeline;
        self.note_readbacks();
        self.pending.clear();
        self.latest = None;
        self.previous_view_projection = None;
        self.cut = true;
        Ok(())
    }

    /// Gives `texture` to every frame as the imported resource `name` (replacing one of
    /// that name), for passes a caller added through [`Renderer::rebuild`].
    pub fn import_texture(&mut self, name: &str, texture: &wgpu::Texture) {
        self.imported_textures.retain(|(n, _)| n != name);
        self.imported_textures
            .push((name.to_string(), texture.clone()));
    }
}
