// fill_clusters, implementation `hierarchy`: the visible instances' culling hierarchies
// walked breadth-first with queues in workgroup memory, each node tested once (frustum,
// then the conservative LOD tests), writing (instance, meshlet) for the meshlets of every
// accepted leaf. `hierarchy_cpu` (Rust) is the reference.
//
// Roots first, a thread each (`roots`): every instance's root (or, in the second walk,
// every node the first walk found hidden) is tested on its own, so an instance that is
// culled or hidden costs one thread, not a workgroup; the thread of a root that passes
// tests its children too, emits the meshlets of those that are accepted leaves and
// hands the children of each accepted inner one on as one entry of the roots list (a
// leaf root emits its meshlets at once). A distant instance, whose cut is its coarsest
// meshlets, so costs one thread.
// Then the walk is split over `steps + 1` dispatches of `fill` so that a large
// instance's walk spreads over many workgroups: step 0 takes the roots list, a workgroup
// per entry (an indirect dispatch `walk_args` writes); each later step's workgroups take
// the subtrees the step before handed on, striding over that list. In a spreading step (every step but the last) a frontier
// holds at most one chunk of nodes; the children that do not fit are handed on to the
// next step's list as one entry (instance, first child, count). In the last step, and
// when a list is full, the children that do not fit are emitted whole (every meshlet
// below them: one range of the depth-first cluster list), so a full queue costs pruning,
// never a cluster of the cut. A step only reads the list the previous dispatch finished,
// so nothing here assumes that workgroups make progress together.
//
// Per round, the frontier is tested 64 nodes at a time, and the thread that accepts an
// inner node tests its children too (two levels a round); an accepted inner child
// appends its children to the next frontier. The meshlets a chunk of 64 nodes emits are reserved
// with one global atomic and written cooperatively, one leaf after another, consecutive
// threads writing consecutive slots.
//
// With OCCLUSION (two-pass occlusion culling, docs/ARCHITECTURE.md), an accepted node
// (a walk's entry, or an inner node with at least `occlusion_min_clusters` meshlets
// below) is also tested against a depth pyramid. The first pass (last frame's pyramid,
// through last frame's view and the instance's previous transform) hands a node it
// proves hidden to the second pass as one entry of `node_list` and goes no deeper; the
// second pass (SECOND_PASS: this frame's pyramid and view) starts its walk from that
// list instead of the instances' roots and drops what is still hidden. A root is the
// instance, so a hidden instance costs one node test per pass and emits nothing.
//
// With MULTI_VIEW, one walk serves up to MAX_VIEWS views (a sun's shadow cascades): a
// node is tested against each view its parent was accepted for, and the walk goes on
// below it for the views that accept it, carried as a mask in the top bits of each
// frontier and list entry; an accepted leaf's meshlets go to the list of each view that
// accepted it (view v's is list `params.list + v` of the buffers). So each view's list
// is the one a walk of that view alone writes (the tests compare them), while a node
// wanted by several views is loaded, transformed and queued once. With OCCLUSION too
// (a first walk only), one view, `params.occlusion_view` (the camera beside the sun's
// cascades), has the pyramid: a node it hides is handed to the second walk for that view
// alone and the walk goes on below it for the others.

#import meshlight::dispatch::linear_workgroup
#import meshlight::meshlet::{Cluster, error_perceptible}
#import meshlight::instance::{Instance, instance_max_scale, instance_transform_point}
#import meshlight::instance_table::{instance_at, instance_total}
#import meshlight::view::{View, error_to_pixels}
#import meshlight::math::F32_MAX
// Qualified (`cluster_list::clusters`): `cluster_count` also names a HierarchyNode field.
#import fill_clusters::list as cluster_list
// The uniform block, declared once for Rust and WGSL by `GpuParams` in hierarchy.rs.
#import fill_clusters::hierarchy_params::Params
#ifdef OCCLUSION
#import meshlight::occlusion::{instance_sphere_rect, sphere_occluded}
#endif

// 64 bytes: the asset's `NodeRecord`, with `first_child` and `first_cluster` rebased
// onto the shared buffers by the GPU scene.
struct HierarchyNode {
    // Mesh space: encloses the culling spheres of every meshlet below.
    bounds: vec4<f32>,
    // Mesh space: encloses the own and parent LOD spheres of every meshlet below.
    lod_sphere: vec4<f32>,
    // Smallest own error of a meshlet below (mesh units).
    min_error: f32,
    // Largest parent error of a meshlet below; F32_MAX with a root below.
    max_parent_error: f32,
    // Children: nodes first_child .. first_child + child_count; none for a leaf.
    first_child: u32,
    child_count: u32,
    // The meshlets below: hierarchy_clusters[first_cluster .. + cluster_count].
    first_cluster: u32,
    cluster_count: u32,
    reserved: vec2<u32>,
}

