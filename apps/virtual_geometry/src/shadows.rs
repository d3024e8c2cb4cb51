//! The sun's shadow in the frame: the pipeline's shadow stage (every pass and resource
//! over the view set [`CASCADES`]) sized for [`ShadowSettings`] or taken out, each
//! frame's cascades ([`meshlight::gpu_scene::cascades`]) handed to the passes as frame
//! inputs, and the cascades' counters read back so their lists grow like the camera's.
//!
//! A shadow pass is told from the camera's by its `views`: the renderer's settings that
//! concern the camera's passes only (the occlusion view's records) leave the shadow
//! passes as the file wrote them, and a streamed scene's shadow culls add their page
//! requests to the camera's. By default the camera's first walk serves the cascades
//! too ([`ShadowWalk`]).

use super::settings::{FrameSettings, ShadowSettings};
use meshlight::gpu_scene::Camera;
use meshlight::gpu_scene::cascades::{Cascade, cascades};
use meshlight::graph::file::{PassEntry, Pipeline, Registry};
use meshlight::graph::{FrameData, GraphBuilder, GraphError, Result};
use meshlight::resolve::shadows::{SHADOW_MAPS, SHADOWS_INPUT, ShadowParams};

/// The view set the shadow stage's entries run over, one view per cascade.
pub const CASCADES: &str = "cascades";
/// The frame input each cascade's passes read their View from (`{view}` its number).
pub const CASCADE_VIEW_INPUT: &str = "cascade_view_{view}";
/// The size parameter of each cascade's map side.
pub const RESOLUTION_PARAM: &str = "shadow_resolution";
/// The size parameter of the maps' texels (cascades × side²).
pub const TEXELS_PARAM: &str = "shadow_texels";
/// The frame input a walk over every cascade reads: their Views back to back (a
/// cascade left out of the frame given a zeroed View, which the walk skips).
pub const CASCADE_VIEWS_INPUT: &str = "cascade_views";
/// The frame input of the camera's first walk when it walks the cascades too
/// ([`ShadowWalk::WithCamera`]): the cascades' Views as in [`CASCADE_VIEWS_INPUT`], then
/// the camera's.
pub const WALK_VIEWS_INPUT: &str = "walk_views";
/// Each cascade's culling counters (`cull_lod`'s `raster_counts`), read back.
pub const RASTER_COUNTS: &str = "shadow_raster_counts_{view}";
/// The cascades' candidate counts (`fill_clusters`' `cluster_count`, two words a
/// cascade), read back.
pub const CLUSTER_COUNTS: &str = "shadow_cluster_counts";
/// The size parameter of the cascades' candidate lists, side by side (cascades ×
/// candidates a cascade may list).
pub const CANDIDATES_PARAM: &str = "shadow_candidates";

/// True for an entry of the shadow stage.
pub fn is_shadow(e: &PassEntry) -> bool {
    e.views.as_deref() == Some(CASCADES)
}

/// True for a shadow entry that is one pass for every cascade (its name holds no
/// `{view}`): the walk over all cascades.
fn is_whole_set(name: &str) -> bool {
    !name.contains("{view}")
}

/// How the cascades' candidates are listed. Each lists the same clusters for each view
/// (the tests compare them); they differ in how many walks run and so in time.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum ShadowWalk {
    /// One walk for every view: the camera's first walk serves the cascades too
    /// ([`walk_with_camera`]), occlusion tested for the camera alone. One chain of
    /// dispatches fewer than [`ShadowWalk::AsWritten`]; on an NVIDIA H200 (`meshlight
    /// bench --scenario vg-shadows`, docs/BENCHMARKS.md) 0.07 ms faster on the million
    /// bunnies with the cascades drawn and 0.04 ms with them kept, and on the default
    /// scene within run-to-run noise of the walks as written (its walks 0.03 ms shorter
    /// in the profile). The camera's `hierarchy_counts` then count the nodes tested for
    /// every view. Where there is no such walk to fold (the flat
    /// fill lists each view on its own; a file that walks its cascades per view, or
    /// has no first walk for the camera) the file's passes run as written.
    #[default]
    WithCamera,
    /// As the pipeline file says (the shipped files: the camera's walk, and one walk
    /// for every cascade after the camera's passes).
    AsWritten,
    /// A walk per cascade: the file's walk over every cascade is split into one pass
    /// per cascade, each writing its own list (for comparisons).
    PerView,
}

