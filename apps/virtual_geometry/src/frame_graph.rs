//! The virtual-geometry frame as a graph: built in code ([`build`]) or loaded from a
//! pipeline file ([`load`]); both declare the same resources under the same names, so a
//! file a user edits renders with the same renderer.
//!
//! With occlusion (the default), two culling passes (docs/ARCHITECTURE.md, "Two-pass
//! occlusion culling"):
//!
//! ```text
//! fill → cull (first, last frame's pyramid) → remap → sw_raster → hw_raster
//!      → depth_pyramid → cull_second (the first's candidates, this frame's pyramid)
//!      → remap_second → sw_raster_second → hw_raster_second → resolve
//!      → depth_pyramid (history for the next frame)
//! ```
//!
//! Both rasterisations accumulate into one visibility target and one slot list, so a
//! visibility id means the same to resolve whichever pass drew it: the second software
//! pass (`accumulate`) keeps the target and draws the slots `cull_second` put after the
//! first pass's software clusters; the second hardware pass draws the slots below the
//! first's hardware clusters.

use super::counts::{
    CLUSTER_COUNT_READBACK, HIERARCHY_COUNTS_READBACK, RASTER_COUNTS_READBACK,
    SECOND_COUNTS_READBACK, SECOND_HIERARCHY_COUNTS_READBACK, SECOND_WALK_COUNT_READBACK,
};
use meshlight::cull_lod::{
    CullLod, OCCLUSION_COUNT_WORDS, PER_INSTANCE_FIRST, PER_INSTANCE_SECOND, Thresholds,
    WALKED_COUNT_SLOT, WALKED_SLOT,
};
use meshlight::fill_clusters::hierarchy::{ENTRY_COUNT_WORDS, OCCLUSION_MIN_CLUSTERS};
use meshlight::fill_clusters::{FillClusters, HIDDEN_NODE, HierarchyFill};
use meshlight::gpu_scene::Phase;
use meshlight::gpu_scene::gpu::{
    buffer_lengths, elements, hierarchy_lengths, import_for, import_hierarchy_for,
};
use meshlight::gpu_scene::{SceneData, names};
use meshlight::graph::file::{AUTO, Registry};
use meshlight::graph::{
    Bindings, BufferDesc, Choice, Element, GraphBuilder, GraphError, Result, TextureDesc,
};
use meshlight::remap_dispatch::RemapDispatch;
use meshlight::resolve::{DebugView, OCCLUDED_PER_INSTANCE, Resolve};
use meshlight_light_clustering::ClusteringSettings;
use meshlight_light_clustering::frame_graph as clustering;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// Size parameter: candidate clusters the per-frame list holds.
pub const CLUSTERS_PARAM: &str = "clusters";
/// Size parameter: raster slots (clusters in the LOD cut) one frame holds.
pub const SLOTS_PARAM: &str = "slots";
/// A visibility id has 25 bits for the slot: more slots could not be told apart.
pub const MAX_SLOTS: u64 = 1 << 25;
/// How many frames later the counters come back to the CPU.
pub const COUNTS_LATENCY: u32 = 2;
/// The history resource holding the frame's final depth pyramid, read by the next
/// frame's first culling pass as `pyramid_history.prev`.
pub const PYRAMID_HISTORY: &str = "pyramid_history";
/// Resources of the two-pass frame, named unlike `cull_lod`'s slots so that each pass
/// binds them where the frame says (a slot binds a same-named resource by default).
pub const CANDIDATES: &str = "candidates";
pub const CANDIDATE_COUNT: &str = "candidate_count";
pub const SECOND_COUNTS: &str = "raster_counts_second";
pub const SECOND_HW_ARGS: &str = "hw_args_second";
pub const SECOND_SW_ARGS: &str = "sw_args_second";
/// The per-instance occlusion counters (two words per instance), created only for the
/// `occlusion` view: the first cull clears and fills them, the second updates them,
/// resolve reads them (named unlike all three slots).
pub const INSTANCE_OCCLUSION: &str = "instance_occlusion";
/// Resources of the two walks of the hierarchy: the nodes the first walk found hidden
/// (three words each) and their count, the second walk's cluster list and count, and its
/// counters; each named unlike the slots it is bound to.
pub const HIDDEN_NODES: &str = "hidden_nodes";
pub const HIDDEN_NODE_COUNT: &str = "hidden_node_count";
pub const SECOND_WALK_CLUSTERS: &str = "second_walk_clusters";
pub const SECOND_WALK_COUNT: &str = "second_walk_count";
pub const SECOND_HIERARCHY_COUNTS: &str = "hierarchy_counts_second";
/// Size parameter: entries of [`HIDDEN_NODES`]. A full list costs no correctness (the
/// first walk then walks on below the node), only pruning.
pub const HIDDEN_NODES_PARAM: &str = "hidden_nodes";

/// [`HIDDEN_NODES_PARAM`] for a scene: room for every instance's root and then some,
/// within 4 Mi entries (48 MiB).
pub fn hidden_node_capacity(instances: usize) -> u64 {
    (instances as u64 * 4).clamp(1 << 16, 1 << 22)
}

