//! The CPU reference of `cull_lod`: the shared WGSL it calls (`instance_max_scale`,
//! `instance_transform_point`, `sphere_in_frustum`; the LOD cut is
//! `meshlight_shaders::cpu::lod`'s, the one mirror of it) and its own `is_software`,
//! mirrored operation for operation in f32 (matrix times vector summed column by column,
//! dot products left to right).
//!
//! A decision can still differ from the GPU's when a value lies within rounding of its
//! threshold (a GPU may fuse a multiply and an add); [`Decision`] keeps the values each
//! decision compared, so a test can tell such a cluster from a real disagreement.

use meshlight_gpu_scene::SceneData;
use meshlight_scene::asset::format::NO_GROUP;
use meshlight_shaders::cpu::layout::{Cluster, Instance, View};
use meshlight_shaders::cpu::lod::lod_cut;
use meshlight_shaders::cpu::matrix::{mat_vec, transform_point};
use meshlight_shaders::cpu::occlusion::{DepthPyramid, OcclusionRect, occlusion_rect};

/// `draw_indirect` vertex count of one hardware cluster (128 triangles × 3).
pub const HW_VERTICES: u32 = 384;

/// The thresholds the pass compares with (its params).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Thresholds {
    /// Pixels of error the cut may show: `lod_threshold_px`.
    pub lod_threshold_px: f32,
    /// Screen-box size under which a cluster goes to software: `sw_threshold_px`.
    pub sw_threshold_px: f32,
    /// `false`: every cluster of the cut goes to software, for pipelines with no
    /// hardware rasteriser (sw_raster clips the clusters crossing the near plane).
    pub hardware: bool,
}

impl Default for Thresholds {
    fn default() -> Self {
        Self {
            lod_threshold_px: 1.0,
            sw_threshold_px: 128.0,
            hardware: true,
        }
    }
}

/// What the pass decides for one cluster, with the values it compared.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Decision {
    /// Smallest `dot(plane.xyz, centre) + plane.w + radius`: in the frustum when >= 0.
    pub frustum_margin: f32,
    /// Whether the sphere touches the frustum (the first test; nothing else runs without it).
    pub in_frustum: bool,
    /// Own and parent error in pixels (`f32::MAX` parent for a root: never projected).
    pub own_px: f32,
    /// The parent group's error in pixels, compared after `own_px`.
    pub parent_px: f32,
    /// Whether the cluster is in the LOD cut: own error hidden, parent's shown.
    pub in_cut: bool,
    /// Distance of the sphere's centre beyond the near plane, minus its radius.
    pub near_margin: f32,
    /// Screen box of the sphere (0 when it reaches the near plane: not computed).
    pub box_size: [f32; 2],
    /// Whether the cluster goes to the software rasteriser.
    pub software: bool,
    /// The world-space radius, for scaling the frustum and near margins.
    pub radius: f32,
    /// Once in the cut with the occlusion test on: the sphere's rectangle, and the
    /// farthest depth the pyramid holds under it (when testable).
    pub occlusion: Option<(OcclusionRect, f32)>,
    /// Whether the pyramid proved the cluster hidden (it then takes no raster slot).
    pub occluded: bool,
}