/// The lists of the shadow stage's buffers for `cascades` cascades: one per cascade,
/// and the camera's after them where `p`'s camera walk serves the cascades
/// ([`walk_with_camera`] folded them).
pub fn list_count(p: &Pipeline, cascades: u32) -> u32 {
    let folded = p.passes.iter().any(|e| {
        !is_shadow(e)
            && e.stage == meshlight::fill_clusters::STAGE
            && e.param("views").and_then(toml::Value::as_integer) > Some(1)
    });
    cascades + u32::from(folded)
}

/// Folds the walk over every cascade into the camera's first walk, which then serves
/// `cascades + 1` views: the cascades' (lists `0 .. cascades` of the shadow stage's
/// buffers, as before) and the camera's last (list `cascades`, occlusion tested for it
/// alone; its first cull reads that list). The camera's walk keeps its place at the
/// frame's start and its hidden nodes still go to the second walk; the shadow walk's
/// pass goes, and so does what only it wrote (its counters). Returns false, changing
/// nothing, where the pipeline has no walk over every cascade or no first walk for the
/// camera.
pub fn walk_with_camera(p: &mut Pipeline, registry: &Registry, cascades: u32) -> Result<bool> {
    use meshlight::fill_clusters::{STAGE as FILL, VIEW_INPUT};
    let Some(shadow_walk) = p
        .passes
        .iter()
        .find(|e| is_shadow(e) && is_whole_set(&e.name) && e.stage == FILL)
    else {
        return Ok(false);
    };
    let shadow_walk_name = shadow_walk.name.clone();
    let lists_of = |slot: &'static str| shadow_walk.binding(slot).unwrap_or(slot).to_string();
    let (clusters, counts) = (lists_of("clusters"), lists_of("cluster_count"));
    let lists = cascades + 1;
    let Some(camera) = p.passes.iter_mut().find(|e| {
        !is_shadow(e)
            && e.stage == FILL
            && e.implementation == meshlight::fill_clusters::hierarchy::IMPLEMENTATION
            && !super::frame_graph::is_second_pass(e)
    }) else {
        return Ok(false);
    };
    let camera_list = camera.binding("clusters").unwrap_or("clusters").to_string();
    for (key, value) in [
        ("views", lists),
        ("occlusion_view", cascades),
        // View v's list is `list + v`: the cascades' first, the camera's last.
        ("list", 0),
        ("lists", lists),
    ] {
        camera.set_param(key, i64::from(value));
    }
    camera.bind("clusters", &clusters);
    camera.bind("cluster_count", &counts);
    camera
        .inputs
        .insert(VIEW_INPUT.to_string(), WALK_VIEWS_INPUT.to_string());
    for pass in p.passes_of_mut(meshlight::cull_lod::STAGE) {
        if is_shadow(pass) {
            pass.set_param("lists", i64::from(lists));
        } else if pass.binding("clusters").unwrap_or("clusters") == camera_list {
            pass.bind("clusters", &clusters);
            pass.bind("cluster_count", &counts);
            pass.set_param("list", i64::from(cascades));
            pass.set_param("lists", i64::from(lists));
        }
    }
    // Two words a list: a fixed count written for the cascades alone grows by the
    // camera's two.
    if let Some(b) = p
        .resources
        .iter_mut()
        .find(|r| r.name == counts)
        .and_then(|r| r.buffer.as_mut())
        && let Some(words) = &mut b.count
    {
        *words = (*words).max(2 * u64::from(lists));
    }
    p.remove_passes(registry, |e| e.name == shadow_walk_name)?;
    Ok(true)
}