/// What a frame is asked for; the same for both ways of building the graph.
#[derive(Clone, Debug, PartialEq)]
pub struct FrameSettings {
    pub width: u32,
    pub height: u32,
    pub view: DebugView,
    /// With a pipeline file, leave the `view` its `resolve` passes name (the renderer then
    /// takes `view` from the file); off, every `resolve` pass shows `view`. A command
    /// line sets it when no view was asked for, so the file's own choice stands. The
    /// frame built in code always shows `view`.
    pub keep_file_view: bool,
    /// Screen-space error (pixels) the LOD cut may show.
    pub lod_threshold_px: f32,
    /// Screen-box size under which a cluster is rasterised in software; `None`: the
    /// adapter class's default ([`super::split::AdapterClass::sw_threshold_px`]).
    pub sw_threshold_px: Option<f32>,
    /// `sw_raster`'s implementation: `auto` (texture atomics where the adapter has
    /// them), `texture` or `buffer`.
    pub sw_raster: String,
    /// `hw_raster`'s implementation: `auto` (the first of the adapter class's
    /// [`super::split::AdapterClass::hardware_feeds`] the adapter runs), `mesh_shader`
    /// or `indirect_draw`.
    pub hw_raster: String,
    /// The adapter's class, which orders `auto`'s candidates; the renderer sets it.
    /// `None`: mesh shaders first.
    pub adapter_class: Option<super::split::AdapterClass>,
    /// `Some(false)`: no `hw_raster` pass; culling sends every cluster to software,
    /// which clips those crossing the near plane. `None`: with a split given, the pass
    /// is there; else the adapter class decides
    /// ([`super::split::AdapterClass::hardware_raster`]; the environment variable
    /// `MESHLIGHT_HARDWARE_RASTER=on|off` sets it, for sweeps). A graph built without a
    /// renderer has the pass.
    pub hardware: Option<bool>,
    /// Initial candidate-list and raster-slot sizes; the renderer grows them on
    /// overflow.
    pub clusters: u64,
    pub slots: u64,
    /// With a pipeline file, leave the `clusters` and `slots` its `[params]` give
    /// (each one the file declares); off, `clusters` and `slots` above win. A command
    /// line sets it for the lists no flag sized, as [`FrameSettings::keep_file_view`].
    pub keep_file_lists: KeepFileLists,
    /// Resolve the `depth` and `material_depth` targets: a fullscreen fragment pass
    /// each, which only a frame compositing raster geometry over the image needs. Off
    /// by default: the frame resolves colour alone, in one compute dispatch.
    pub depth: bool,
    pub material_depth: bool,
    /// The software rasteriser divides exactly in integers (bit-exact on every driver,
    /// slower); see `SwRaster::exact_division`.
    pub exact_division: bool,
    /// Cluster the renderer's lights and shade with them (the graph built in code only).
    pub clustering: Option<ClusteringSettings>,
    /// Keep the visibility target (`visbuffer`), the slot list (`raster_clusters`) and
    /// the culling passes' counters (`raster_counts`, `raster_counts_second`) after the
    /// frame, for `Executor::read_buffer` (tests, debugging).
    pub keep_visibility: bool,
    /// Two-pass occlusion culling against the depth pyramid. Off: one pass, everything
    /// in the LOD cut drawn.
    pub occlusion: bool,
    /// `fill` walks each visible instance's culling hierarchy (the frustum and LOD tested
    /// per node), so only clusters that may be in the LOD cut become candidates. Off:
    /// every cluster of every instance in view is a candidate (`workgroup_per_instance`).
    pub hierarchy: bool,
    /// With both, the walk tests a node against the pyramid only when it has at least
    /// this many meshlets below (`HierarchyFill::occlusion_min_clusters`; the
    /// environment variable `MESHLIGHT_OCCLUSION_MIN_CLUSTERS` sets it, for sweeps).
    pub occlusion_min_clusters: u32,
    /// `sw_raster`'s `big_triangle_px`: triangles whose box is this many pixels wide or
    /// tall are covered a tile per workgroup (0: by their thread). The environment
    /// variable `MESHLIGHT_BIG_TRIANGLE_PX` sets it, for sweeps.
    pub big_triangle_px: u32,
}

impl FrameSettings {
    pub fn new(width: u32, height: u32) -> Self {
        let t = Thresholds::default();
        Self {
            width,
            height,
            view: DebugView::Shaded,
            keep_file_view: false,
            keep_file_lists: KeepFileLists::default(),
            lod_threshold_px: t.lod_threshold_px,
            // `MESHLIGHT_SW_THRESHOLD_PX` overrides the adapter class's split, for sweeps.
            sw_threshold_px: std::env::var("MESHLIGHT_SW_THRESHOLD_PX")
                .ok()
                .and_then(|v| v.parse().ok()),
            sw_raster: AUTO.into(),
            hw_raster: AUTO.into(),
            adapter_class: None,
            hardware: std::env::var("MESHLIGHT_HARDWARE_RASTER")
                .ok()
                .and_then(|v| match v.as_str() {
                    "on" | "1" | "true" => Some(true),
                    "off" | "0" | "false" => Some(false),
                    _ => None,
                }),
            clusters: 1 << 20,
            slots: 1 << 18,
            depth: false,
            material_depth: false,
            exact_division: false,
            clustering: None,
            occlusion: true,
            hierarchy: true,
            occlusion_min_clusters: std::env::var("MESHLIGHT_OCCLUSION_MIN_CLUSTERS")
                .ok()
                .and_then(|v| v.parse().ok())
                .unwrap_or(OCCLUSION_MIN_CLUSTERS),
            big_triangle_px: std::env::var("MESHLIGHT_BIG_TRIANGLE_PX")
                .ok()
                .and_then(|v| v.parse().ok())
                .unwrap_or(meshlight::sw_raster::BIG_TRIANGLE_PX),
            keep_visibility: false,
        }
    }

    /// Whether the frame built in code culls by occlusion.
    pub fn two_pass(&self) -> bool {
        self.occlusion
    }

