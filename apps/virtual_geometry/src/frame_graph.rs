//! The virtual-geometry frame as a graph. The frame is a pipeline file:
//! `pipelines/virtual_geometry.toml` ([`SHIPPED`], embedded), its one-pass variant
//! without occlusion, or a file of the caller's. [`frame`] applies the renderer's
//! [`FrameSettings`] to it through the pipeline's methods (parameters, implementations,
//! resources added and bound, passes removed), never by editing its text, then builds it
//! and adds the counters' readbacks. So every tool that runs the shipped frame (`meshlight
//! render`, `view`, `graph`, the bench) runs the same passes, and a user's copy of the
//! file takes the same settings the same way.
//!
//! With occlusion (the shipped frame), two culling passes (see docs/ARCHITECTURE.md):
//!
//! ```text
//! fill → cull (first, last frame's pyramid) → remap → sw_raster → hw_raster
//!      → depth_pyramid → fill_second → cull_second (the first's candidates, this
//!      frame's pyramid) → remap_second → sw_raster_second → hw_raster_second
//!      → z_slice → count → scan → populate → resolve
//! ```
//!
//! The one pyramid, built after the first pass, is also kept for the next frame.
//!
//! Both rasterisations accumulate into one visibility target and one slot list, so a
//! visibility id means the same to resolve whichever pass drew it.

use super::counts::{
    CLUSTER_COUNT_READBACK, HIERARCHY_COUNTS_READBACK, RASTER_COUNTS_READBACK,
    SECOND_COUNTS_READBACK, SECOND_HIERARCHY_COUNTS_READBACK, SECOND_WALK_COUNT_READBACK,
};
use super::settings::{FrameSettings, HostTargets};
use meshlight::cull_lod::{OCCLUSION_COUNT_WORDS, PER_INSTANCE_FIRST, PER_INSTANCE_SECOND};
use meshlight::fill_clusters::hierarchy::ENTRY_COUNT_WORDS;
use meshlight::gpu_scene::gpu::{buffer_lengths, elements, hierarchy_lengths};
use meshlight::gpu_scene::{SceneData, names};
use meshlight::graph::file::{
    EntryKind, PassEntry, Pipeline, Registry, ResourceEntry, format_text,
};
use meshlight::graph::{GraphBuilder, GraphError, Result};
use meshlight::resolve::{DebugView, OCCLUDED_PER_INSTANCE};
use meshlight_light_clustering::frame_graph as clustering;
use std::path::PathBuf;

/// The shipped frame, `pipelines/virtual_geometry.toml`: two-pass occlusion culling and
/// the light clustering.
pub const SHIPPED: &str = include_str!("../pipelines/virtual_geometry.toml");
/// How errors name [`SHIPPED`].
pub const SHIPPED_FILE: &str = "pipelines/virtual_geometry.toml";
/// The shipped frame without occlusion culling,
/// `pipelines/virtual_geometry_one_pass.toml`.
pub const SHIPPED_ONE_PASS: &str = include_str!("../pipelines/virtual_geometry_one_pass.toml");
/// How errors name [`SHIPPED_ONE_PASS`].
pub const SHIPPED_ONE_PASS_FILE: &str = "pipelines/virtual_geometry_one_pass.toml";