impl Decision {
    /// How close the decisions that matter for this cluster came to flipping, relative to
    /// what was compared: the smallest of the frustum margin (over the radius), and, once
    /// in the frustum, each error's distance from the LOD threshold and, once in the cut,
    /// the near margin and the box sizes' distance from the software threshold (all over
    /// their thresholds).
    pub fn closeness(&self, t: &Thresholds) -> f32 {
        let rel = |v: f32, to: f32| (v - to).abs() / to.abs().max(f32::MIN_POSITIVE);
        let mut c = self.frustum_margin.abs() / self.radius.max(f32::MIN_POSITIVE);
        if !self.in_frustum {
            return c;
        }
        c = c.min(rel(self.own_px, t.lod_threshold_px));
        if self.parent_px < f32::MAX {
            c = c.min(rel(self.parent_px, t.lod_threshold_px));
        }
        if !self.in_cut {
            return c;
        }
        if let Some((rect, farthest)) = self.occlusion
            && rect.testable
        {
            // The depth comparison, and each rectangle edge's distance from the pixel
            // boundary where its truncation would change.
            let nearest = rect.depth * meshlight_shaders::cpu::occlusion::DEPTH_SLACK;
            c = c.min(rel(nearest, farthest));
            let margin = meshlight_shaders::cpu::occlusion::MARGIN_PX;
            for (v, m) in rect.screen.iter().zip([-margin, -margin, margin, margin]) {
                let edge = v + m;
                let frac = (edge - edge.round()).abs();
                c = c.min(frac / edge.abs().max(1.0));
            }
        }
        if self.occluded {
            return c;
        }
        c = c.min(self.near_margin.abs() / self.radius.max(f32::MIN_POSITIVE));
        if self.near_margin > 0.0 {
            c = c
                .min(rel(self.box_size[0], t.sw_threshold_px))
                .min(rel(self.box_size[1], t.sw_threshold_px));
        }
        c
    }
}

/// What `cull_lod` produces for a cluster list.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct CullResult {
    /// Clusters whose bounding sphere touches the frustum, in list order.
    pub frustum: Vec<Cluster>,
    /// Of those, the ones in the LOD cut that the occlusion test kept (each wants a
    /// raster slot), in list order.
    pub cut: Vec<Cluster>,
    /// The cut split by rasteriser (every cut cluster, whether or not a slot was free).
    pub software: Vec<Cluster>,
    /// The cut clusters the hardware rasteriser takes.
    pub hardware: Vec<Cluster>,
    /// Cut clusters the pyramid proved hidden, in list order: the first pass's
    /// candidates (`occluded`), or what the second pass culled.
    pub occluded: Vec<Cluster>,
    /// `raster_counts`. Words 0, 1, 5 and 6 count the clusters that got a slot; when the
    /// cut exceeds the capacity, which ones do depends on the GPU's atomics, and the
    /// reference gives the slots in list order. Words 8..12 are 0 without occlusion, and
    /// words 8, 9 and 11 when the test is skipped.
    pub counts: [u32; 12],
    /// `hw_args`: `[384, counts[1], 0, 0]`.
    pub hw_args: [u32; 4],
}

fn dot3(a: [f32; 3], b: [f32; 3]) -> f32 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

fn xyz(v: [f32; 4]) -> [f32; 3] {
    [v[0], v[1], v[2]]
}

/// `instance_max_scale`.
pub fn instance_max_scale(instance: &Instance) -> f32 {
    meshlight_shaders::cpu::lod::instance_max_scale(&instance.world_from_local)
}

/// `sphere_in_frustum` (a NaN distance keeps the sphere, as the WGSL's `<` does) and the
/// smallest margin over the planes.
#[allow(clippy::neg_cmp_op_on_partial_ord)]
pub fn sphere_in_frustum(view: &View, center: [f32; 3], radius: f32) -> (bool, f32) {
    let mut inside = true;
    let mut margin = f32::INFINITY;
    for p in &view.frustum {
        let d = dot3(xyz(*p), center) + p[3];
        inside &= !(d < -radius);
        margin = margin.min(d + radius);
    }
    (inside, margin)
}

/// `is_software`: (software, near margin, screen box size).
pub fn is_software(
    view: &View,
    center: [f32; 3],
    radius: f32,
    threshold: f32,
) -> (bool, f32, [f32; 2]) {
    // The view's near plane (view-space depth `near`), as cull.wgsl measures it.
    let c = transform_point(&view.view, center);
    let near_distance = -c[2] - view.near;
    if near_distance <= radius {
        return (false, near_distance - radius, [0.0; 2]);
    }
    let mut lo = [f32::MAX; 2];
    let mut hi = [-f32::MAX; 2];
    for k in 0..8u32 {
        let pick = |bit: u32| if k & bit != 0 { radius } else { -radius };
        let corner = [c[0] + pick(1), c[1] + pick(2), c[2] + pick(4), 1.0];
        let clip = mat_vec(&view.projection, corner);
        let ndc = [clip[0] / clip[3], clip[1] / clip[3]];
        let screen = [
            (ndc[0] * 0.5 + 0.5) * view.viewport_size[0],
            (0.5 - ndc[1] * 0.5) * view.viewport_size[1],
        ];
        for a in 0..2 {
            lo[a] = lo[a].min(screen[a]);
            hi[a] = hi[a].max(screen[a]);
        }
    }
    let size = [hi[0] - lo[0], hi[1] - lo[1]];
    (
        size[0] < threshold && size[1] < threshold,
        near_distance - radius,
        size,
    )
}