// Children `first .. first + count` of one node of `instance`'s hierarchy, handed to the
// next step to walk.
struct Subtree {
    instance: u32,
    first: u32,
    count: u32,
}

// The instances: `instance_at` (meshlight::instance_table, bindings 30 and 31); the
// cluster list and its count (fill_clusters::list, bindings 1 and 2).
#ifdef MULTI_VIEW
// `params.views` of them; a view with an empty viewport is left out of the walk.
@group(0) @binding(3) var<uniform> views: array<View, MAX_VIEWS>;
#else
@group(0) @binding(3) var<uniform> view: View;
#endif
@group(0) @binding(4) var<uniform> params: Params;
// Every mesh's hierarchy nodes.
@group(0) @binding(5) var<storage, read> hierarchy_nodes: array<HierarchyNode>;
// The leaves' meshlets, as indices into the scene's meshlets.
@group(0) @binding(6) var<storage, read> hierarchy_clusters: array<u32>;
// Per mesh, its root node.
@group(0) @binding(7) var<storage, read> hierarchy_roots: array<u32>;
// [0] nodes tested, [1] leaves accepted, [2] subtrees emitted whole (queue full),
// [3] walks (of a roots-list entry or a handed-on subtree) that hit the round limit (0
// unless the data is damaged).
@group(0) @binding(8) var<storage, read_write> hierarchy_counts: array<atomic<u32>>;
// [k] entries requested in the list step k + 1 reads (at most list_capacity written);
// [MAX_STEPS] the roots list's.
@group(0) @binding(9) var<storage, read_write> subtree_counts: array<atomic<u32>>;
// The lists, step k + 1's at [k * list_capacity ..].
@group(0) @binding(10) var<storage, read_write> subtrees: array<Subtree>;
// The roots list: the children of every root that passed, step 0's entries.
@group(0) @binding(14) var<storage, read_write> root_list: array<Subtree>;
// Step 0's indirect dispatch, [x, y, 1], from the roots list's length.
@group(0) @binding(15) var<storage, read_write> walk_args: array<u32>;
#ifdef OCCLUSION
// The depth pyramid (R32Float, farthest depth per texel): last frame's in the first
// pass, this frame's in the second.
@group(0) @binding(11) var pyramid: texture_2d<f32>;
#ifdef SECOND_PASS
// The first pass's hidden nodes, (instance, node, 1) each: where this walk starts.
@group(0) @binding(12) var<storage, read> node_list: array<Subtree>;
// [0] entries written, [1] found.
@group(0) @binding(13) var<storage, read> node_list_count: array<u32>;
#else
// The nodes this pass finds hidden, for the second pass; [0] written, [1] found.
@group(0) @binding(12) var<storage, read_write> node_list: array<Subtree>;
@group(0) @binding(13) var<storage, read_write> node_list_count: array<atomic<u32>>;
#endif
#endif

const WORKGROUP_SIZE: u32 = 64u;
#ifdef MULTI_VIEW
// Views one walk serves; their mask takes the top bits of a node id (a binding of
// 64-byte nodes holds fewer than 2^26, so an id never reaches them).
const MAX_VIEWS: u32 = 5u;
const ID_BITS: u32 = 27u;
#else
const MAX_VIEWS: u32 = 1u;
#endif
// Nodes a frontier holds; two frontiers take 8 KiB of workgroup memory.
const QUEUE: u32 = 1024u;
// Lists of subtrees at most (spreading steps).
const MAX_STEPS: u32 = 4u;
// Words of `hierarchy_counts`: with OCCLUSION, [4] counts the nodes the pyramid hid.
// With room for them (ENTRY_WORDS words bound), [5] counts the walk's entries tested
// (the first walk: instances) and [6] those that passed.
const ENTRY_WORDS: u32 = 7u;
#ifdef OCCLUSION
const COUNT_WORDS: u32 = 5u;
#else
const COUNT_WORDS: u32 = 4u;
#endif
// More rounds than any stored tree has levels (the loader bounds nothing deeper than the
// node count, but a walk must end even on damaged data).
const MAX_ROUNDS: u32 = 256u;
// Rounding slack of a node test, relative to the magnitudes the world transform and
// the projection combine (2^-13: about 1000 times the f32 rounding of those steps).
const SLACK: f32 = 1.220703125e-4;