/// Size parameter: candidate clusters the per-frame list holds.
pub const CLUSTERS_PARAM: &str = "clusters";
/// Size parameter: raster slots (clusters in the LOD cut) one frame holds.
pub const SLOTS_PARAM: &str = "slots";
/// A visibility id has 25 bits for the slot: more slots could not be told apart.
pub const MAX_SLOTS: u64 = 1 << 25;
/// How many frames later the counters come back to the CPU.
pub const COUNTS_LATENCY: u32 = 2;
/// The second culling pass's counters, named unlike `cull_lod`'s slot `raster_counts`.
pub const SECOND_COUNTS: &str = "raster_counts_second";
/// The per-instance occlusion counters (two words per instance), added only for the
/// `occlusion` view: the first cull clears and fills them, the second updates them,
/// resolve reads them (named unlike all three slots).
pub const INSTANCE_OCCLUSION: &str = "instance_occlusion";
/// The second walk's counters.
pub const SECOND_HIERARCHY_COUNTS: &str = "hierarchy_counts_second";
/// The second walk's cluster list count.
pub const SECOND_WALK_COUNT: &str = "second_walk_count";
/// Size parameter: entries of the list of nodes the first walk hands to the second. A
/// full list costs no correctness (the first walk then walks on below the node), only
/// pruning.
pub const HIDDEN_NODES_PARAM: &str = "hidden_nodes";
/// The `[params]` giving the depth pyramid texture's size (its mips are `"full"`).
pub const PYRAMID_WIDTH_PARAM: &str = "pyramid_width";
/// See [`PYRAMID_WIDTH_PARAM`].
pub const PYRAMID_HEIGHT_PARAM: &str = "pyramid_height";
/// The imported texture a host's frame ends in ([`HostTargets`]).
pub const HOST_TARGET: &str = "target";
/// The depth texture resolve writes (a host's, with [`HostTargets::depth`]).
pub const DEPTH: &str = "depth";
/// The material-depth texture resolve writes with [`FrameSettings::material_depth`].
pub const MATERIAL_DEPTH: &str = "material_depth";
/// The image resolve writes.
pub const COLOR: &str = "color";

/// [`HIDDEN_NODES_PARAM`] for a scene: room for every instance's root and then some,
/// within 4 Mi entries (48 MiB).
pub fn hidden_node_capacity(instances: usize) -> u64 {
    (instances as u64 * 4).clamp(1 << 16, 1 << 22)
}

/// Where the frame's pipeline comes from.
#[derive(Clone, Debug)]
pub enum GraphSource {
    /// The shipped frame: [`SHIPPED`], or [`SHIPPED_ONE_PASS`] without
    /// [`FrameSettings::occlusion`].
    Shipped,
    /// A pipeline file, its stages from [`meshlight::registry`].
    File(PathBuf),
    /// A pipeline file whose stages come from the registry the function returns: the
    /// built-in one with the caller's own implementations registered, e.g.
    /// `|| { let mut r = meshlight::registry(); r.register(STAGE, "mine", Mine::from_params); r }`.
    FileWith(PathBuf, fn() -> Registry),
    /// A pipeline the caller holds (read from anywhere, changed already).
    Pipeline(Box<Pipeline>),
}

impl GraphSource {
    /// The pipeline before the settings are applied.
    pub fn pipeline(&self, s: &FrameSettings) -> Result<Pipeline> {
        match self {
            GraphSource::Shipped if s.occlusion => Pipeline::parse(SHIPPED, SHIPPED_FILE),
            GraphSource::Shipped => Pipeline::parse(SHIPPED_ONE_PASS, SHIPPED_ONE_PASS_FILE),
            GraphSource::File(path) | GraphSource::FileWith(path, _) => Pipeline::load(path),
            GraphSource::Pipeline(p) => Ok(p.as_ref().clone()),
        }
    }

    /// The registry the pipeline's stages are built from.
    pub fn registry(&self) -> Registry {
        match self {
            GraphSource::FileWith(_, registry) => registry(),
            _ => meshlight::registry(),
        }
    }
}

/// A frame ready to compile, and what the renderer needs to know of it.
pub struct Frame {
    /// The graph, counters' readbacks included.
    pub graph: GraphBuilder,
    /// The pipeline as the settings left it (what the graph was built from).
    pub pipeline: Pipeline,
    /// What the frame's `resolve` shows.
    pub view: DebugView,
}