/// The occlusion side of a culling pass.
#[derive(Clone, Copy, Debug, Default)]
pub enum Occlusion<'a> {
    /// No pyramid bound, or the first pass skipping the test (no valid history, camera
    /// cut): nothing is occluded.
    #[default]
    Off,
    /// A pyramid bound but the first pass's test skipped (no valid history, camera cut):
    /// nothing is occluded, and the occlusion words are counted.
    Skipped,
    /// The first pass against last frame's pyramid (previous view-projection and
    /// instance transforms).
    First(&'a DepthPyramid),
    /// The second pass against this frame's, given the first pass's `raster_counts`.
    Second {
        /// This frame's pyramid, built from what the first pass drew.
        pyramid: &'a DepthPyramid,
        /// The first pass's `raster_counts`, whose software and hardware ends bound the free slots.
        first_counts: [u32; 12],
    },
}

/// `is_occluded`: the rectangle, the pyramid's farthest depth under it, and the verdict.
pub fn occlusion_test(
    scene: &SceneData,
    view: &View,
    cluster: Cluster,
    pyramid: &DepthPyramid,
    previous: bool,
) -> (OcclusionRect, f32, bool) {
    let mut seen = scene.instances[cluster.instance as usize];
    let mut view_projection = view.view_projection;
    if previous {
        seen.world_from_local = seen.previous_world_from_local;
        view_projection = view.previous_view_projection;
    }
    let bounds = scene.meshlets[cluster.meshlet as usize].bounds;
    let center = transform_point(&seen.world_from_local, xyz(bounds));
    let radius = bounds[3] * instance_max_scale(&seen);
    let rect = occlusion_rect(&view_projection, view.viewport_size, center, radius);
    let farthest = if rect.testable {
        pyramid.farthest(rect.pixels)
    } else {
        0.0
    };
    (rect, farthest, pyramid.occludes(&rect))
}

/// The LOD test of one cluster, whatever the frustum says: `lod_cut` with the own and
/// parent spheres and errors the scene's groups give it (as the GPU reads them, so on a
/// streamed scene the cut over resident pages). (in the cut, own px, parent px).
pub fn lod_test(
    scene: &SceneData,
    view: &View,
    cluster: Cluster,
    threshold: f32,
) -> (bool, f32, f32) {
    let instance = &scene.instances[cluster.instance as usize];
    let meshlet = &scene.meshlets[cluster.meshlet as usize];
    let (own_sphere, own_error) = scene.own_lod(meshlet);
    let (parent_sphere, parent_error) = scene.parent_lod(meshlet);
    lod_cut(
        view,
        &instance.world_from_local,
        instance_max_scale(instance),
        own_sphere,
        own_error,
        parent_sphere,
        parent_error,
        threshold,
    )
}

/// Everything the pass decides for one cluster (no occlusion test).
pub fn classify(scene: &SceneData, view: &View, cluster: Cluster, t: &Thresholds) -> Decision {
    classify_with(scene, view, cluster, t, Occlusion::Off)
}