    /// Whether this frame has a hardware rasteriser on an adapter of `class`: as set,
    /// else with a split given (it asks for both rasterisers), else the class's choice.
    pub fn hardware_on(&self, class: super::split::AdapterClass) -> bool {
        self.hardware
            .unwrap_or_else(|| self.sw_threshold_px.is_some() || class.hardware_raster().0)
    }

    /// Whether the graph has a `hw_raster` pass (the class's choice filled in by the
    /// renderer; with none, it has).
    pub fn has_hardware(&self) -> bool {
        self.hardware.unwrap_or(true)
    }

    /// The split threshold this frame uses on an adapter of `class`.
    pub fn sw_threshold_on(&self, class: super::split::AdapterClass) -> f32 {
        self.sw_threshold_px
            .unwrap_or_else(|| class.sw_threshold_px().0)
    }

    /// A viewport of 0, or past the device's 2-D texture limit, named with what to do.
    pub fn check_viewport(&self, max_dimension: u32) -> Result<()> {
        let (w, h) = (self.width, self.height);
        if w == 0 || h == 0 || w > max_dimension || h > max_dimension {
            return Err(GraphError::Setting {
                setting: "the viewport".into(),
                message: format!(
                    "the viewport {w} × {h} must be at least 1 × 1 and at most {max_dimension} on each side (this device's 2-D texture limit); change --width/--height"
                ),
            });
        }
        Ok(())
    }
}

/// Where the frame graph comes from.
#[derive(Clone, Debug)]
pub enum GraphSource {
    /// [`build`]: the stages wired in Rust.
    Code,
    /// [`load`]: a pipeline file, its stages from [`meshlight::registry`].
    File(PathBuf),
    /// A pipeline file whose stages come from the registry the function returns: the
    /// built-in one with the caller's own implementations registered, e.g.
    /// `|| { let mut r = meshlight::registry(); r.register(STAGE, "mine", Mine::from_params); r }`.
    FileWith(PathBuf, fn() -> Registry),
}

impl GraphSource {
    pub fn graph(&self, data: &SceneData, settings: &FrameSettings) -> Result<GraphBuilder> {
        match self {
            GraphSource::Code => build(data, settings),
            GraphSource::File(path) => load_with(path, data, settings, &meshlight::registry()),
            GraphSource::FileWith(path, registry) => load_with(path, data, settings, &registry()),
        }
    }
}