/// The frame `source` declares, with `s` applied for the scene `data`.
pub fn frame(source: &GraphSource, data: &SceneData, s: &FrameSettings) -> Result<Frame> {
    let registry = source.registry();
    let mut pipeline = source.pipeline(s)?;
    apply(&mut pipeline, &registry, data, s)?;
    let view = view_of(&pipeline)?;
    let mut graph = pipeline.build(&registry)?;
    if s.keep_visibility {
        for name in [
            "visbuffer",
            "raster_clusters",
            "raster_counts",
            SECOND_COUNTS,
        ] {
            if let Some(h) = graph.resource(name) {
                graph.export(h);
            }
        }
    }
    add_readbacks(&mut graph, &pipeline)?;
    super::streaming::add_readbacks(&mut graph)?;
    let cascades = pipeline.views.get(super::shadows::CASCADES).copied();
    super::shadows::add_readbacks(&mut graph, cascades.unwrap_or(0))?;
    if s.clustering.is_some() {
        clustering::add_readbacks(&mut graph)?;
    }
    Ok(Frame {
        graph,
        pipeline,
        view,
    })
}

/// Applies `s` to the frame's pipeline, in the order each step needs: what the frame
/// holds (lights, flat fill, hardware raster, targets), then its sizes and parameters.
pub fn apply(
    p: &mut Pipeline,
    registry: &Registry,
    data: &SceneData,
    s: &FrameSettings,
) -> Result<()> {
    lights(p, registry, s)?;
    super::shadows::apply(p, registry, s)?;
    for (stage, implementation) in &s.implementations {
        if stage == meshlight::fill_clusters::STAGE && implementation == FLAT_FILL {
            flat_fill(p, registry)?;
            continue;
        }
        if p.set_implementation(stage, implementation) == 0 {
            return Err(no_stage(p, stage, &format!("run `{implementation}`")));
        }
    }
    if !s.hierarchy {
        flat_fill(p, registry)?;
    }
    // A split given asks for both rasterisers.
    hardware(p, registry, s.hardware.or(s.sw_threshold_px.map(|_| true)))?;
    sizes(p, data, s)?;
    instance_table(p, data)?;
    material_variants(p, data);
    thresholds(p, s);
    super::shadows::size_lists(p, s)?;
    if let Some(view) = s.view {
        p.set_stage_param(meshlight::resolve::STAGE, "view", view.name());
    }
    if let Some(sun) = s.sun_direction {
        let sun = toml::Value::Array(sun.to_array().map(|c| f64::from(c).into()).into());
        p.set_stage_param(meshlight::resolve::STAGE, "light_direction", sun);
    }
    if view_of(p)?.needs_occlusion_records() {
        occlusion_records(p, data.instances.len())?;
    }
    super::streaming::apply(p, data)?;
    targets(p, s)
}

/// The resource holding the camera's list words (written, requested) and the list's
/// number in it: the camera's first fill's `cluster_count`, and its `list` plus its
/// `occlusion_view` (by default `cluster_count`, list 0; the shadow stage's buffers when
/// the camera's walk serves the cascades, [`super::shadows::ShadowWalk::WithCamera`]).
fn camera_list_words(p: &Pipeline) -> (String, u64) {
    let fill = p.passes.iter().find(|e| {
        e.stage == meshlight::fill_clusters::STAGE
            && !super::shadows::is_shadow(e)
            && !is_second_pass(e)
    });
    let resource = fill
        .and_then(|f| f.binding("cluster_count"))
        .unwrap_or("cluster_count");
    // A walk over several views writes view v's list at `list + v`; the camera is the
    // view with the pyramid.
    let int = |key| {
        fill.and_then(|f| f.param(key))
            .and_then(toml::Value::as_integer)
            .unwrap_or(0)
            .max(0) as u64
    };
    (resource.to_string(), int("list") + int("occlusion_view"))
}

/// The implementation of `fill_clusters` that lists every cluster of every instance in
/// view (no hierarchy walk, no occlusion of nodes).
pub const FLAT_FILL: &str = "workgroup_per_instance";

fn no_stage(p: &Pipeline, stage: &str, what: &str) -> GraphError {
    GraphError::PipelineFile {
        file: p.file().to_string(),
        message: format!(
            "it has no pass of stage `{stage}` to {what}; add one, or drop the setting"
        ),
    }
}