/// Splits the walk over every cascade into a walk per cascade (each view's own pass,
/// reading `cascade_view_{view}` and writing list `{view}`), in the same place of the
/// frame. A pipeline that walks per cascade already is left as it is.
pub fn walk_per_view(p: &mut Pipeline) {
    for pass in p.passes.iter_mut().filter(|e| {
        is_shadow(e) && is_whole_set(&e.name) && e.stage == meshlight::fill_clusters::STAGE
    }) {
        pass.name = format!("{}_{{view}}", pass.name);
        pass.params.remove("views");
        pass.set_param("list", "{view}");
        pass.set_param("lists", format!("${CASCADES}"));
        pass.inputs.insert(
            meshlight::fill_clusters::VIEW_INPUT.to_string(),
            CASCADE_VIEW_INPUT.to_string(),
        );
    }
}

/// Sizes the shadow stage for `s.shadows`, or takes it out (its passes, and the
/// resources only it uses, `shadow_maps` among them, so resolve binds none). Shadows
/// asked of a pipeline without the stage are an error saying what to add.
pub fn apply(p: &mut Pipeline, registry: &Registry, s: &FrameSettings) -> Result<()> {
    let has_stage = p.passes.iter().any(is_shadow);
    let Some(shadows) = s.shadows else {
        if has_stage {
            p.remove_passes(registry, is_shadow)?;
            let unused: Vec<String> = p
                .resources
                .iter()
                .filter(|r| r.views.as_deref() == Some(CASCADES) || r.name == SHADOW_MAPS)
                .map(|r| r.name.clone())
                .collect();
            for name in unused {
                p.remove_resource(&name);
            }
            p.views.remove(CASCADES);
        }
        return Ok(());
    };
    shadows.validate()?;
    if !has_stage || !p.views.contains_key(CASCADES) {
        return Err(GraphError::PipelineFile {
            file: p.file().to_string(),
            message: format!(
                "shadows are asked for, but the pipeline has no shadow stage (passes over the view set `{CASCADES}`); render without shadows (`--shadow-cascades 0`), or add the stage as pipelines/virtual_geometry.toml does"
            ),
        });
    }
    let c = shadows.cascades;
    p.views.insert(CASCADES.to_string(), c.count);
    match shadows.walk {
        ShadowWalk::AsWritten => {}
        ShadowWalk::PerView => walk_per_view(p),
        ShadowWalk::WithCamera => {
            // The flat fill lists each view on its own.
            let flat = !s.hierarchy
                || s.implementations.iter().any(|(stage, i)| {
                    stage == meshlight::fill_clusters::STAGE && i == super::frame_graph::FLAT_FILL
                });
            if !flat {
                walk_with_camera(p, registry, c.count)?;
            }
        }
    }
    let side = u64::from(c.resolution);
    for (name, value) in [
        (RESOLUTION_PARAM, side),
        (TEXELS_PARAM, u64::from(c.count) * side * side),
    ] {
        if p.param(name).is_some() {
            p.set_param(name, value)?;
        }
    }
    Ok(())
}

/// After the camera's sizes are set: each cascade's candidate list as long as the
/// camera's (`shadow_candidates` = cascades × `clusters`).
pub fn size_lists(p: &mut Pipeline, s: &FrameSettings) -> Result<()> {
    let Some(shadows) = s.shadows else {
        return Ok(());
    };
    if let (Some(clusters), true) = (
        p.param(super::frame_graph::CLUSTERS_PARAM),
        p.param(CANDIDATES_PARAM).is_some(),
    ) {
        let lists = u64::from(list_count(p, shadows.cascades.count).max(1));
        p.set_param(CANDIDATES_PARAM, clusters * lists)?;
    }
    Ok(())
}