/// The frame built in code: the scene imported, the lists transient and sized by the
/// [`CLUSTERS_PARAM`] and [`SLOTS_PARAM`] parameters, depth, material depth and colour
/// exported, the counters read back.
pub fn build(data: &SceneData, s: &FrameSettings) -> Result<GraphBuilder> {
    let mut g = GraphBuilder::new();
    g.size_param(CLUSTERS_PARAM, s.clusters);
    g.size_param(SLOTS_PARAM, s.slots.min(MAX_SLOTS));
    import_for(data, &mut g);
    let occlusion = s.two_pass();
    let count_words = if occlusion { OCCLUSION_COUNT_WORDS } else { 8 };
    for (name, desc) in [
        (
            "clusters",
            BufferDesc::array_param(elements::CLUSTER, CLUSTERS_PARAM),
        ),
        ("cluster_count", BufferDesc::array(Element::U32, 2)),
        (
            "raster_clusters",
            BufferDesc::array_param(elements::CLUSTER, SLOTS_PARAM),
        ),
        (
            "raster_counts",
            BufferDesc::array(Element::U32, count_words),
        ),
        ("hw_args", BufferDesc::array(Element::DRAW_ARGS, 1)),
        ("sw_args", BufferDesc::array(Element::DISPATCH_ARGS, 1)),
    ] {
        g.create_buffer(name, desc);
    }
    // A u64 buffer or an R64Uint texture, as the chosen software rasteriser writes it.
    let visbuffer = g.create_visibility64("visbuffer", s.width, s.height);
    let depth = meshlight::resolve::DEPTH_FORMAT;
    for (name, format, wanted) in [
        ("depth", depth, s.depth),
        ("material_depth", depth, s.material_depth),
        ("color", meshlight::resolve::COLOR_FORMAT, true),
    ] {
        if !wanted {
            continue;
        }
        let t = g.create_texture(name, TextureDesc::d2(format, s.width, s.height));
        g.export(t);
    }
    let history = occlusion.then(|| {
        for (name, desc) in [
            (
                CANDIDATES,
                BufferDesc::array_param(elements::CLUSTER, CLUSTERS_PARAM),
            ),
            (CANDIDATE_COUNT, BufferDesc::array(Element::U32, 2)),
            (
                SECOND_COUNTS,
                BufferDesc::array(Element::U32, OCCLUSION_COUNT_WORDS),
            ),
            (SECOND_HW_ARGS, BufferDesc::array(Element::DRAW_ARGS, 1)),
            (SECOND_SW_ARGS, BufferDesc::array(Element::DISPATCH_ARGS, 1)),
        ] {
            g.create_buffer(name, desc);
        }
        let desc = meshlight::depth_pyramid::texture_desc(s.width, s.height);
        g.create_texture("pyramid", desc.clone());
        g.history_texture(PYRAMID_HISTORY, desc)
    });
    // Slots not bound here bind to the resource of the same name.
    // The walk prunes by the LOD threshold cull tests with: they must agree, or
    // clusters of the cut would be pruned.
    let walk = HierarchyFill {
        lod_threshold_px: s.lod_threshold_px,
        occlusion_min_clusters: s.occlusion_min_clusters,
        ..HierarchyFill::default()
    };
    // Room for the entry counters: instances tested and visible.
    let walk_counts = ENTRY_COUNT_WORDS;
    if s.hierarchy {
        import_hierarchy_for(data, &mut g);
        g.create_buffer(
            HIERARCHY_COUNTS_READBACK,
            BufferDesc::array(Element::U32, walk_counts),
        );
        let bindings = match &history {
            // Nodes last frame's pyramid hides wait for the second walk.
            Some(h) => {
                g.size_param(
                    HIDDEN_NODES_PARAM,
                    hidden_node_capacity(data.instances.len()),
                );
                for (name, desc) in [
                    (
                        HIDDEN_NODES,
                        BufferDesc::array_param(HIDDEN_NODE, HIDDEN_NODES_PARAM),
                    ),
                    (HIDDEN_NODE_COUNT, BufferDesc::array(Element::U32, 2)),
                    (
                        SECOND_WALK_CLUSTERS,
                        BufferDesc::array_param(elements::CLUSTER, CLUSTERS_PARAM),
                    ),
                    (SECOND_WALK_COUNT, BufferDesc::array(Element::U32, 2)),
                    (
                        SECOND_HIERARCHY_COUNTS,
                        BufferDesc::array(Element::U32, walk_counts),
                    ),
                ] {
                    g.create_buffer(name, desc);
                }
                Bindings::new()
                    .bind("pyramid", h.prev)
                    .bind_named("occluded_nodes", HIDDEN_NODES)
                    .bind_named("occluded_node_count", HIDDEN_NODE_COUNT)
            }
            None => Bindings::new(),
        };
        g.add_pass("fill", walk, bindings)?;
    } else {
        g.add_pass("fill", FillClusters::default(), Bindings::new())?;
    }
    let thresholds = Thresholds {
        lod_threshold_px: s.lod_threshold_px,
        // The renderer fills in its adapter's default; a graph built elsewhere
        // without one takes cull_lod's.
        sw_threshold_px: s
            .sw_threshold_px
            .unwrap_or(Thresholds::default().sw_threshold_px),
        hardware: s.has_hardware(),
    };
    let cull = CullLod {
        thresholds,
        ..CullLod::default()
    };
    // The occlusion view's records: a clear and two atomics per cluster of the cut, so
    // only that view pays for them.
    let records = history.is_some() && s.view.needs_occlusion_records();
    if records {
        let words = data.instances.len().max(1) as u64 * 2;
        g.create_buffer(INSTANCE_OCCLUSION, BufferDesc::array(Element::U32, words));
    }
    let first = match &history {
        Some(h) => Bindings::new()
            .bind("pyramid", h.prev)
            .bind_named("occluded", CANDIDATES)
            .bind_named("occluded_count", CANDIDATE_COUNT),
        None => Bindings::new(),
    };
    let first = if records {
        first.bind_named(PER_INSTANCE_FIRST, INSTANCE_OCCLUSION)
    } else {
        first
    };
    g.add_pass("cull", cull, first)?;
    let remap = RemapDispatch {
        count_word: 0,
        max_per_dimension: None,
    };
    let remap_bindings = Bindings::new()
        .bind_named("count", "raster_counts")
        .bind_named("args", "sw_args");
    g.add_pass("remap", remap, remap_bindings)?;
    let (width, height) = (s.width, s.height);
    // The stages with several implementations come from the registry, as in a pipeline
    // file: the implementation named in the settings (or `auto`) with these parameters.
    let registry = frame_registry(s);
    let sw_choice = |accumulate: bool| {
        registered(
            &registry,
            meshlight::sw_raster::STAGE,
            &s.sw_raster,
            toml::toml! {
                width = (width)
                height = (height)
                exact_division = (s.exact_division)
                accumulate = (accumulate)
                big_triangle_px = (s.big_triangle_px)
            },
        )
    };
    g.add_choice("sw_raster", sw_choice(false)?, Bindings::new())?;
    // The stages whose one parameter is the viewport.
    let at_viewport = |stage: &str, implementation: &str| {
        registered(
            &registry,
            stage,
            implementation,
            toml::toml! {
                width = (width)
                height = (height)
            },
        )
    };
    let hw_choice = || at_viewport(meshlight::hw_raster::STAGE, &s.hw_raster);
    if s.has_hardware() {
        g.add_choice("hw_raster", hw_choice()?, Bindings::new())?;
    }
    let pyramid = || at_viewport(meshlight::depth_pyramid::STAGE, AUTO);
    if history.is_some() {
        let visibility = Bindings::new().bind_named("visibility", "visbuffer");
        g.add_choice("depth_pyramid", pyramid()?, visibility)?;
        if s.hierarchy {
            // The nodes the first walk found hidden, walked again against this frame's
            // pyramid; cull_second takes the clusters below those still visible.
            let second_walk = HierarchyFill {
                phase: Phase::Second,
                ..walk
            };
            let bindings = Bindings::new()
                .bind_named("candidate_nodes", HIDDEN_NODES)
                .bind_named("candidate_node_count", HIDDEN_NODE_COUNT)
                .bind_named("clusters", SECOND_WALK_CLUSTERS)
                .bind_named("cluster_count", SECOND_WALK_COUNT)
                .bind_named("hierarchy_counts", SECOND_HIERARCHY_COUNTS);
            g.add_pass("fill_second", second_walk, bindings)?;
        }
        let second = CullLod {
            thresholds,
            phase: Phase::Second,
            ..CullLod::default()
        };
        let bindings = Bindings::new()
            .bind_named("clusters", CANDIDATES)
            .bind_named("cluster_count", CANDIDATE_COUNT)
            .bind_named("first_counts", "raster_counts")
            .bind_named("raster_counts", SECOND_COUNTS)
            .bind_named("hw_args", SECOND_HW_ARGS);
        let bindings = if s.hierarchy {
            bindings
                .bind_named(WALKED_SLOT, SECOND_WALK_CLUSTERS)
                .bind_named(WALKED_COUNT_SLOT, SECOND_WALK_COUNT)
        } else {
            bindings
        };
        let bindings = if records {
            bindings.bind_named(PER_INSTANCE_SECOND, INSTANCE_OCCLUSION)
        } else {
            bindings
        };
        g.add_pass("cull_second", second, bindings)?;
        let bindings = Bindings::new()
            .bind_named("count", SECOND_COUNTS)
            .bind_named("args", SECOND_SW_ARGS);
        g.add_pass("remap_second", remap, bindings)?;
        let bindings = Bindings::new()
            .bind_named("raster_counts", SECOND_COUNTS)
            .bind_named("sw_args", SECOND_SW_ARGS);
        g.add_choice("sw_raster_second", sw_choice(true)?, bindings)?;
        if s.has_hardware() {
            let bindings = Bindings::new()
                .bind_named("raster_counts", SECOND_COUNTS)
                .bind_named("hw_args", SECOND_HW_ARGS);
            g.add_choice("hw_raster_second", hw_choice()?, bindings)?;
        }
    }
    if let Some(c) = &s.clustering {
        // The light clustering's outputs bind to resolve's slots of the same names.
        clustering::import_objects(&mut g, c);
        clustering::add_stages(&mut g, c)?;
        clustering::add_readbacks(&mut g)?;
    }
    let mut resolve = Resolve::new(width, height);
    resolve.settings.view = s.view;
    let bindings = if records {
        Bindings::new()
            .bind_named(meshlight::resolve::SECOND_COUNTS, SECOND_COUNTS)
            .bind_named(OCCLUDED_PER_INSTANCE, INSTANCE_OCCLUSION)
    } else {
        Bindings::new()
    };
    g.add_pass("resolve", resolve, bindings)?;
    if let Some(h) = history {
        // The frame's final depth, for the next frame's first pass.
        let bindings = Bindings::new()
            .bind_named("visibility", "visbuffer")
            .bind("pyramid", h.current);
        g.add_choice("history_pyramid", pyramid()?, bindings)?;
    }
    if s.keep_visibility {
        g.export(visbuffer);
        for name in ["raster_clusters", "raster_counts", SECOND_COUNTS] {
            if let Some(h) = g.resource(name) {
                g.export(h);
            }
        }
    }
    add_readbacks(&mut g)?;
    Ok(g)
}