var<workgroup> frontier: array<array<u32, QUEUE>, 2>;
var<workgroup> frontier_len: u32;
var<workgroup> next_len: atomic<u32>;
// The ranges of hierarchy_clusters a chunk emits, packed, each with its offset in the
// chunk's reservation. A thread emits up to 1 + MAX_CHILDREN ranges (fewer: adjacent
// leaves merge); past EMIT_SLOTS it reserves and writes its range alone. One slot per
// thread keeps the workgroup's memory, and so the workgroups resident per compute unit,
// what they were with one range per thread (about 9 KiB with the frontiers).
const EMIT_SLOTS: u32 = 64u;
// With MULTI_VIEW a range goes to each view of its mask (packed with its count), at its
// offset in that view's reservation.
var<workgroup> emit_first: array<u32, EMIT_SLOTS>;
var<workgroup> emit_count: array<u32, EMIT_SLOTS>;
var<workgroup> emit_offset: array<u32, EMIT_SLOTS * MAX_VIEWS>;
var<workgroup> emit_ranges: atomic<u32>;
var<workgroup> emit_total: array<atomic<u32>, MAX_VIEWS>;
var<workgroup> emit_len: u32;
var<workgroup> emit_base: array<u32, MAX_VIEWS>;
var<workgroup> leaves: atomic<u32>;
var<workgroup> tested_nodes: atomic<u32>;
// The walk's entries (instance roots; the second walk's hidden nodes) tested and passed.
var<workgroup> entries_tested: atomic<u32>;
var<workgroup> entries_passed: atomic<u32>;
var<workgroup> spilled: atomic<u32>;
var<workgroup> hidden_nodes: atomic<u32>;
// Entries this step walks (the roots list's length in step 0, the handed-on list's
// after).
var<workgroup> entry_total: u32;

fn capacity() -> u32 {
    return cluster_list::cluster_capacity(params.capacity, params.lists);
}

// View v's list: its first cluster, and its words in `cluster_count` ([w]: 0 written,
// 1 requested).
fn list_base(v: u32) -> u32 {
#ifdef MULTI_VIEW
    return (params.list + v) * cluster_list::list_length(params.lists);
#else
    if params.lists <= 1u {
        return 0u;
    }
    return params.list * cluster_list::list_length(params.lists);
#endif
}

fn count_word(v: u32, w: u32) -> u32 {
    return 2u * (params.list + v) + w;
}

// A node id with the views it is walked for (MULTI_VIEW), and its parts; with one view
// the mask is 1 and the entry the id.
fn with_views(id: u32, mask: u32) -> u32 {
#ifdef MULTI_VIEW
    return id | (mask << ID_BITS);
#else
    return id;
#endif
}

fn entry_id(entry: u32) -> u32 {
#ifdef MULTI_VIEW
    return entry & ((1u << ID_BITS) - 1u);
#else
    return entry;
#endif
}

fn entry_views(entry: u32) -> u32 {
#ifdef MULTI_VIEW
    return entry >> ID_BITS;
#else
    return 1u;
#endif
}

// The views the walk starts with: every view given a viewport.
fn walked_views() -> u32 {
#ifdef MULTI_VIEW
    var mask = 0u;
    for (var v = 0u; v < min(params.views, MAX_VIEWS); v += 1u) {
        if views[v].viewport_size.x > 0.0 {
            mask |= 1u << v;
        }
    }
    return mask;
#else
    return 1u;
#endif
}

// This thread's range not yet handed to the chunk (adjacent leaves with the same views
// extend it), and the instance the workgroup walks.
var<private> pending_first: u32;
var<private> pending_count: u32;
var<private> pending_views: u32;
var<private> walk_instance: u32;

// Hands the pending range to the chunk's emission, or, when the chunk's slots are
// taken, reserves and writes it alone.
fn flush() {
    let count = pending_count;
    pending_count = 0u;
    if count == 0u {
        return;
    }
    let e = atomicAdd(&emit_ranges, 1u);
    if e < EMIT_SLOTS {
        emit_first[e] = pending_first;
        emit_count[e] = with_views(count, pending_views);
#ifdef MULTI_VIEW
        for (var v = 0u; v < MAX_VIEWS; v += 1u) {
            if (pending_views & (1u << v)) != 0u {
                emit_offset[v * EMIT_SLOTS + e] = atomicAdd(&emit_total[v], count);
            }
        }
#else
        emit_offset[e] = atomicAdd(&emit_total[0], count);
#endif
        return;
    }
    emit_now(walk_instance, pending_first, count, pending_views);
}