/// The readbacks of each cascade's counters (the cull's first eight words) and of the
/// candidate counts (two words a cascade), [`super::frame_graph::COUNTS_LATENCY`]
/// frames late.
pub fn add_readbacks(g: &mut GraphBuilder, count: u32) -> Result<()> {
    let per_view = (0..count).map(|k| (view_name(RASTER_COUNTS, k), 32));
    let shared = (count > 0).then(|| (CLUSTER_COUNTS.to_string(), 8 * u64::from(count)));
    for (name, bytes) in per_view.chain(shared) {
        if g.resource(&name).is_some() {
            g.readback_named(
                &name,
                &name,
                Some(0..bytes),
                super::frame_graph::COUNTS_LATENCY,
            )?;
        }
    }
    Ok(())
}

/// One cascade's counters, as its culling pass and its walk left them.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct CascadeCounts {
    /// The cascade, 0 the nearest.
    pub cascade: u32,
    /// The frame they were counted in.
    pub frame: u64,
    /// Candidates the walk listed (may exceed the list).
    pub candidates_requested: u32,
    /// Clusters that passed the frustum and LOD tests (slots requested).
    pub visible: u32,
    /// Clusters drawn, by both rasterisers.
    pub drawn: u32,
    /// Triangles drawn.
    pub triangles: u32,
}

impl CascadeCounts {
    /// From the cull's `raster_counts` (eight words) and the walk's `cluster_count` (two
    /// words a cascade).
    pub fn from_words(cascade: u32, frame: u64, cull: &[u8], fill: &[u8]) -> Option<Self> {
        let word = |b: &[u8], i: usize| {
            b.get(i * 4..i * 4 + 4)
                .map(|w| u32::from_le_bytes(w.try_into().expect("four bytes")))
        };
        Some(Self {
            cascade,
            frame,
            candidates_requested: word(fill, 2 * cascade as usize + 1)?,
            visible: word(cull, 2)?,
            drawn: word(cull, 0)? + word(cull, 1)?,
            triangles: word(cull, 5)? + word(cull, 6)?,
        })
    }
}

/// Each instance's world bounding sphere (centre, radius).
fn instance_spheres(
    data: &meshlight::gpu_scene::SceneData,
) -> impl Iterator<Item = (glam::Vec3, f32)> + '_ {
    data.instances.iter().filter_map(|i| {
        let mesh = data.meshes.get(i.mesh as usize)?;
        let m = glam::Mat4::from_cols_array_2d(&i.world_from_local);
        let [x, y, z, r] = mesh.bounding_sphere;
        let centre = m.transform_point3(glam::Vec3::new(x, y, z));
        let scale = m
            .x_axis
            .length()
            .max(m.y_axis.length())
            .max(m.z_axis.length());
        let radius = r * scale;
        (centre.is_finite() && radius.is_finite()).then_some((centre, radius))
    })
}

/// How far the scene reaches from `from`: the farthest instance's bounding sphere's
/// far side (0 for an empty scene).
pub fn scene_reach(data: &meshlight::gpu_scene::SceneData, from: glam::Vec3) -> f32 {
    instance_spheres(data)
        .map(|(c, r)| c.distance(from) + r)
        .fold(0.0, f32::max)
}

/// Pixels across which the median instance is still worth a shadow: past the distance
/// where it looks this small, [`shadow_distance`] ends the shadow.
pub const SHADOWED_PIXELS: f32 = 8.0;