/// The registry a frame's stages come from: the built-in one, with `auto` trying the
/// hardware rasterisers in the adapter class's order when the settings know the class.
fn frame_registry(s: &FrameSettings) -> Registry {
    let mut registry = meshlight::registry();
    prefer_class_order(&mut registry, s);
    registry
}

/// Orders `auto`'s hardware rasterisers as the settings' adapter class prefers them.
fn prefer_class_order(registry: &mut Registry, s: &FrameSettings) {
    if let Some(class) = s.adapter_class {
        let feeds = class.hardware_feeds().map(|f| f.implementation());
        registry.prefer(meshlight::hw_raster::STAGE, &feeds);
    }
}

/// Stage `stage` as the registry builds it for `implementation` (or `auto`) with these
/// parameters, as a choice compile resolves.
fn registered(
    registry: &Registry,
    stage: &str,
    implementation: &str,
    params: toml::Table,
) -> Result<Choice> {
    let params = meshlight::graph::file::Params::new(params);
    match registry.build_choice(stage, implementation, &params)? {
        Some(choice) => Ok(choice),
        None => Choice::select(
            implementation,
            vec![registry.build(stage, implementation, &params)?],
        ),
    }
}

/// A pipeline file with the renderer's sizes (viewport, lists, scene buffers) set in
/// its `[params]` and every `resolve` pass showing `settings.view`, then the counters'
/// readbacks added. Everything else (thresholds, which stages run) is the file's.
pub fn load(path: &Path, data: &SceneData, s: &FrameSettings) -> Result<GraphBuilder> {
    load_with(path, data, s, &meshlight::registry())
}

