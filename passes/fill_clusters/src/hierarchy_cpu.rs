//! The CPU reference of the `hierarchy` implementation: the same node test, operation for
//! operation in f32 (matrix times vector summed column by column, dot products and
//! lengths left to right), and the same steps: breadth-first rounds of two levels (a
//! frontier node and, when it is accepted, its children) with the same queue limits, children that do not fit in a spreading step handed on to the next step's list.
//!
//! A node test can still decide differently from a GPU's when a value lies within
//! rounding of its threshold; [`NodeTest::closeness`] says how close each came, so a test
//! can tell such a node from a real disagreement. Which subtrees a full frontier emits
//! whole depends on the order of the GPU's atomics; the reference appends children in
//! frontier order and walks each list in order, and says when something was emitted
//! whole ([`HierarchyWalk::queue_full`]). Which children are handed on also depends on
//! that order, but not which nodes are tested: every node is tested by one walk, so the
//! counts and the list agree with the GPU's whenever nothing was emitted whole.

use crate::cpu::instance_max_scale;
use crate::hierarchy::{MAX_ROUNDS, QUEUE, SLACK, SPREAD_STEPS, SUBTREE_CAPACITY};
use meshlight_gpu_scene::SceneData;
use meshlight_scene::asset::format::NodeRecord;
use meshlight_shaders::cpu::layout::{Cluster, Instance, View};
use meshlight_shaders::cpu::lod::{error_perceptible, error_to_pixels};
use meshlight_shaders::cpu::matrix::transform_point;
use meshlight_shaders::cpu::occlusion::{DEPTH_SLACK, DepthPyramid, MARGIN_PX, occlusion_rect};

/// The pass's parameters that change what it emits.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WalkParams {
    /// `capacity`: clusters the list may hold.
    pub capacity: u32,
    /// `lod_threshold_px`: the error the cut may show, as `cull_lod`'s.
    pub lod_threshold_px: f32,
    /// `queue_capacity`: nodes a frontier of the last step holds.
    pub queue_capacity: u32,
    /// `spread_steps`: steps that hand wide walks on.
    pub spread_steps: u32,
    /// `subtree_capacity`: entries each step's list holds.
    pub subtree_capacity: u32,
    /// `occlusion_min_clusters`.
    pub occlusion_min_clusters: u32,
}

impl Default for WalkParams {
    fn default() -> Self {
        Self {
            capacity: u32::MAX,
            lod_threshold_px: 1.0,
            queue_capacity: QUEUE,
            spread_steps: SPREAD_STEPS,
            subtree_capacity: SUBTREE_CAPACITY,
            occlusion_min_clusters: crate::hierarchy::OCCLUSION_MIN_CLUSTERS,
        }
    }
}

/// What the walk produces for a scene and a view.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct HierarchyWalk {
    /// Every requested cluster, instance by instance, each instance's in the order its
    /// rounds emitted them (the GPU's order differs; compare as sets).
    pub clusters: Vec<Cluster>,
    /// Instances whose root passed its test.
    pub visible_instances: Vec<u32>,
    /// `hierarchy_counts`: nodes tested, leaves accepted, subtrees emitted whole, walks
    /// unfinished.
    pub counts: [u32; 4],
    /// `cluster_count[1]`: clusters requested.
    pub requested: u32,
    /// `cluster_count[0]`: the requested clusters below the capacity.
    pub written: u32,
    /// Some subtree was emitted whole (a frontier and the next list full): which then
    /// depends on the order the GPU appended children in.
    pub queue_full: bool,
    /// Subtrees handed on, per spreading step (the GPU's numbers may differ: which
    /// children fit in a frontier depends on the order of its atomics).
    pub handed_on: Vec<u32>,
    /// Per step, the most rounds one of its walks took: each round waits for the one
    /// before, so their sum over the steps is the walk's critical path.
    pub rounds: Vec<u32>,
    /// `(instance, node)` of every test decided within `near` (the argument of
    /// [`cpu_walk`]) of a threshold, relative to what it compared.
    pub near_threshold: Vec<(u32, u32)>,
    /// With occlusion, `(instance, node)` of every node the pyramid hid (its count is
    /// `hierarchy_counts[4]`): the first walk's `occluded_nodes`, in walk order (the
    /// GPU's order differs), or what the second walk dropped.
    pub hidden_nodes: Vec<(u32, u32)>,
}