/// The default shadow distance for a scene seen by `camera` in `viewport`: where the
/// median instance's bounding sphere spans [`SHADOWED_PIXELS`] pixels (its shadow a few
/// pixels more), or the scene's far side if nearer. A field of small copies so gets
/// shadows as far as they can be told apart, not across the whole field; an
/// orthographic camera (whose pixels do not shrink with distance) gets the whole scene.
pub fn shadow_distance(
    data: &meshlight::gpu_scene::SceneData,
    camera: &meshlight::gpu_scene::Camera,
    viewport: [u32; 2],
) -> f32 {
    let reach = scene_reach(data, camera.position);
    let projection = camera.projection_matrix(viewport);
    // Pixels per world unit at distance 1: half the viewport's height times the
    // projection's y scale.
    let pixels_at_one = 0.5 * viewport[1].max(1) as f32 * projection.y_axis.y;
    let mut radii: Vec<f32> = instance_spheres(data).map(|(_, r)| r).collect();
    if radii.is_empty()
        || projection.w_axis.w != 0.0
        || pixels_at_one.is_nan()
        || pixels_at_one <= 0.0
    {
        return reach;
    }
    let mid = radii.len() / 2;
    let median = *radii.select_nth_unstable_by(mid, f32::total_cmp).1;
    // The sphere spans 2 · r · pixels_at_one / d pixels.
    let far = 2.0 * median * pixels_at_one / SHADOWED_PIXELS;
    if far.is_finite() && far > 0.0 {
        far.min(reach)
    } else {
        reach
    }
}

/// `name` of view `k`.
pub fn view_name(name: &str, k: u32) -> String {
    name.replace("{view}", &k.to_string())
}

/// A frame's shadow inputs: each cascade's View, and the resolve's [`ShadowParams`].
pub struct ShadowFrame {
    /// The cascades, nearest first.
    pub cascades: Vec<Cascade>,
    /// What the resolve reads.
    pub params: ShadowParams,
}

impl ShadowFrame {
    /// The cascades of `camera` for a `viewport`, the sun shining from `toward_light`;
    /// `lod_scale` divides each cascade view's LOD scale as it does the camera's (a
    /// streamed pool under pressure coarsens both), and so does `2^lod_bias`: an error
    /// of `2^lod_bias` texels in a cascade counts as one, so its cut meets the camera's
    /// pixel threshold with that many texels. In the View, not the threshold, so that
    /// one walk compares every view with the camera's threshold and each cascade's cull
    /// agrees with it.
    pub fn new(
        camera: &Camera,
        viewport: [u32; 2],
        toward_light: glam::Vec3,
        shadows: &ShadowSettings,
        frame_index: u32,
        lod_scale: f32,
    ) -> Result<Self> {
        let mut list = cascades(
            camera,
            viewport,
            toward_light,
            &shadows.cascades,
            frame_index,
        )
        .map_err(|e| GraphError::Setting {
            setting: "shadows".into(),
            message: e.to_string(),
        })?;
        let coarsen = lod_scale * shadows.lod_bias.exp2();
        for c in &mut list {
            c.view.lod_scale /= coarsen;
        }
        let params = ShadowParams::new(
            &list,
            shadows.cascades.resolution,
            shadows.normal_bias,
            shadows.depth_bias,
        );
        Ok(Self {
            cascades: list,
            params,
        })
    }

    /// `frame` with every cascade's View (each, and all back to back) and the
    /// resolve's parameters.
    pub fn add_to(&self, mut frame: FrameData) -> FrameData {
        for (k, c) in self.cascades.iter().enumerate() {
            frame = frame.with(
                &view_name(CASCADE_VIEW_INPUT, k as u32),
                bytemuck::bytes_of(&c.view),
            );
        }
        let views: Vec<_> = self.cascades.iter().map(|c| c.view).collect();
        frame
            .with(CASCADE_VIEWS_INPUT, bytemuck::cast_slice(&views))
            .with(SHADOWS_INPUT, bytemuck::bytes_of(&self.params))
    }
}

/// The cascades' maps, which the renderer owns so that they outlive the frame, and what
/// each layer was last drawn with: a cascade whose view and scene are unchanged since
/// is left out of the frame ([`ShadowSettings::cache`]).
#[derive(Default)]
pub struct ShadowCache {
    maps: Option<wgpu::Buffer>,
    /// Per cascade, the view its layer holds (its frame index zeroed); `None`: not drawn
    /// since the maps were made.
    drawn: Vec<Option<meshlight::shaders::cpu::layout::View>>,
    /// The shadow stage's pass names, `{view}` unreplaced (with their readbacks').
    passes: Vec<String>,
}