/// The light clustering sized for the lights, or taken out of the frame without them.
fn lights(p: &mut Pipeline, registry: &Registry, s: &FrameSettings) -> Result<()> {
    let clusters = p.has_stage(meshlight::z_slice::STAGE);
    match &s.clustering {
        Some(c) if clusters => clustering::apply(p, c),
        Some(_) => Err(GraphError::PipelineFile {
            file: p.file().to_string(),
            message: format!(
                "lights are asked for, but the pipeline clusters none (it has no `{}` pass); render with `--lights 0`, or add the light clustering's passes as pipelines/virtual_geometry.toml does",
                meshlight::z_slice::STAGE
            ),
        }),
        None => {
            p.remove_passes(registry, |e| clustering::STAGES.contains(&e.stage.as_str()))?;
            // The lights themselves, which resolve reads beside the lists.
            for input in clustering::INPUTS {
                p.remove_resource(input);
            }
            Ok(())
        }
    }
}

/// The flat fill instead of the hierarchy walk: the first walk becomes
/// [`FLAT_FILL`] (its pyramid and hidden-node bindings dropped), the second walk goes,
/// and with it what only it made (the second cull's walked clusters).
fn flat_fill(p: &mut Pipeline, registry: &Registry) -> Result<()> {
    // The flat fill lists one view: the shadow walk over every cascade becomes one fill
    // per cascade, each writing its cascade's list.
    super::shadows::walk_per_view(p);
    let mut second = Vec::new();
    for fill in p.passes_of_mut(meshlight::fill_clusters::STAGE) {
        if is_second_pass(fill) {
            second.push(fill.name.clone());
            continue;
        }
        fill.implementation = FLAT_FILL.to_string();
        // Which list of the buffers it writes stays; the walk's own params go.
        fill.params
            .retain(|k, _| meshlight::gpu_scene::list_part::LIST_PARAM_KEYS.contains(&k));
        if super::shadows::is_shadow(fill) {
            // A shadow view's lists stay its own; the walk's occlusion slot goes.
            fill.unbind("pyramid");
        } else {
            fill.bind.clear();
        }
    }
    p.remove_passes(registry, |e| second.contains(&e.name))?;
    // What only the walk reads or writes: the hierarchy and its counters.
    for name in [
        names::HIERARCHY_NODES,
        names::HIERARCHY_CLUSTERS,
        names::HIERARCHY_ROOTS,
        HIERARCHY_COUNTS_READBACK,
    ] {
        p.remove_resource(name);
    }
    Ok(())
}

/// `Some(false)`: no hardware rasteriser (culling sends every cluster to software);
/// `Some(true)`: culling sends clusters there on every adapter class.
fn hardware(p: &mut Pipeline, registry: &Registry, hardware: Option<bool>) -> Result<()> {
    let Some(on) = hardware else {
        return Ok(());
    };
    p.set_stage_param(meshlight::cull_lod::STAGE, "hardware", on);
    if on {
        p.set_stage_param(meshlight::hw_raster::STAGE, "run", "always");
    } else {
        p.remove_passes(registry, |e| e.stage == meshlight::hw_raster::STAGE)?;
    }
    Ok(())
}