/// The occlusion side of a walk.
#[derive(Clone, Copy, Debug, Default)]
pub enum WalkOcclusion<'a> {
    /// No pyramid, or the first walk's test skipped (no valid history, camera cut).
    #[default]
    Off,
    /// The first walk against last frame's pyramid (previous view-projection and
    /// instance transforms); `capacity` entries of `occluded_nodes`.
    First {
        /// Last frame's pyramid.
        pyramid: &'a DepthPyramid,
        /// Entries of `occluded_nodes`; hidden nodes past it are walked as if visible.
        capacity: u32,
    },
    /// The second walk from the first's hidden nodes against this frame's pyramid.
    Second {
        /// This frame's pyramid.
        pyramid: &'a DepthPyramid,
        /// The first walk's hidden nodes, `(instance, node)`, where this walk starts.
        nodes: &'a [(u32, u32)],
    },
}

/// `node_occluded`, with how close it came to deciding otherwise (as
/// [`NodeTest::closeness`]).
pub fn node_occlusion(
    view: &View,
    instance: &Instance,
    node: &NodeRecord,
    pyramid: &DepthPyramid,
    previous: bool,
) -> NodeTest {
    let mut seen = *instance;
    let mut view_projection = view.view_projection;
    if previous {
        seen.world_from_local = seen.previous_world_from_local;
        view_projection = view.previous_view_projection;
    }
    let w = Walker::new(&seen, view);
    let centre = w.transform(node.bounds);
    let radius = node.bounds[3] * w.scale;
    let rect = occlusion_rect(&view_projection, view.viewport_size, centre, radius);
    let mut closeness = f32::INFINITY;
    if rect.testable {
        let farthest = pyramid.farthest(rect.pixels);
        let nearest = rect.depth * DEPTH_SLACK;
        closeness = (nearest - farthest).abs() / farthest.abs().max(f32::MIN_POSITIVE);
        for (v, m) in rect
            .screen
            .iter()
            .zip([-MARGIN_PX, -MARGIN_PX, MARGIN_PX, MARGIN_PX])
        {
            let edge = v + m;
            closeness = closeness.min((edge - edge.round()).abs() / edge.abs().max(1.0));
        }
    }
    NodeTest {
        visible: !pyramid.occludes(&rect),
        closeness,
    }
}

/// One node test: whether the walk goes on below the node, and how close the deciding
/// comparisons came to flipping (relative to their scale; `f32::INFINITY` when no
/// comparison was made).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NodeTest {
    /// Whether the walk goes on below the node.
    pub visible: bool,
    /// How close the deciding comparison came to flipping, relative to its scale.
    pub closeness: f32,
}

fn dot3(a: [f32; 3], b: [f32; 3]) -> f32 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

fn length3(a: [f32; 3]) -> f32 {
    dot3(a, a).sqrt()
}

fn xyz(v: [f32; 4]) -> [f32; 3] {
    [v[0], v[1], v[2]]
}

/// What stays the same for every node of one instance (`Walker` in the shader).
#[derive(Clone, Copy, Debug)]
pub struct Walker<'a> {
    /// The instance walked.
    pub instance: &'a Instance,
    /// Its largest axis scale, which grows every sphere and error.
    pub scale: f32,
    /// `|translation| + |camera|`: with a sphere's own size, the magnitudes a test's
    /// slack is relative to.
    pub reach: f32,
}

impl<'a> Walker<'a> {
    /// The walker of `instance` seen from `view`, as the shader's `walker` builds it.
    pub fn new(instance: &'a Instance, view: &View) -> Self {
        Self {
            instance,
            scale: instance_max_scale(instance),
            reach: length3(xyz(instance.world_from_local[3])) + length3(view.camera_position),
        }
    }

    fn slack(&self, sphere: [f32; 4]) -> f32 {
        (self.reach + self.scale * (length3(xyz(sphere)) + sphere[3])) * SLACK
    }

    fn transform(&self, p: [f32; 4]) -> [f32; 3] {
        transform_point(&self.instance.world_from_local, xyz(p))
    }
}