/// [`load`] with the stages of `registry`.
pub fn load_with(
    path: &Path,
    data: &SceneData,
    s: &FrameSettings,
    registry: &Registry,
) -> Result<GraphBuilder> {
    let file = path.display().to_string();
    let text = std::fs::read_to_string(path).map_err(|e| GraphError::PipelineFile {
        file: file.clone(),
        message: format!("cannot read it: {e}"),
    })?;
    let clusters_lights = clusters_lights(&text);
    if s.clustering.is_some() && !clusters_lights {
        return Err(GraphError::PipelineFile {
            file,
            message: format!(
                "lights are asked for, but the file clusters none (it has no `{}` pass); render with `--lights 0`, or add the light clustering's passes as pipelines/virtual_geometry.toml does",
                meshlight::z_slice::STAGE
            ),
        });
    }
    let text = with_view(&text, &file, s, data.instances.len())?;
    let text = with_instance_table(&text, &file, data)?;
    let mut params = overrides(data, s);
    // A file without a depth pyramid (one culling pass) does not declare its size, nor
    // one whose `fill` visits every cluster the hierarchy's.
    let declared: toml::Table = toml::from_str(&text).unwrap_or_default();
    let declares = |name: &str| {
        declared
            .get("params")
            .and_then(toml::Value::as_table)
            .is_some_and(|p| p.contains_key(name))
    };
    let optional = [
        PYRAMID_WIDTH_PARAM,
        PYRAMID_HEIGHT_PARAM,
        HIDDEN_NODES_PARAM,
        names::INSTANCES_HIGH,
    ]
    .into_iter()
    .chain(hierarchy_lengths(data).map(|(name, _, _)| name));
    for name in optional {
        if !declares(name) {
            params.remove(name);
        }
    }
    // The light clustering's sizes, from the lights (none: the smallest lists).
    if clusters_lights {
        let lights = s
            .clustering
            .clone()
            .unwrap_or_else(|| ClusteringSettings::new([s.width, s.height], 1));
        params.extend(clustering::overrides(&lights));
    }
    // The file's list sizes where it keeps them (slots still no more than an id holds).
    let keep = s.keep_file_lists;
    for (name, kept, most) in [
        (CLUSTERS_PARAM, keep.clusters, u64::MAX),
        (SLOTS_PARAM, keep.slots, MAX_SLOTS),
    ] {
        let declared = declared
            .get("params")
            .and_then(|p| p.get(name))
            .and_then(toml::Value::as_integer)
            .and_then(|v| u64::try_from(v).ok());
        if let (true, Some(value)) = (kept, declared) {
            params.insert(name.to_string(), value.min(most));
        }
    }
    // `auto` tries the hardware rasterisers in the adapter class's order, as in code.
    let mut registry = registry.clone();
    prefer_class_order(&mut registry, s);
    let mut pipeline = meshlight::graph::file::Pipeline::parse(&text, &file)?;
    pipeline.set_params(params)?;
    let mut g = pipeline.build(&registry)?;
    add_readbacks(&mut g)?;
    if clusters_lights {
        clustering::add_readbacks(&mut g)?;
    }
    Ok(g)
}

/// Whether a pipeline file's text clusters lights (has a `z_slice` pass): the renderer
/// then uploads its lights (none when none are asked for) and sizes the clustering.
pub fn clusters_lights(text: &str) -> bool {
    let doc: toml::Table = toml::from_str(text).unwrap_or_default();
    doc.get("pass")
        .and_then(toml::Value::as_array)
        .is_some_and(|passes| {
            passes.iter().any(|p| {
                p.get("stage").and_then(toml::Value::as_str) == Some(meshlight::z_slice::STAGE)
            })
        })
}

/// [`clusters_lights`] of the file at `path`; `false` when it is not a pipeline file
/// that can be read (a device, too large: loading it reports why).
pub fn file_clusters_lights(path: &Path) -> bool {
    meshlight::graph::file::read_pipeline_text(path).is_ok_and(|text| clusters_lights(&text))
}

/// The `[params]` the renderer sets in a pipeline file.
pub fn overrides(data: &SceneData, s: &FrameSettings) -> BTreeMap<String, u64> {
    let mut o: BTreeMap<String, u64> = buffer_lengths(data)
        .into_iter()
        .chain(hierarchy_lengths(data))
        .map(|(name, _, count)| (name.to_string(), count))
        .collect();
    o.insert("width".into(), s.width as u64);
    o.insert("height".into(), s.height as u64);
    o.insert("pixels".into(), s.width as u64 * s.height as u64);
    o.insert(CLUSTERS_PARAM.into(), s.clusters);
    o.insert(SLOTS_PARAM.into(), s.slots.min(MAX_SLOTS));
    o.insert(
        HIDDEN_NODES_PARAM.into(),
        hidden_node_capacity(data.instances.len()),
    );
    let pyramid = meshlight::depth_pyramid::pyramid_extent(s.width, s.height);
    let [w, h] = pyramid.texture_size();
    o.insert(PYRAMID_WIDTH_PARAM.into(), w as u64);
    o.insert(PYRAMID_HEIGHT_PARAM.into(), h as u64);
    o
}

/// Which list sizes of a pipeline file stand over [`FrameSettings`]' own.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct KeepFileLists {
    /// The file's [`CLUSTERS_PARAM`].
    pub clusters: bool,
    /// The file's [`SLOTS_PARAM`].
    pub slots: bool,
}

/// The `[params]` giving a pyramid texture's size in a pipeline file; the renderer also
/// sets `mip_levels` of every texture whose width is `$pyramid_width`.
pub const PYRAMID_WIDTH_PARAM: &str = "pyramid_width";
pub const PYRAMID_HEIGHT_PARAM: &str = "pyramid_height";

/// The view the file's first `resolve` pass names (`None`: it names none), read as
/// [`load`] reads it when [`FrameSettings::keep_file_view`] is set.
pub fn view_in_file(path: &Path) -> Result<Option<DebugView>> {
    let file = path.display().to_string();
    let ferr = |message: String| GraphError::PipelineFile {
        file: file.clone(),
        message,
    };
    let text = std::fs::read_to_string(path).map_err(|e| ferr(format!("cannot read it: {e}")))?;
    let doc: toml::Table = toml::from_str(&text).map_err(|e| ferr(e.to_string()))?;
    let Some(toml::Value::Array(passes)) = doc.get("pass") else {
        return Ok(None);
    };
    for pass in passes.iter().filter_map(toml::Value::as_table) {
        if let Some(view) = file_view_of(pass).map_err(&ferr)? {
            return Ok(Some(view));
        }
    }
    Ok(None)
}