/// The viewport, the scene's buffer sizes, the pyramid's and the lists' sizes, set in
/// the `[params]` the pipeline declares (a frame without a pyramid declares no pyramid
/// size, one with the flat fill no hierarchy sizes).
fn sizes(p: &mut Pipeline, data: &SceneData, s: &FrameSettings) -> Result<()> {
    let pyramid = meshlight::depth_pyramid::texture_desc(s.width, s.height);
    let required = [
        ("width", u64::from(s.width)),
        ("height", u64::from(s.height)),
    ];
    p.set_params(required)?;
    let optional = buffer_lengths(data)
        .into_iter()
        .chain(hierarchy_lengths(data))
        .map(|(name, _, count)| (name, count))
        .chain([
            ("pixels", u64::from(s.width) * u64::from(s.height)),
            (PYRAMID_WIDTH_PARAM, u64::from(pyramid.width)),
            (PYRAMID_HEIGHT_PARAM, u64::from(pyramid.height)),
            (
                HIDDEN_NODES_PARAM,
                hidden_node_capacity(data.instances.len()),
            ),
        ])
        .chain(s.clusters.map(|c| (CLUSTERS_PARAM, c)))
        .chain(s.slots.map(|n| (SLOTS_PARAM, n.min(MAX_SLOTS))));
    for (name, value) in optional {
        if p.param(name).is_some() {
            p.set_param(name, value)?;
        }
    }
    // A file's own slot count is bounded too: no visibility id names more.
    if let Some(slots) = p.param(SLOTS_PARAM) {
        p.set_param(SLOTS_PARAM, slots.min(MAX_SLOTS))?;
    }
    Ok(())
}

/// The second binding of the instance table where the scene needs it
/// ([`meshlight::gpu_scene::instance_table`]): an imported `instances_high` like the
/// pipeline's `instances`, which every pass reading instances binds by name. A pipeline
/// that declares `instances_high` itself is left as it is; one that imports no
/// `instances` cannot take a split table and is refused.
fn instance_table(p: &mut Pipeline, data: &SceneData) -> Result<()> {
    if !data.instances_split() || p.resource(names::INSTANCES_HIGH).is_some() {
        return Ok(());
    }
    let usage = p
        .resource(names::INSTANCES)
        .filter(|r| r.kind == EntryKind::Imported)
        .map(|r| r.usage.clone())
        .ok_or_else(|| GraphError::PipelineFile {
            file: p.file().to_string(),
            message: format!(
                "the scene's {} instances take two storage bindings on this adapter (one holds {}), and the pipeline imports no `{}` buffer to split; import the scene's instances as `{}`",
                data.instances.len(),
                data.limits().instances_per_binding,
                names::INSTANCES,
                names::INSTANCES,
            ),
        })?;
    let high = (data.instances.len() - data.instance_split()) as u64;
    let mut entry = ResourceEntry::buffer(
        names::INSTANCES_HIGH,
        EntryKind::Imported,
        elements::INSTANCE.name.as_ref(),
        Some(elements::INSTANCE.size),
        high,
    );
    entry.usage = usage;
    p.add_resource(entry)
}

/// Both rasterisers act on double-sided materials (`two_sided`: back faces drawn) and
/// MASK materials (`alpha_mask`: texels below the cutoff left undrawn) only when the
/// scene has such a material: the material lookup and the turn cost the software
/// rasteriser about 2% on an H200, which a scene without one should not pay. A
/// renderer's scene keeps its materials, so the choice holds for the frame's life.
/// The hardware rasteriser's `mesh_shader` implementation cannot cut out texels yet: it
/// refuses `alpha_mask`, so `auto` passes over it, and a pipeline that names it draws
/// such a scene with `indirect_draw` instead, with a warning. Likewise the resolve
/// multiplies by vertex colours (`vertex_colors`) only when some mesh has them.
fn material_variants(p: &mut Pipeline, data: &SceneData) {
    use meshlight::hw_raster::Feed;
    use meshlight::shaders::cpu::layout::{
        MATERIAL_FLAG_DOUBLE_SIDED, MATERIAL_FLAG_MASK, MESH_FLAG_COLORS,
    };
    if data.meshes.iter().any(|m| m.flags & MESH_FLAG_COLORS != 0) {
        p.set_stage_param(meshlight::resolve::STAGE, "vertex_colors", true);
    }
    let has = |flag: u32| data.materials.iter().any(|m| m.flags & flag != 0);
    for (flag, param) in [
        (MATERIAL_FLAG_DOUBLE_SIDED, "two_sided"),
        (MATERIAL_FLAG_MASK, "alpha_mask"),
    ] {
        if has(flag) {
            for stage in [meshlight::sw_raster::STAGE, meshlight::hw_raster::STAGE] {
                p.set_stage_param(stage, param, true);
            }
        }
    }
    if !has(MATERIAL_FLAG_MASK) {
        return;
    }
    let mesh_shader = Feed::MeshShader.implementation();
    for pass in p.passes.iter_mut() {
        if pass.stage == meshlight::hw_raster::STAGE && pass.implementation == mesh_shader {
            log::warn!(
                "pass `{}`: the scene has MASK materials, which the `{mesh_shader}` hardware \
                 rasteriser cannot cut out yet; drawing it with `indirect_draw` instead",
                pass.name
            );
            pass.implementation = Feed::IndirectDraw.implementation().to_string();
        }
    }
}