/// Everything the pass decides for one cluster.
pub fn classify_with(
    scene: &SceneData,
    view: &View,
    cluster: Cluster,
    t: &Thresholds,
    occlusion: Occlusion,
) -> Decision {
    let instance = &scene.instances[cluster.instance as usize];
    let meshlet = &scene.meshlets[cluster.meshlet as usize];
    let scale = instance_max_scale(instance);
    let bounds = meshlet.bounds;
    let center = transform_point(&instance.world_from_local, xyz(bounds));
    let radius = bounds[3] * scale;
    let (in_frustum, frustum_margin) = sphere_in_frustum(view, center, radius);
    let mut d = Decision {
        frustum_margin,
        in_frustum,
        radius,
        ..Decision::default()
    };
    if !in_frustum {
        return d;
    }
    let (in_cut, own_px, parent_px) = lod_test(scene, view, cluster, t.lod_threshold_px);
    d.in_cut = in_cut;
    d.own_px = own_px;
    d.parent_px = parent_px;
    if !in_cut {
        return d;
    }
    let tested = match occlusion {
        Occlusion::Off | Occlusion::Skipped => None,
        Occlusion::First(pyramid) => Some((pyramid, true)),
        Occlusion::Second { pyramid, .. } => Some((pyramid, false)),
    };
    if let Some((pyramid, previous)) = tested {
        let (rect, farthest, occluded) = occlusion_test(scene, view, cluster, pyramid, previous);
        d.occlusion = Some((rect, farthest));
        d.occluded = occluded;
        if occluded {
            return d;
        }
    }
    let (software, near_margin, box_size) = is_software(view, center, radius, t.sw_threshold_px);
    d.software = software || !t.hardware;
    d.near_margin = near_margin;
    d.box_size = box_size;
    d
}

/// The reference over a cluster list, for a raster list of `capacity` slots.
pub fn cpu_cull(
    scene: &SceneData,
    view: &View,
    clusters: &[Cluster],
    thresholds: &Thresholds,
    capacity: u32,
) -> CullResult {
    cpu_cull_with(scene, view, clusters, thresholds, capacity, Occlusion::Off)
}

/// The slots a pass may fill, `[start, end)`: `slot_range` of the WGSL.
pub fn slot_range(capacity: u32, occlusion: Occlusion) -> (u32, u32) {
    match occlusion {
        Occlusion::Second { first_counts, .. } => {
            let c = first_counts[3].min(capacity);
            let top = c - first_counts[1].min(c);
            (first_counts[0].min(top), top)
        }
        _ => (0, capacity),
    }
}

/// The reference with the occlusion test: `clusters` is the first pass's candidate list
/// (`fill_clusters`' output) or the second pass's (the first pass's `occluded`);
/// `capacity` is the pass's own (`C`, the list's length unless the param lowers it).
pub fn cpu_cull_with(
    scene: &SceneData,
    view: &View,
    clusters: &[Cluster],
    thresholds: &Thresholds,
    capacity: u32,
    occlusion: Occlusion,
) -> CullResult {
    let mut r = CullResult::default();
    let (start, end) = slot_range(capacity, occlusion);
    let slots = end - start;
    let mut wanted = 0u32;
    for &cluster in clusters {
        let d = classify_with(scene, view, cluster, thresholds, occlusion);
        if !d.in_frustum {
            continue;
        }
        r.frustum.push(cluster);
        if !d.in_cut {
            continue;
        }
        r.counts[8] += 1;
        if d.occlusion.is_some_and(|(rect, _)| rect.testable) {
            r.counts[11] += 1;
        }
        if d.occluded {
            r.occluded.push(cluster);
            continue;
        }
        let slot_free = wanted < slots;
        wanted += 1;
        r.cut.push(cluster);
        let triangles = scene.meshlets[cluster.meshlet as usize].triangle_count();
        let (side, count, tris) = if d.software {
            (&mut r.software, 0, 5)
        } else {
            (&mut r.hardware, 1, 6)
        };
        side.push(cluster);
        if slot_free {
            r.counts[count] += 1;
            r.counts[tris] += triangles;
        }
    }
    r.counts[2] = r.cut.len() as u32;
    r.counts[3] = end;
    r.counts[7] = start;
    r.counts[4] = r.frustum.len() as u32;
    if !matches!(occlusion, Occlusion::Off) {
        r.counts[9] = r.occluded.len() as u32;
        r.counts[10] = slots;
    }
    // The cut is counted only where the test runs.
    if matches!(occlusion, Occlusion::Off | Occlusion::Skipped) {
        r.counts[8] = 0;
    }
    r.hw_args = [HW_VERTICES, r.counts[1], 0, 0];
    r
}