/// The view a `resolve` pass of a pipeline file names, if it is one and names one.
fn file_view_of(pass: &toml::Table) -> std::result::Result<Option<DebugView>, String> {
    if pass.get("stage").and_then(toml::Value::as_str) != Some("resolve") {
        return Ok(None);
    }
    match pass
        .get("params")
        .and_then(toml::Value::as_table)
        .and_then(|p| p.get("view"))
    {
        None => Ok(None),
        Some(toml::Value::String(name)) => DebugView::parse(name)
            .map(Some)
            .map_err(|e| format!("a resolve pass's `view`: {e}")),
        Some(other) => Err(format!(
            "a resolve pass's `view` is {other}, not a view's name"
        )),
    }
}

/// The file's text with `view` set in the params of every pass of stage `resolve`
/// (unless [`FrameSettings::keep_file_view`] keeps the file's), and the mip count of the
/// pyramid textures (those sized by `pyramid_width`) set for the viewport, which the
/// file format cannot derive from a parameter. For the `occlusion` view of a two-pass
/// file, the view's records are bound as in the frame built in code (see
/// [`with_occlusion_records`]).
fn with_view(text: &str, file: &str, s: &FrameSettings, instances: usize) -> Result<String> {
    let view = s.view;
    let mut records = !s.keep_file_view && view.needs_occlusion_records();
    let ferr = |message: String| GraphError::PipelineFile {
        file: file.to_string(),
        message,
    };
    let mut doc: toml::Table = toml::from_str(text).map_err(|e| ferr(e.to_string()))?;
    let levels = meshlight::depth_pyramid::pyramid_extent(s.width, s.height).mip_levels;
    if let Some(toml::Value::Array(resources)) = doc.get_mut("resource") {
        for r in resources.iter_mut().filter_map(toml::Value::as_table_mut) {
            if let Some(toml::Value::Table(t)) = r.get_mut("texture")
                && t.get("width_param").and_then(toml::Value::as_str) == Some(PYRAMID_WIDTH_PARAM)
            {
                t.insert("mip_levels".into(), toml::Value::Integer(levels.into()));
            }
        }
    }
    if let Some(toml::Value::Array(passes)) = doc.get_mut("pass") {
        for pass in passes.iter_mut().filter_map(toml::Value::as_table_mut) {
            if pass.get("stage").and_then(toml::Value::as_str) != Some("resolve") {
                continue;
            }
            if s.keep_file_view {
                let named = file_view_of(pass).map_err(ferr)?;
                records |= named.is_some_and(DebugView::needs_occlusion_records);
                continue;
            }
            let params = pass
                .entry("params")
                .or_insert_with(|| toml::Value::Table(toml::Table::new()));
            let Some(params) = params.as_table_mut() else {
                return Err(ferr("a resolve pass's `params` is not a table".into()));
            };
            params.insert("view".into(), toml::Value::String(view.name().into()));
        }
    }
    if records {
        with_occlusion_records(&mut doc, instances).map_err(ferr)?;
    }
    toml::to_string(&doc).map_err(|e| ferr(e.to_string()))
}

/// The file's text with the second binding of the instance table added when the scene
/// needs it ([`meshlight::gpu_scene::instance_table`]): an imported `instances_high`
/// like the file's `instances`, which every pass reading instances then binds by name.
/// A file that declares `instances_high` itself is left as it is; one that does not
/// import `instances` under that name cannot take a split table and is refused.
fn with_instance_table(text: &str, file: &str, data: &SceneData) -> Result<String> {
    if !data.instances_split() {
        return Ok(text.to_string());
    }
    let ferr = |message: String| GraphError::PipelineFile {
        file: file.to_string(),
        message,
    };
    let mut doc: toml::Table = toml::from_str(text).map_err(|e| ferr(e.to_string()))?;
    let Some(toml::Value::Array(resources)) = doc.get_mut("resource") else {
        return Err(ferr("the file declares no resources".into()));
    };
    let named =
        |r: &toml::Value, name: &str| r.get("name").and_then(toml::Value::as_str) == Some(name);
    if resources.iter().any(|r| named(r, names::INSTANCES_HIGH)) {
        return Ok(text.to_string());
    }
    let low = resources
        .iter()
        .find(|r| named(r, names::INSTANCES))
        .filter(|r| r.get("kind").and_then(toml::Value::as_str) == Some("imported"))
        .ok_or_else(|| {
            ferr(format!(
                "the scene's {} instances take two storage bindings on this adapter (one holds {}), and the file imports no `{}` buffer to split; import the scene's instances as `{}`",
                data.instances.len(),
                data.limits().instances_per_binding,
                names::INSTANCES,
                names::INSTANCES,
            ))
        })?;
    let usage = low
        .get("usage")
        .cloned()
        .unwrap_or_else(|| toml::Value::Array(Vec::new()));
    let high = data.instances.len() - data.instance_split();
    let mut resource: toml::Table = toml::from_str(&format!(
        "name = \"{}\"\nkind = \"imported\"\nbuffer = {{ element = \"Instance\", element_size = {}, count = {high} }}\n",
        names::INSTANCES_HIGH,
        elements::INSTANCE.size,
    ))
    .map_err(|e| ferr(e.to_string()))?;
    resource.insert("usage".into(), usage);
    resources.push(toml::Value::Table(resource));
    toml::to_string(&doc).map_err(|e| ferr(e.to_string()))
}