/// `node_visible`, with how close it came to deciding otherwise.
pub fn node_test(view: &View, w: &Walker, node: &NodeRecord, threshold: f32) -> NodeTest {
    let rel = |v: f32, to: f32| (v - to).abs() / to.abs().max(f32::MIN_POSITIVE);
    let centre = w.transform(node.bounds);
    let radius = node.bounds[3] * w.scale + w.slack(node.bounds);
    let mut closeness = f32::INFINITY;
    for p in &view.frustum {
        let keep = radius + SLACK * p[3].abs();
        let d = dot3(xyz(*p), centre) + p[3];
        closeness = closeness.min((d + keep).abs() / keep.max(f32::MIN_POSITIVE));
        if d < -keep {
            return NodeTest {
                visible: false,
                closeness,
            };
        }
    }
    let lod_centre = w.transform(node.lod_sphere);
    let lod_radius = node.lod_sphere[3] * w.scale;
    let s = w.slack(node.lod_sphere);
    let c = view.camera_position;
    let d = length3([
        lod_centre[0] - c[0],
        lod_centre[1] - c[1],
        lod_centre[2] - c[2],
    ]);
    if node.max_parent_error < f32::MAX {
        let parent_px = error_to_pixels(view, d - lod_radius - s, node.max_parent_error * w.scale);
        closeness = closeness.min(rel(parent_px, threshold));
        if !error_perceptible(parent_px, threshold) {
            return NodeTest {
                visible: false,
                closeness,
            };
        }
    }
    let own_px = error_to_pixels(view, d + lod_radius + s, node.min_error * w.scale);
    closeness = closeness.min(rel(own_px, threshold));
    NodeTest {
        visible: !error_perceptible(own_px, threshold),
        closeness,
    }
}

/// Children `first .. first + count` of one node of `instance`'s hierarchy (a root:
/// the node alone), walked by one workgroup of a step.
#[derive(Clone, Copy, Debug)]
struct Entry {
    instance: u32,
    first: u32,
    count: u32,
}

/// The reference walk over every instance. Tests deciding within `near` of a threshold
/// are listed in [`HierarchyWalk::near_threshold`].
pub fn cpu_walk(scene: &SceneData, view: &View, params: &WalkParams, near: f32) -> HierarchyWalk {
    cpu_walk_with(scene, view, params, near, WalkOcclusion::Off)
}