/// The thresholds and rasteriser parameters the settings give, on every pass they
/// concern; the walk and the cull take the same LOD threshold, or the walk would prune
/// clusters of the cull's cut.
fn thresholds(p: &mut Pipeline, s: &FrameSettings) {
    let walks =
        |e: &PassEntry| e.stage == meshlight::fill_clusters::STAGE && e.implementation != FLAT_FILL;
    for pass in p.passes.iter_mut() {
        let cull = pass.stage == meshlight::cull_lod::STAGE;
        let walk = walks(pass);
        if let Some(lod) = s.lod_threshold_px.filter(|_| cull || walk) {
            pass.set_param("lod_threshold_px", f64::from(lod));
        }
        if let Some(sw) = s.sw_threshold_px.filter(|_| cull) {
            pass.set_param("sw_threshold_px", f64::from(sw));
        }
        if let Some(n) = s.occlusion_min_clusters.filter(|_| walk) {
            pass.set_param("occlusion_min_clusters", i64::from(n));
        }
        if pass.stage == meshlight::sw_raster::STAGE {
            if let Some(px) = s.big_triangle_px {
                pass.set_param("big_triangle_px", i64::from(px));
            }
            if let Some(exact) = s.exact_division {
                pass.set_param("exact_division", exact);
            }
        }
    }
}

/// The view the pipeline's first `resolve` pass shows (shaded when it names none).
pub fn view_of(p: &Pipeline) -> Result<DebugView> {
    let Some(resolve) = p.passes_of(meshlight::resolve::STAGE).next() else {
        return Ok(DebugView::default());
    };
    match resolve.param("view") {
        None => Ok(DebugView::default()),
        Some(toml::Value::String(name)) => {
            DebugView::parse(name).map_err(|e| GraphError::Parameter {
                pass: resolve.name.clone(),
                message: e.to_string(),
            })
        }
        Some(other) => Err(GraphError::Parameter {
            pass: resolve.name.clone(),
            message: format!("`view` is {other}, not a view's name"),
        }),
    }
}

/// The `occlusion` view's records, in a two-pass pipeline (one with a `cull_lod` pass of
/// `mode = "second"`; others are left as they are): a transient [`INSTANCE_OCCLUSION`]
/// buffer of two words per instance, bound to the first cull (the one with a `pyramid`)
/// as `occluded_per_instance`, to the second as `still_occluded_per_instance`, and to
/// every `resolve` as `occluded_per_instance`, with the second cull's `raster_counts` as
/// resolve's `second_counts`. The shipped frame leaves them out: they cost a clear and
/// two atomics per cluster of the cut that no other view reads.
fn occlusion_records(p: &mut Pipeline, instances: usize) -> Result<()> {
    let cull = meshlight::cull_lod::STAGE;
    let Some(second_counts) = p.passes_of(cull).find(|e| is_second_pass(e)).map(|e| {
        e.binding("raster_counts")
            .unwrap_or("raster_counts")
            .to_string()
    }) else {
        return Ok(());
    };
    if p.resource(INSTANCE_OCCLUSION).is_none() {
        p.add_resource(ResourceEntry::buffer(
            INSTANCE_OCCLUSION,
            EntryKind::Transient,
            "u32",
            None,
            instances.max(1) as u64 * 2,
        ))?;
    }
    for pass in p.passes_of_mut(cull) {
        if super::shadows::is_shadow(pass) {
            continue;
        }
        if is_second_pass(pass) {
            pass.bind(PER_INSTANCE_SECOND, INSTANCE_OCCLUSION);
        } else if pass.binding("pyramid").is_some_and(|b| !b.is_empty()) {
            pass.bind(PER_INSTANCE_FIRST, INSTANCE_OCCLUSION);
        }
    }
    for resolve in p.passes_of_mut(meshlight::resolve::STAGE) {
        resolve.bind(meshlight::resolve::SECOND_COUNTS, &second_counts);
        resolve.bind(OCCLUDED_PER_INSTANCE, INSTANCE_OCCLUSION);
    }
    Ok(())
}