fn emit_range(first: u32, count: u32, mask: u32) {
    if count == 0u {
        return;
    }
    if pending_count > 0u && pending_first + pending_count == first && pending_views == mask {
        pending_count += count;
        return;
    }
    flush();
    pending_first = first;
    pending_count = count;
    pending_views = mask;
}

// What stays the same for every node of one instance.
struct Walker {
    instance: Instance,
    scale: f32,
    // |translation|: with |camera| and the sphere's own size, the magnitudes a test adds.
    translation: f32,
}

fn slack(w: Walker, camera: vec3<f32>, sphere: vec4<f32>) -> f32 {
    return (w.translation + length(camera) + w.scale * (length(sphere.xyz) + sphere.w)) * SLACK;
}

// View v's frustum plane p and camera position, read from the uniform in place (a View
// copied into a function would put its plane array in local memory, indexed per plane).
fn view_plane(v: u32, p: u32) -> vec4<f32> {
#ifdef MULTI_VIEW
    return views[v].frustum[p];
#else
    return view.frustum[p];
#endif
}

fn view_camera(v: u32) -> vec3<f32> {
#ifdef MULTI_VIEW
    return views[v].camera_position;
#else
    return view.camera_position;
#endif
}

// `error` seen from `distance` in view v, in pixels (`error_to_pixels`).
fn view_pixels(v: u32, distance: f32, error: f32) -> f32 {
#ifdef MULTI_VIEW
    return error_to_pixels(views[v], distance, error);
#else
    return error_to_pixels(view, distance, error);
#endif
}

// Whether any meshlet below `node` can be in cull_lod's cut of the walk's view v:
// its culling sphere in the frustum, its parent perceptible and its own error
// imperceptible. Every comparison is the per-cluster one with the node's bounds, shifted
// by the slack toward keeping.
fn node_visible_in(node: HierarchyNode, w: Walker, v: u32) -> bool {
    let camera = view_camera(v);
    let centre = instance_transform_point(w.instance, node.bounds.xyz);
    let radius = node.bounds.w * w.scale + slack(w, camera, node.bounds);
    for (var p = 0u; p < 6u; p += 1u) {
        let plane = view_plane(v, p);
        if dot(plane.xyz, centre) + plane.w < -(radius + SLACK * abs(plane.w)) {
            return false;
        }
    }
    let lod_centre = instance_transform_point(w.instance, node.lod_sphere.xyz);
    let lod_radius = node.lod_sphere.w * w.scale;
    let s = slack(w, camera, node.lod_sphere);
    let d = length(lod_centre - camera);
    // Too fine: the largest parent error, seen from the sphere's nearest point, is
    // imperceptible, so every parent below is.
    if node.max_parent_error < F32_MAX {
        let parent_px = view_pixels(v, d - lod_radius - s, node.max_parent_error * w.scale);
        if !error_perceptible(parent_px, params.lod_threshold_px) {
            return false;
        }
    }
    // Too coarse: the smallest own error, seen from the sphere's farthest point, is
    // perceptible, so every own error below is.
    let own_px = view_pixels(v, d + lod_radius + s, node.min_error * w.scale);
    return !error_perceptible(own_px, params.lod_threshold_px);
}

// The views of `mask` for which the walk goes on below `node` (`node_visible_in`).
fn node_views(node: HierarchyNode, w: Walker, mask: u32) -> u32 {
#ifdef MULTI_VIEW
    var kept = 0u;
    for (var v = 0u; v < MAX_VIEWS; v += 1u) {
        if (mask & (1u << v)) != 0u && node_visible_in(node, w, v) {
            kept |= 1u << v;
        }
    }
    return kept;
#else
    return select(0u, 1u, node_visible_in(node, w, 0u));
#endif
}

#ifdef OCCLUSION
// Whether the pyramid proves a node's bounding sphere (which encloses the culling
// sphere of every meshlet below) hidden: cull_lod's cluster test on the node's sphere.
fn node_occluded(node: HierarchyNode, w: Walker) -> bool {
#ifdef MULTI_VIEW
    let rect = instance_sphere_rect(w.instance, views[params.occlusion_view], node.bounds);
#else
    let rect = instance_sphere_rect(w.instance, view, node.bounds);
#endif
    return sphere_occluded(pyramid, rect);
}

// The mask bit of the view the pyramid belongs to.
fn occlusion_bit() -> u32 {
#ifdef MULTI_VIEW
    return 1u << params.occlusion_view;
#else
    return 1u;
#endif
}