/// The per-instance occlusion counters after a first pass (`first`) and, if one ran, a
/// second (`second`, over the first's `occluded`): per instance `i` of `instances`,
/// `[2i]` the first pass's LOD cut (drawn or not, hidden or not) and `[2i + 1]` the
/// clusters it found hidden less those the second pass found visible.
pub fn occluded_per_instance(
    first: &CullResult,
    second: Option<&CullResult>,
    instances: usize,
) -> Vec<u32> {
    let mut words = vec![0u32; instances * 2];
    let mut add = |clusters: &[Cluster], word: usize, delta: i64| {
        for c in clusters {
            let at = c.instance as usize * 2 + word;
            if at < words.len() {
                words[at] = (words[at] as i64 + delta) as u32;
            }
        }
    };
    add(&first.cut, 0, 1);
    add(&first.occluded, 0, 1);
    add(&first.occluded, 1, 1);
    if let Some(second) = second {
        add(&second.cut, 1, -1);
    }
    words
}

/// The pages a streaming first pass lists (`want_page`), by group: for each cluster in
/// the frustum and the LOD cut, its source group when that group's page is missing and
/// its error shows (priority: the error in pixels); and for the first cluster of each
/// run of the list from one page of one instance (`mark_page_in_use`), its parent group
/// when that group's error shows (in use, priority 0). A page wanted by several clusters
/// is listed once, with the priority of whichever cluster the GPU's atomics let first,
/// so the reference gives each group the range of priorities its clusters computed.
pub fn wanted_pages(
    scene: &SceneData,
    view: &View,
    clusters: &[Cluster],
    thresholds: &Thresholds,
) -> std::collections::BTreeMap<u32, (f32, f32)> {
    let stream_errors = scene.streaming().map_or(&[][..], |s| &s.stream_errors[..]);
    let mut wanted = std::collections::BTreeMap::new();
    let mut want = |group: u32, priority: f32| {
        let e = wanted.entry(group).or_insert((priority, priority));
        e.0 = f32::min(e.0, priority);
        e.1 = f32::max(e.1, priority);
    };
    for (i, &cluster) in clusters.iter().enumerate() {
        let instance = &scene.instances[cluster.instance as usize];
        let meshlet = &scene.meshlets[cluster.meshlet as usize];
        let scale = instance_max_scale(instance);
        let project = |group: u32, error: f32| {
            let sphere = scene.groups[group as usize].lod_sphere;
            let centre = transform_point(&instance.world_from_local, xyz(sphere));
            meshlight_shaders::cpu::lod::project_error_to_pixels(
                view,
                centre,
                sphere[3] * scale,
                error * scale,
            )
        };
        let parent = meshlet.parent_group;
        let starts_run = i == 0 || {
            let previous = clusters[i - 1];
            previous.instance != cluster.instance
                || scene.meshlets[previous.meshlet as usize].parent_group != parent
        };
        if parent != NO_GROUP && starts_run {
            let px = project(parent, scene.groups[parent as usize].error);
            if meshlight_shaders::cpu::lod::error_perceptible(px, thresholds.lod_threshold_px) {
                want(parent, 0.0);
            }
        }
        let d = classify(scene, view, cluster, thresholds);
        if !(d.in_frustum && d.in_cut) {
            continue;
        }
        if let Some(&missing) = stream_errors.get(meshlet.source_group as usize)
            && missing > 0.0
        {
            let px = project(meshlet.source_group, missing);
            if meshlight_shaders::cpu::lod::error_perceptible(px, thresholds.lod_threshold_px) {
                want(meshlet.source_group, px);
            }
        }
    }
    wanted
}