impl ShadowCache {
    /// Maps for `count` cascades of `resolution²` (none for 0, or where the pipeline
    /// keeps `shadow_maps` itself instead of importing it: then nothing is kept), the
    /// frame's shadow passes taken from `pipeline`; every layer is drawn by the next
    /// frame.
    pub fn reset(
        &mut self,
        gpu: &meshlight::graph::GpuContext,
        count: u32,
        resolution: u32,
        pipeline: &Pipeline,
    ) {
        let bytes = u64::from(count) * u64::from(resolution) * u64::from(resolution) * 4;
        self.drawn = vec![None; count as usize];
        self.passes = pipeline
            .passes
            .iter()
            .filter(|e| is_shadow(e))
            .map(|e| e.name.clone())
            .chain([RASTER_COUNTS, CLUSTER_COUNTS].map(|n| format!("readback:{n}")))
            .collect();
        let imported = pipeline
            .resource(SHADOW_MAPS)
            .is_some_and(|r| r.kind == meshlight::graph::file::EntryKind::Imported);
        if bytes == 0 || !imported {
            self.maps = None;
            self.drawn.clear();
        } else if self.maps.as_ref().is_none_or(|b| b.size() != bytes) {
            self.maps = Some(gpu.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(SHADOW_MAPS),
                size: bytes,
                usage: wgpu::BufferUsages::STORAGE
                    | wgpu::BufferUsages::COPY_DST
                    | wgpu::BufferUsages::COPY_SRC,
                mapped_at_creation: false,
            }));
        }
    }

    /// The maps, `count × resolution²` words of reverse-Z depth bits.
    pub fn maps(&self) -> Option<&wgpu::Buffer> {
        self.maps.as_ref()
    }

    /// Leaves out of `data` the passes of every cascade whose layer already holds
    /// `frame`'s view of an unchanged scene (with `cache`), and notes the others as drawn.
    /// The walk over every cascade runs while one is drawn, given a zeroed View for each
    /// cascade left out (so it lists nothing for it); so does the camera's walk when it
    /// serves the cascades, given those Views and then `camera`'s
    /// ([`WALK_VIEWS_INPUT`]). Returns how many cascades are drawn.
    pub fn skip_unchanged(
        &mut self,
        frame: &ShadowFrame,
        scene_changed: bool,
        cache: bool,
        camera: &meshlight::shaders::cpu::layout::View,
        data: &mut FrameData,
    ) -> u32 {
        let mut drawn = 0;
        let mut views = Vec::with_capacity(frame.cascades.len());
        for (k, c) in frame.cascades.iter().enumerate() {
            let mut view = c.view;
            view.frame_index = 0;
            let Some(slot) = self.drawn.get_mut(k) else {
                drawn += 1;
                views.push(c.view);
                continue;
            };
            let same = slot.is_some_and(|v| bytemuck::bytes_of(&v) == bytemuck::bytes_of(&view));
            if cache && same && !scene_changed {
                for name in self.passes.iter().filter(|n| !is_whole_set(n)) {
                    data.skip(&view_name(name, k as u32));
                }
                views.push(meshlight::shaders::cpu::layout::View::default());
            } else {
                *slot = Some(view);
                drawn += 1;
                views.push(c.view);
            }
        }
        if drawn == 0 {
            for name in self.passes.iter().filter(|n| is_whole_set(n)) {
                data.skip(name);
            }
        }
        data.set(CASCADE_VIEWS_INPUT, bytemuck::cast_slice(&views));
        views.push(*camera);
        data.set(WALK_VIEWS_INPUT, bytemuck::cast_slice(&views));
        drawn
    }
}