#ifndef SECOND_PASS
// Hands a hidden node to the second pass; false when the list is full (the walk then
// goes on below it, as without occlusion).
fn defer_node(id: u32) -> bool {
    let at = atomicAdd(&node_list_count[1], 1u);
    if at >= min(params.node_capacity, arrayLength(&node_list)) {
        return false;
    }
    node_list[at] = Subtree(walk_instance, id, 1u);
    atomicAdd(&node_list_count[0], 1u);
    return true;
}
#endif
#endif

// The views of `views` (those `node_views` accepted) for which the walk goes on below
// a node: with OCCLUSION, all but the pyramid's view when the pyramid hides the node
// (the first pass hands it to the second for that view, the second drops it).
fn node_seen(node: HierarchyNode, id: u32, w: Walker, entry: bool, views: u32) -> u32 {
#ifdef OCCLUSION
    let bit = occlusion_bit();
    let tested = entry || node.cluster_count >= params.occlusion_min_clusters;
    if (views & bit) != 0u && params.test_occlusion != 0u && tested && node_occluded(node, w) {
#ifdef SECOND_PASS
        atomicAdd(&hidden_nodes, 1u);
        return views & ~bit;
#else
        if defer_node(id) {
            atomicAdd(&hidden_nodes, 1u);
            return views & ~bit;
        }
#endif
    }
#endif
    return views;
}

// A child of an accepted node, tested: the node, and the views of `mask` for which the
// walk goes on below it (none when it is rejected, hidden, or past the buffer).
struct TestedChild {
    node: HierarchyNode,
    views: u32,
}

fn test_child(id: u32, w: Walker, mask: u32) -> TestedChild {
    var tested: TestedChild;
    tested.views = 0u;
    if id >= arrayLength(&hierarchy_nodes) {
        return tested;
    }
    tested.node = hierarchy_nodes[id];
    let views = node_views(tested.node, w, mask);
    if views != 0u {
        tested.views = node_seen(tested.node, id, w, false, views);
    }
    return tested;
}

@compute @workgroup_size(1)
fn prepare() {
    // Every list of the walk's views (in a one-view dispatch of a walk over several,
    // the others' too, so none keeps an old count).
    let words = arrayLength(&cluster_list::cluster_count);
    for (var l = 0u; l < params.cleared_lists; l += 1u) {
        let w = 2u * (params.first_cleared + l);
        if w + 1u < words {
            atomicStore(&cluster_list::cluster_count[w], 0u);
            atomicStore(&cluster_list::cluster_count[w + 1u], 0u);
        }
    }
    for (var i = 0u; i < min(ENTRY_WORDS, arrayLength(&hierarchy_counts)); i += 1u) {
        atomicStore(&hierarchy_counts[i], 0u);
    }
#ifdef OCCLUSION
#ifndef SECOND_PASS
    atomicStore(&node_list_count[0], 0u);
    atomicStore(&node_list_count[1], 0u);
#endif
#endif
    for (var i = 0u; i < min(MAX_STEPS + 1u, arrayLength(&subtree_counts)); i += 1u) {
        atomicStore(&subtree_counts[i], 0u);
    }
}

// Hands children `first .. first + count` of `instance` to the next step as one entry;
// false when the list is full. The length word may pass the capacity; readers clamp it,
// and every slot below the clamped length was written by the call that reserved it.
fn hand_on(instance: u32, first: u32, count: u32) -> bool {
    let list = params.step;
    if list >= params.steps || list >= arrayLength(&subtree_counts) {
        return false;
    }
    let at = atomicAdd(&subtree_counts[list], 1u);
    let slot = list * params.list_capacity + at;
    if at >= params.list_capacity || slot >= arrayLength(&subtrees) {
        return false;
    }
    subtrees[slot] = Subtree(instance, first, count);
    return true;
}

// Appends an accepted inner node's children to the next frontier (`into`); those that
// do not fit are handed on to the next step or, when that cannot be, emitted whole.
// `mask`: the views the children are walked for.
fn enqueue(node: HierarchyNode, mask: u32, into: u32, width: u32, spreading: bool, index: u32) {
    let slot = atomicAdd(&next_len, node.child_count);
    let fit = min(node.child_count, width - min(slot, width));
    for (var k = 0u; k < fit; k += 1u) {
        frontier[into][slot + k] = with_views(node.first_child + k, mask);
    }
    let rest = node.child_count - fit;
    if rest > 0u && !(spreading && hand_on(index, with_views(node.first_child + fit, mask), rest)) {
        // The children that did not fit, with everything below them.
        let end = node.first_cluster + node.cluster_count;
        let from_cluster = hierarchy_nodes[node.first_child + fit].first_cluster;
        emit_range(from_cluster, select(0u, end - from_cluster, from_cluster < end), mask);
        atomicAdd(&spilled, 1u);
    }
}