/// The targets beyond the shaded image: depth and material depth (resolved by a
/// fullscreen pass each, bound by name), and a host's targets: its colour texture, which
/// a `present` pass draws the image into, and its depth texture, which resolve's depth
/// pass writes.
fn targets(p: &mut Pipeline, s: &FrameSettings) -> Result<()> {
    let depth_format = format_text(meshlight::resolve::DEPTH_FORMAT);
    let exported = |name: &str| {
        ResourceEntry::texture_sized_by(name, EntryKind::Exported, &depth_format, "width", "height")
    };
    if s.material_depth && p.resource(MATERIAL_DEPTH).is_none() {
        p.add_resource(exported(MATERIAL_DEPTH))?;
    }
    let host_depth = s.host.is_some_and(|h| h.depth);
    if host_depth {
        // The host's texture, where resolve's depth pass writes.
        p.resources.retain(|r| r.name != DEPTH);
        p.add_resource(
            ResourceEntry::texture_sized_by(
                DEPTH,
                EntryKind::Imported,
                &depth_format,
                "width",
                "height",
            )
            .with_usage(&["RENDER_ATTACHMENT"]),
        )?;
    } else if s.depth && p.resource(DEPTH).is_none() {
        p.add_resource(exported(DEPTH))?;
    }
    if let Some(HostTargets { color, .. }) = s.host {
        if p.resource(HOST_TARGET).is_some() {
            return Err(GraphError::PipelineFile {
                file: p.file().to_string(),
                message: format!(
                    "it declares `{HOST_TARGET}`, the name the renderer gives a host's colour texture; rename that resource"
                ),
            });
        }
        p.add_resource(
            ResourceEntry::texture_sized_by(
                HOST_TARGET,
                EntryKind::Imported,
                &format_text(color),
                "width",
                "height",
            )
            .with_usage(&["RENDER_ATTACHMENT"]),
        )?;
        // The image is drawn into the host's texture; nobody reads it back.
        for r in p.resources.iter_mut().filter(|r| r.name == COLOR) {
            r.kind = EntryKind::Transient;
        }
        p.passes.push(PassEntry::new(
            "present",
            meshlight::present::STAGE,
            "fullscreen",
        ));
    }
    Ok(())
}

/// Whether `e` is a second culling pass's walk or cull (`mode = "second"`): it re-tests
/// what the first pass hid against this frame's pyramid.
pub fn is_second_pass(e: &PassEntry) -> bool {
    e.param_str("mode") == Some(meshlight::gpu_scene::Phase::Second.name())
}

/// The counters come back [`COUNTS_LATENCY`] frames later; the graph needs a resource
/// named `raster_counts`, and the camera's list words where its first fill writes them
/// ([`camera_list_words`]; a pipeline file too). With a second culling pass (a resource
/// named [`SECOND_COUNTS`]) both passes' words come back, twelve each.
fn add_readbacks(g: &mut GraphBuilder, p: &Pipeline) -> Result<()> {
    let (resource, list) = camera_list_words(p);
    g.readback_named(
        CLUSTER_COUNT_READBACK,
        &resource,
        Some(8 * list..8 * list + 8),
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