/// Adds the `occlusion` view's records to a two-pass file (one with a `cull_lod` pass of
/// `mode = "second"`; others are left as they are): a transient [`INSTANCE_OCCLUSION`]
/// buffer of two words per instance, bound to the first cull (the one with a `pyramid`)
/// as `occluded_per_instance`, to the second as `still_occluded_per_instance`, and to
/// every `resolve` as `occluded_per_instance`, with the second cull's `raster_counts` as
/// resolve's `second_counts`. The shipped file leaves them out: they cost a clear and two
/// atomics per cluster of the cut that no other view reads.
fn with_occlusion_records(
    doc: &mut toml::Table,
    instances: usize,
) -> std::result::Result<(), String> {
    let str_of =
        |t: &toml::Table, key: &str| t.get(key).and_then(toml::Value::as_str).map(String::from);
    let Some(toml::Value::Array(passes)) = doc.get_mut("pass") else {
        return Ok(());
    };
    let mode = |pass: &toml::Table| {
        pass.get("params")
            .and_then(toml::Value::as_table)
            .and_then(|p| str_of(p, "mode"))
    };
    let is_cull =
        |pass: &toml::Table| str_of(pass, "stage").as_deref() == Some(meshlight::cull_lod::STAGE);
    let Some(second_counts) = passes
        .iter()
        .filter_map(toml::Value::as_table)
        .find(|p| is_cull(p) && mode(p).as_deref() == Some("second"))
        .map(|p| {
            p.get("bind")
                .and_then(toml::Value::as_table)
                .and_then(|b| str_of(b, "raster_counts"))
                .unwrap_or_else(|| "raster_counts".into())
        })
    else {
        return Ok(());
    };
    for pass in passes.iter_mut().filter_map(toml::Value::as_table_mut) {
        let stage = str_of(pass, "stage");
        let second = mode(pass).as_deref() == Some("second");
        let binds_pyramid = pass
            .get("bind")
            .and_then(toml::Value::as_table)
            .is_some_and(|b| b.contains_key("pyramid"));
        let slots: Vec<(&str, String)> = match stage.as_deref() {
            Some(meshlight::cull_lod::STAGE) if second => {
                vec![(PER_INSTANCE_SECOND, INSTANCE_OCCLUSION.into())]
            }
            Some(meshlight::cull_lod::STAGE) if binds_pyramid => {
                vec![(PER_INSTANCE_FIRST, INSTANCE_OCCLUSION.into())]
            }
            Some(meshlight::resolve::STAGE) => vec![
                (meshlight::resolve::SECOND_COUNTS, second_counts.clone()),
                (OCCLUDED_PER_INSTANCE, INSTANCE_OCCLUSION.into()),
            ],
            _ => continue,
        };
        let bind = pass
            .entry("bind")
            .or_insert_with(|| toml::Value::Table(toml::Table::new()))
            .as_table_mut()
            .ok_or("a pass's `bind` is not a table")?;
        for (slot, resource) in slots {
            bind.insert(slot.into(), toml::Value::String(resource));
        }
    }
    let resource: toml::Table = toml::from_str(&format!(
        "name = \"{INSTANCE_OCCLUSION}\"\nkind = \"transient\"\nbuffer = {{ element = \"u32\", count = {} }}\n",
        instances.max(1) * 2
    ))
    .map_err(|e| e.to_string())?;
    match doc
        .entry("resource")
        .or_insert_with(|| toml::Value::Array(Vec::new()))
    {
        toml::Value::Array(resources) => resources.push(toml::Value::Table(resource)),
        _ => return Err("`resource` is not an array of tables".into()),
    }
    Ok(())
}

/// The counters come back [`COUNTS_LATENCY`] frames later; the graph needs resources
/// named `cluster_count` and `raster_counts` (a pipeline file too).
/// With a second culling pass (a resource named [`SECOND_COUNTS`]) both passes' words
/// come back, twelve each.
fn add_readbacks(g: &mut GraphBuilder) -> Result<()> {
    g.readback_named(
        CLUSTER_COUNT_READBACK,
        "cluster_count",
        Some(0..8),
        COUNTS_LATENCY,
    )?;
    let two_pass = g.resource(SECOND_COUNTS).is_some();
    let bytes = if two_pass {
        OCCLUSION_COUNT_WORDS * 4
    } else {
        32
    };
    g.readback_named(
        RASTER_COUNTS_READBACK,
        "raster_counts",
        Some(0..bytes),
        COUNTS_LATENCY,
    )?;
    if two_pass {
        g.readback_named(
            SECOND_COUNTS_READBACK,
            SECOND_COUNTS,
            Some(0..bytes),
            COUNTS_LATENCY,
        )?;
    }
    if g.resource(HIERARCHY_COUNTS_READBACK).is_some() {
        // As many of the walk's words as the buffer holds, up to the entry counters
        // (a pipeline file may declare it shorter: four words, five with occlusion).
        let second_walk = g.resource(SECOND_HIERARCHY_COUNTS).is_some();
        let bytes = g
            .resources()
            .iter()
            .find(|r| r.name == HIERARCHY_COUNTS_READBACK)
            .map_or(16, |r| r.desc.bytes())
            .min(ENTRY_COUNT_WORDS * 4);
        g.readback_named(
            HIERARCHY_COUNTS_READBACK,
            HIERARCHY_COUNTS_READBACK,
            Some(0..bytes),
            COUNTS_LATENCY,
        )?;
        if second_walk {
            g.readback_named(
                SECOND_HIERARCHY_COUNTS_READBACK,
                SECOND_HIERARCHY_COUNTS,
                Some(0..bytes),
                COUNTS_LATENCY,
            )?;
            g.readback_named(
                SECOND_WALK_COUNT_READBACK,
                SECOND_WALK_COUNT,
                Some(0..8),
                COUNTS_LATENCY,
            )?;
        }
    }
    Ok(())
}