// The roots list's length, clamped to what it holds.
fn root_total() -> u32 {
    let held = min(params.root_capacity, arrayLength(&root_list));
    return min(atomicLoad(&subtree_counts[MAX_STEPS]), held);
}

// Writes meshlets `first .. first + count` of hierarchy_clusters for instance `index` at
// once: a root that is a leaf, one the roots list has no room for (then every meshlet
// below it, as a full queue emits a subtree whole), or a range a chunk has no slot for.
// Into the list of each view of `mask`.
fn emit_now(index: u32, first: u32, count: u32, mask: u32) {
    let cap = capacity();
    for (var v = 0u; v < MAX_VIEWS; v += 1u) {
        if (mask & (1u << v)) == 0u {
            continue;
        }
        let start = atomicAdd(&cluster_list::cluster_count[count_word(v, 1u)], count);
        let written = min(count, cap - min(start, cap));
        if written > 0u {
            atomicAdd(&cluster_list::cluster_count[count_word(v, 0u)], written);
        }
        let base = list_base(v) + start;
        for (var k = 0u; k < written; k += 1u) {
            cluster_list::clusters[base + k] = Cluster(index, hierarchy_clusters[first + k]);
        }
    }
}

// Zeroes the workgroup's node counters (one thread, before a dispatch's walks).
fn clear_counters() {
    atomicStore(&tested_nodes, 0u);
    atomicStore(&leaves, 0u);
    atomicStore(&spilled, 0u);
    atomicStore(&hidden_nodes, 0u);
}

// Adds the workgroup's node counters to `hierarchy_counts` (one thread, after the walks).
fn add_counters() {
    atomicAdd(&hierarchy_counts[0], atomicLoad(&tested_nodes));
    atomicAdd(&hierarchy_counts[1], atomicLoad(&leaves));
    atomicAdd(&hierarchy_counts[2], atomicLoad(&spilled));
#ifdef OCCLUSION
    atomicAdd(&hierarchy_counts[4], atomicLoad(&hidden_nodes));
#endif
}

fn walker(index: u32) -> Walker {
    var w: Walker;
    w.instance = instance_at(min(index, instance_total() - 1u));
    w.scale = instance_max_scale(w.instance);
    w.translation = length(w.instance.world_from_local[3].xyz);
    return w;
}

// A thread per root, striding: each instance's root (the second walk: each node the
// first found hidden) tested; one that passes hands its children to the roots list.
@compute @workgroup_size(64)
fn roots(
    @builtin(workgroup_id) wg: vec3<u32>,
    @builtin(num_workgroups) groups: vec3<u32>,
    @builtin(local_invocation_index) t: u32,
) {
    if t == 0u {
        clear_counters();
        atomicStore(&entries_tested, 0u);
        atomicStore(&entries_passed, 0u);
    }
    workgroupBarrier();
    let threads = groups.x * groups.y * WORKGROUP_SIZE;
#ifdef SECOND_PASS
    let total = min(min(node_list_count[0], params.node_capacity), arrayLength(&node_list));
#else
    let total = min(params.instance_count, instance_total());
#endif
    let held = min(params.root_capacity, arrayLength(&root_list));
    let walked = walked_views();
    for (var e = linear_workgroup(wg, groups.x) * WORKGROUP_SIZE + t; e < total; e += threads) {
        var index = e;
        var id = 0xffffffffu;
#ifdef SECOND_PASS
        let entry = node_list[e];
        index = entry.instance;
        id = entry.first;
#else
        let instance = instance_at(e);
        // An instance without meshlets (a placeholder that only keeps a binding from
        // being empty) has nothing to walk.
        if instance.mesh < arrayLength(&hierarchy_roots) && instance.meshlet_count > 0u {
            id = hierarchy_roots[instance.mesh];
        }
#endif
        if index >= instance_total() || id >= arrayLength(&hierarchy_nodes) {
            continue;
        }
        walk_instance = index;
        let w = walker(index);
        let node = hierarchy_nodes[id];
        atomicAdd(&tested_nodes, 1u);
        atomicAdd(&entries_tested, 1u);
        var seen = node_views(node, w, walked);
        if seen != 0u {
            seen = node_seen(node, id, w, true, seen);
        }
        if seen == 0u {
            continue;
        }
        atomicAdd(&entries_passed, 1u);
        if node.child_count == 0u {
            atomicAdd(&leaves, 1u);
            emit_now(index, node.first_cluster, node.cluster_count, seen);
            continue;
        }
        // The root's children are tested here too: an accepted leaf emits at once, an
        // accepted inner child hands its children on as one entry of the roots list. An
        // instance whose cut is its coarsest meshlets (the root's first child, the roots
        // leaf; the second, the chain of finer levels, too fine) so costs no workgroup.
        for (var c = 0u; c < node.child_count; c += 1u) {
            atomicAdd(&tested_nodes, 1u);
            let tested = test_child(node.first_child + c, w, seen);
            let child = tested.node;
            let child_seen = tested.views;
            if child_seen == 0u {
                continue;
            }
            if child.child_count == 0u {
                atomicAdd(&leaves, 1u);
                emit_now(index, child.first_cluster, child.cluster_count, child_seen);
                continue;
            }
            let at = atomicAdd(&subtree_counts[MAX_STEPS], 1u);
            if at < held {
                root_list[at] = Subtree(index, with_views(child.first_child, child_seen), child.child_count);
            } else {
                atomicAdd(&spilled, 1u);
                emit_now(index, child.first_cluster, child.cluster_count, child_seen);
            }
        }
    }
    workgroupBarrier();
    if t == 0u {
        add_counters();
        if arrayLength(&hierarchy_counts) >= ENTRY_WORDS {
            atomicAdd(&hierarchy_counts[5], atomicLoad(&entries_tested));
            atomicAdd(&hierarchy_counts[6], atomicLoad(&entries_passed));
        }
    }
}