/// The reference walk with occlusion: the first walk from every instance's root, the
/// second from the first's hidden nodes.
pub fn cpu_walk_with(
    scene: &SceneData,
    view: &View,
    params: &WalkParams,
    near: f32,
    occlusion: WalkOcclusion,
) -> HierarchyWalk {
    let nodes = &scene.hierarchy_nodes;
    let queue = params.queue_capacity.clamp(1, QUEUE) as usize;
    let mut r = HierarchyWalk::default();
    // The roots (`roots` in the shader): each instance's, or the second walk's nodes.
    let roots: Vec<Entry> = match occlusion {
        WalkOcclusion::Second { nodes: hidden, .. } => hidden
            .iter()
            .filter(|(instance, _)| (*instance as usize) < scene.instances.len())
            .map(|&(instance, node)| Entry {
                instance,
                first: node,
                count: 1,
            })
            .collect(),
        _ => scene
            .instances
            .iter()
            .enumerate()
            // An instance without meshlets has nothing to walk.
            .filter(|(_, instance)| instance.meshlet_count > 0)
            .filter_map(|(index, instance)| {
                let &root = scene.hierarchy_roots.get(instance.mesh as usize)?;
                Some(Entry {
                    instance: index as u32,
                    first: root,
                    count: 1,
                })
            })
            .collect(),
    };
    // `node_seen`: false when the pyramid hides the node (the first walk hands it on
    // while its list has room; the second drops it).
    let seen = |r: &mut HierarchyWalk,
                index: u32,
                instance: &Instance,
                id: u32,
                node: &NodeRecord,
                entry: bool| {
        let (pyramid, previous) = match occlusion {
            WalkOcclusion::Off => return true,
            _ if !entry && node.cluster_count < params.occlusion_min_clusters => return true,
            WalkOcclusion::First { pyramid, .. } => (pyramid, true),
            WalkOcclusion::Second { pyramid, .. } => (pyramid, false),
        };
        let test = node_occlusion(view, instance, node, pyramid, previous);
        if test.closeness < near {
            r.near_threshold.push((index, id));
        }
        if test.visible {
            return true;
        }
        if let WalkOcclusion::First { capacity, .. } = occlusion
            && r.hidden_nodes.len() >= capacity as usize
        {
            return true;
        }
        r.hidden_nodes.push((index, id));
        false
    };
    // Each root tested on its own, and the children of one that passes by the same
    // thread: an accepted leaf emits its meshlets, an accepted inner child hands its
    // children on as step 0's entry (a leaf root emits its meshlets; the list is never
    // full here).
    let mut entries = Vec::new();
    for root in &roots {
        let (index, id) = (root.instance, root.first);
        let instance = &scene.instances[index as usize];
        let Some(node) = nodes.get(id as usize) else {
            continue;
        };
        let w = Walker::new(instance, view);
        r.counts[0] += 1;
        let test = node_test(view, &w, node, params.lod_threshold_px);
        if test.closeness < near {
            r.near_threshold.push((index, id));
        }
        if !test.visible || !seen(&mut r, index, instance, id, node, true) {
            continue;
        }
        r.visible_instances.push(index);
        let emit = |r: &mut HierarchyWalk, node: &NodeRecord| {
            r.counts[1] += 1;
            r.clusters.extend(
                scene.hierarchy_clusters[node.first_cluster as usize
                    ..(node.first_cluster + node.cluster_count) as usize]
                    .iter()
                    .map(|&meshlet| Cluster {
                        instance: index,
                        meshlet,
                    }),
            );
        };
        if node.is_leaf() {
            emit(&mut r, node);
            continue;
        }
        // The root's thread tests its children too: an accepted leaf emits, an accepted
        // inner child hands its children on as step 0's entry.
        for child_id in node.first_child..node.first_child + node.child_count {
            r.counts[0] += 1;
            let Some(child) = nodes.get(child_id as usize) else {
                continue;
            };
            let test = node_test(view, &w, child, params.lod_threshold_px);
            if test.closeness < near {
                r.near_threshold.push((index, child_id));
            }
            if !test.visible || !seen(&mut r, index, instance, child_id, child, false) {
                continue;
            }
            if child.is_leaf() {
                emit(&mut r, child);
                continue;
            }
            entries.push(Entry {
                instance: index,
                first: child.first_child,
                count: child.child_count,
            });
        }
    }
    for step in 0..=params.spread_steps {
        let spreading = step < params.spread_steps;
        let width = if spreading { queue.min(64) } else { queue };
        let mut list = Vec::new();
        let mut most_rounds = 0;
        for entry in &entries {
            let index = entry.instance;
            let instance = &scene.instances[index as usize];
            let w = Walker::new(instance, view);
            let emit = |r: &mut HierarchyWalk, first: u32, end: u32| {
                r.clusters.extend(
                    scene.hierarchy_clusters[first as usize..end as usize]
                        .iter()
                        .map(|&meshlet| Cluster {
                            instance: index,
                            meshlet,
                        }),
                );
            };
            // The node test and `node_seen` (an accepted leaf emits its meshlets): the
            // node, when the walk goes on below it.
            let accept = |r: &mut HierarchyWalk, id: u32| -> Option<NodeRecord> {
                let node = *nodes.get(id as usize)?;
                let test = node_test(view, &w, &node, params.lod_threshold_px);
                if test.closeness < near {
                    r.near_threshold.push((index, id));
                }
                if !test.visible || !seen(r, index, instance, id, &node, false) {
                    return None;
                }
                if node.is_leaf() {
                    r.counts[1] += 1;
                    emit(
                        r,
                        node.first_cluster,
                        node.first_cluster + node.cluster_count,
                    );
                    return None;
                }
                Some(node)
            };
            let mut frontier: Vec<u32> = (entry.first..entry.first + entry.count).collect();
            let mut round = 0;
            while !frontier.is_empty() && round < MAX_ROUNDS {
                r.counts[0] += frontier.len() as u32;
                let mut next = Vec::new();
                // Children reserved so far, counting those past the queue (the GPU's atomic).
                let mut reserved = 0usize;
                for &id in &frontier {
                    let Some(node) = accept(&mut r, id) else {
                        continue;
                    };
                    // Two levels a round: the children of an accepted node are tested
                    // by the same thread, in the same round.
                    for child_id in node.first_child..node.first_child + node.child_count {
                        r.counts[0] += 1;
                        let Some(child) = accept(&mut r, child_id) else {
                            continue;
                        };
                        let slot = reserved;
                        reserved += child.child_count as usize;
                        let fit = (child.child_count as usize).min(width - slot.min(width));
                        next.extend((0..fit as u32).map(|k| child.first_child + k));
                        if fit < child.child_count as usize {
                            if spreading && list.len() < params.subtree_capacity as usize {
                                list.push(Entry {
                                    instance: index,
                                    first: child.first_child + fit as u32,
                                    count: child.child_count - fit as u32,
                                });
                                continue;
                            }
                            r.queue_full = true;
                            r.counts[2] += 1;
                            let first = nodes[child.first_child as usize + fit].first_cluster;
                            emit(&mut r, first, child.first_cluster + child.cluster_count);
                        }
                    }
                }
                frontier = next;
                round += 1;
            }
            most_rounds = most_rounds.max(round);
            if !frontier.is_empty() {
                r.counts[3] += 1;
            }
        }
        r.rounds.push(most_rounds);
        if spreading {
            r.handed_on.push(list.len() as u32);
        }
        entries = list;
    }
    r.requested = r.clusters.len() as u32;
    r.written = r.requested.min(params.capacity);
    r
}