// Step 0's indirect dispatch: a workgroup per entry of the roots list.
@compute @workgroup_size(1)
fn walk_dispatch() {
    let n = root_total();
    let max_dim = max(params.max_per_dimension, 1u);
    let x = min(n, max_dim);
    var y = 0u;
    if x > 0u {
        y = min((n + x - 1u) / x, max_dim);
    }
    walk_args[0] = x;
    walk_args[1] = y;
    walk_args[2] = 1u;
}

@compute @workgroup_size(64)
fn fill(
    @builtin(workgroup_id) wg: vec3<u32>,
    @builtin(num_workgroups) groups: vec3<u32>,
    @builtin(local_invocation_index) t: u32,
) {
    let first_entry = linear_workgroup(wg, groups.x);
    let stride = groups.x * groups.y;
    let spreading = params.step < params.steps;
    // A spreading step's frontier is one chunk: a wide walk is handed on, not queued.
    let width = select(
        clamp(params.queue_capacity, 1u, QUEUE),
        clamp(params.queue_capacity, 1u, WORKGROUP_SIZE),
        spreading,
    );
    let cap = capacity();
    if t == 0u {
        if params.step == 0u {
            entry_total = root_total();
        } else {
            let list = params.step - 1u;
            var n = 0u;
            if list < arrayLength(&subtree_counts) {
                n = min(atomicLoad(&subtree_counts[list]), params.list_capacity);
            }
            entry_total = n;
        }
        atomicStore(&next_len, 0u);
        atomicStore(&emit_ranges, 0u);
        for (var v = 0u; v < MAX_VIEWS; v += 1u) {
            atomicStore(&emit_total[v], 0u);
        }
        clear_counters();
    }
    let entries = workgroupUniformLoad(&entry_total);
    var unfinished = 0u;
    for (var entry = first_entry; entry < entries; entry += stride) {
        // The entry: the children of a root that passed (step 0) or a handed-on range of
        // children.
        var index = entry;
        var first = 0u;
        var count = 0u;
        var s = Subtree(0u, 0u, 0u);
        if params.step == 0u {
            s = root_list[entry];
        } else {
            let at = (params.step - 1u) * params.list_capacity + entry;
            if at < arrayLength(&subtrees) {
                s = subtrees[at];
            }
        }
        index = s.instance;
        first = entry_id(s.first);
        let mask = entry_views(s.first);
        count = min(s.count, QUEUE);
        if index >= instance_total() {
            count = 0u;
        }
        walk_instance = index;
        let w = walker(index);
        if t == 0u {
            frontier_len = count;
        }
        for (var k = t; k < count; k += WORKGROUP_SIZE) {
            frontier[0][k] = with_views(first + k, mask);
        }
        var left = 0u;
        var cur = 0u;
        for (var round = 0u; round <= MAX_ROUNDS; round += 1u) {
            let n = workgroupUniformLoad(&frontier_len);
            left = n;
            if n == 0u || round == MAX_ROUNDS {
                break;
            }
            for (var base = 0u; base < n; base += WORKGROUP_SIZE) {
                let i = base + t;
                var tests = 0u;
                if i < n {
                    // Two levels a round: the node, and at once the children of an
                    // accepted inner node (the same nodes a level-by-level walk tests,
                    // in half the dependent rounds).
                    let entry = frontier[cur][i];
                    let id = entry_id(entry);
                    tests = 1u;
                    var seen = 0u;
                    if id < arrayLength(&hierarchy_nodes) {
                        seen = node_views(hierarchy_nodes[id], w, entry_views(entry));
                    }
                    if seen != 0u {
                        seen = node_seen(hierarchy_nodes[id], id, w, false, seen);
                    }
                    if seen != 0u {
                        let node = hierarchy_nodes[id];
                        if node.child_count == 0u {
                            emit_range(node.first_cluster, node.cluster_count, seen);
                            atomicAdd(&leaves, 1u);
                        } else {
                            for (var c = 0u; c < node.child_count; c += 1u) {
                                tests += 1u;
                                let tested = test_child(node.first_child + c, w, seen);
                                let child = tested.node;
                                let child_seen = tested.views;
                                if child_seen == 0u {
                                    continue;
                                }
                                if child.child_count == 0u {
                                    emit_range(child.first_cluster, child.cluster_count, child_seen);
                                    atomicAdd(&leaves, 1u);
                                } else {
                                    enqueue(child, child_seen, 1u - cur, width, spreading, index);
                                }
                            }
                        }
                    }
                    flush();
                }
                if tests > 0u {
                    atomicAdd(&tested_nodes, tests);
                }
                workgroupBarrier();
                if t == 0u {
                    emit_len = min(atomicExchange(&emit_ranges, 0u), EMIT_SLOTS);
                    for (var v = 0u; v < MAX_VIEWS; v += 1u) {
                        let total = atomicExchange(&emit_total[v], 0u);
                        if total > 0u {
                            emit_base[v] = atomicAdd(&cluster_list::cluster_count[count_word(v, 1u)], total);
                            // The written word grows by the part below the capacity: the
                            // reservations tile [0, requested), so the sum is
                            // min(requested, capacity) once every step is done, with no
                            // dispatch after.
                            let written = min(total, cap - min(emit_base[v], cap));
                            if written > 0u {
                                atomicAdd(&cluster_list::cluster_count[count_word(v, 0u)], written);
                            }
                        }
                    }
                }
                // One range after another (and view after view), consecutive threads on
                // consecutive slots.
                let ranges = workgroupUniformLoad(&emit_len);
#ifdef MULTI_VIEW
                for (var e = 0u; e < ranges; e += 1u) {
                    let packed = emit_count[e];
                    let c = entry_id(packed);
                    let range_views = entry_views(packed);
                    let range_first = emit_first[e];
                    for (var v = 0u; v < MAX_VIEWS; v += 1u) {
                        if (range_views & (1u << v)) == 0u {
                            continue;
                        }
                        let start = emit_base[v] + emit_offset[v * EMIT_SLOTS + e];
                        let base = list_base(v) + start;
                        for (var k = t; k < c; k += WORKGROUP_SIZE) {
                            if start + k < cap {
                                cluster_list::clusters[base + k] = Cluster(index, hierarchy_clusters[range_first + k]);
                            }
                        }
                    }
                }
#else
                let chunk_base = emit_base[0];
                let first_slot = list_base(0u);
                for (var e = 0u; e < ranges; e += 1u) {
                    let c = emit_count[e];
                    let start = chunk_base + emit_offset[e];
                    let range_first = emit_first[e];
                    for (var k = t; k < c; k += WORKGROUP_SIZE) {
                        if start + k < cap {
                            cluster_list::clusters[first_slot + start + k] = Cluster(index, hierarchy_clusters[range_first + k]);
                        }
                    }
                }
#endif
                workgroupBarrier();
            }
            if t == 0u {
                frontier_len = min(atomicLoad(&next_len), width);
                atomicStore(&next_len, 0u);
            }
            cur = 1u - cur;
        }
        if left > 0u {
            unfinished += 1u;
        }
        // Every thread is done with this entry's frontier before the next one is written.
        workgroupBarrier();
    }
    if t == 0u {
        add_counters();
        atomicAdd(&hierarchy_counts[3], unfinished);
    }
}
