// Per-cluster culling: frustum, LOD cut, with OCCLUSION the test against a depth
// pyramid, then the split between the software and the hardware rasteriser in one
// shared slot buffer (software from the left, hardware from the right). `prepare` (one
// thread) turns the cluster count into an indirect dispatch and resets the counters;
// `cull` runs one thread per cluster. `cpu::cpu_cull` (Rust) is the reference; every
// float operation below has its mirror there, in the same order.
//
// Two passes per frame with OCCLUSION (`params.mode`): the first tests against last
// frame's pyramid, through last frame's view-projection and each instance's previous
// transform, and appends what it finds hidden to `occluded`; the second takes that list
// as its clusters and tests it against this frame's pyramid with the current view, and
// puts what survives into the slots the first pass left free, split as the first pass
// splits: software from the left of that range, hardware from its right (lib.rs, "Two-pass
// occlusion"). With WALKED, the second pass also takes the clusters the
// second hierarchy walk listed (below the nodes the first walk found hidden), after its
// own list: those were never tested, and are tested like the rest.
//
// With STREAMING (a streamed scene, `meshlight_gpu_scene::streaming`), each cluster of
// the LOD cut asks for the page of its source group when that group's error shows but
// its page is missing (the cluster stands in for finer ones the pool lacks), and the
// first cluster of each run of one page marks that page in use when its group is
// refined (so it is kept). Each page is listed once a frame, through a per-group mark
// of the last frame it was wanted.

#import meshlight::dispatch::linear_workgroup
#import meshlight::math::F32_MAX
#import meshlight::meshlet::{Meshlet, MeshletGroup, Cluster, meshlet_bounds, meshlet_triangle_count, lod_cut, error_perceptible, MESHLET_NO_GROUP}
#import meshlight::instance::{Instance, instance_max_scale, instance_transform_point}
#import meshlight::instance_table::instance_at
#import meshlight::scene_buffers::{meshlets, meshlet_groups}
#import meshlight::view::{View, sphere_in_frustum, project_error_to_pixels}
#ifdef OCCLUSION
#import meshlight::occlusion::{instance_sphere_rect, sphere_occluded}
#endif
// The uniform block, declared once for Rust and WGSL by `GpuParams` in lib.rs.
#import cull_lod::params::Params

// The candidate clusters, `fill_clusters`' list.
@group(0) @binding(0) var<storage, read> clusters: array<Cluster>;
// [0]: how many of `clusters` are valid.
@group(0) @binding(1) var<storage, read> cluster_count: array<u32>;
// The scene's meshlets and simplification groups (meshlight::scene_buffers); its
// instances through `instance_at` (meshlight::instance_table).
// Software clusters in slots 0, 1, …; hardware clusters in slots C-1, C-2, ….
@group(0) @binding(5) var<storage, read_write> raster_clusters: array<Cluster>;
// The count words of the contract (see lib.rs): eight, twelve with OCCLUSION
// (`OCCLUSION_COUNT_WORDS`).
@group(0) @binding(6) var<storage, read_write> raster_counts: array<atomic<u32>>;
// draw_indirect arguments of the hardware rasteriser: [384, hardware clusters, 0, 0].
@group(0) @binding(7) var<storage, read_write> hw_args: array<atomic<u32>>;
// The cull dispatch [x, y, 1], written by `prepare`...
@group(0) @binding(8) var<storage, read_write> dispatch_out: array<u32>;
// ... and read by `cull` to linearise its workgroup id.
@group(0) @binding(9) var<storage, read> dispatch_in: array<u32>;
@group(0) @binding(10) var<uniform> view: View;
@group(0) @binding(11) var<uniform> params: Params;
#ifdef STREAMING
// Per group of the scene: its error while its page is not resident, 0 while it is.
@group(0) @binding(17) var<storage, read> page_errors: array<f32>;
// Per group: 1 + the last frame (`view.frame_index`) its page was wanted; kept across
// frames, never cleared.
@group(0) @binding(18) var<storage, read_write> page_marks: array<atomic<u32>>;
// The pages wanted this frame, each once: (group, priority as f32 bits: the error in
// pixels of a missing page, 0 for a page in use).
@group(0) @binding(19) var<storage, read_write> page_requests: array<vec2<u32>>;
// [0] requests written, [1] found (more than the list holds: the rest wait a frame).
@group(0) @binding(20) var<storage, read_write> page_request_count: array<atomic<u32>>;

// The page cluster `i` lies on is in use when its group is refined for the instance
// (its error shows: the group's children, this page, are drawn). Asked once per run of
// the list's clusters from one page of one instance (the walk lists a leaf's meshlets
// together, the flat fill an instance's meshlets in page order), by the run's first,
// whatever the frustum says of it: one test and one mark where every cluster of the
// page would otherwise hit the same word.
fn mark_page_in_use(i: u32, cluster: Cluster, meshlet: Meshlet, instance: Instance, scale: f32) {
    let group = meshlet.parent_group;
    if group == MESHLET_NO_GROUP {
        return;
    }
    if i > 0u {
        let previous = clusters[i - 1u];
        if previous.instance == cluster.instance && meshlets[previous.meshlet].parent_group == group {
            return;
        }
    }
    let sphere = meshlet_groups[group].lod_sphere;
    let centre = (instance.world_from_local * vec4(sphere.xyz, 1.0)).xyz;
    let px = project_error_to_pixels(view, centre, sphere.w * scale, meshlet_groups[group].error * scale);
    if error_perceptible(px, params.lod_threshold_px) {
        want_page(group, 0.0);
    }
}

// Lists `group`'s page unless this frame already has.
fn want_page(group: u32, priority: f32) {
    let stamp = view.frame_index + 1u;
    // Most clusters find their page marked already: a load, no atomic write.
    if atomicLoad(&page_marks[group]) == stamp {
        return;
    }
    if atomicMax(&page_marks[group], stamp) == stamp {
        return;
    }
    let k = atomicAdd(&page_request_count[1], 1u);
    if k < arrayLength(&page_requests) {
        page_requests[k] = vec2(group, bitcast<u32>(priority));
        atomicAdd(&page_request_count[0], 1u);
    }
}
#endif
#ifdef OCCLUSION
// The depth pyramid (R32Float, farthest depth per texel, full mip chain): last frame's
// in the first pass, this frame's in the second.
@group(0) @binding(12) var pyramid: texture_2d<f32>;
#ifdef SECOND_PASS
// The first pass's `raster_counts`, for the slots it left free.
@group(0) @binding(15) var<storage, read> first_counts: array<u32>;
#else
// The clusters the first pass found hidden: the second pass's candidates.
@group(0) @binding(13) var<storage, read_write> occluded: array<Cluster>;
// [0] candidates written, [1] candidates found: the layout of `cluster_count`, so the
// second pass takes it as its count.
@group(0) @binding(14) var<storage, read_write> occluded_count: array<atomic<u32>>;
#endif
#ifdef PER_INSTANCE
// Per instance i: [2i] clusters of the first pass's LOD cut, [2i + 1] of those hidden;
// the first pass adds to both (from zero), the second takes back the ones it finds
// visible, so after both passes [2i + 1] counts what occlusion culled.
@group(0) @binding(16) var<storage, read_write> per_instance: array<atomic<u32>>;

fn per_instance_word(instance: u32, word: u32) -> u32 {
    return instance * 2u + word;
}
#endif
#ifdef WALKED
// The second walk's list and its count words (`fill_clusters`' layout).
@group(0) @binding(17) var<storage, read> walked_clusters: array<Cluster>;
@group(0) @binding(18) var<storage, read> walked_cluster_count: array<u32>;
#endif
#endif

const WORKGROUP_SIZE: u32 = 64u;
// Vertices of one hardware-rasterised cluster: 128 triangles × 3.
const HW_VERTICES: u32 = 384u;

fn is_second_pass() -> bool {
#ifdef SECOND_PASS
    return true;
#else
    return false;
#endif
}

fn capacity() -> u32 {
    return min(params.capacity, arrayLength(&raster_clusters));
}

#ifdef OCCLUSION
const COUNT_WORDS: u32 = 12u;

// The slots this pass may fill, [x, y): the whole list in the first pass; in the
// second, what lies between the first pass's software clusters and its hardware ones.
// Software clusters fill it from x (`raster_counts[7]`, where sw_raster's `accumulate`
// starts), hardware ones from y down, so hardware rasteriser instance j draws slot
// y - 1 - j (`raster_counts[3]` = y is the `C` it reads).
fn slot_range() -> vec2<u32> {
#ifdef SECOND_PASS
    let c = min(first_counts[3], capacity());
    let top = c - min(first_counts[1], c);
    return vec2(min(first_counts[0], top), top);
#else
    return vec2(0u, capacity());
#endif
}

// The occlusion test of one cluster sphere (mesh space), through last frame's camera
// and transform in the first pass, this frame's in the second. Counts the clusters it
// could test.
fn is_occluded(instance: Instance, bounds: vec4<f32>) -> bool {
    let rect = instance_sphere_rect(instance, view, bounds);
    if rect.testable {
        atomicAdd(&raster_counts[11], 1u);
    }
    return sphere_occluded(pyramid, rect);
}
#else
const COUNT_WORDS: u32 = 8u;
#endif

// The list read: list `params.list` of `params.lists` equal parts of the buffers
// (fill_clusters' list module), its written word at cluster_count[2 * list].
fn list_length() -> u32 {
    return arrayLength(&clusters) / max(params.lists, 1u);
}

fn listed_total() -> u32 {
    return min(cluster_count[2u * params.list], list_length());
}

fn walked_total() -> u32 {
#ifdef WALKED
    return min(walked_cluster_count[0], arrayLength(&walked_clusters));
#else
    return 0u;
#endif
}

fn cluster_total() -> u32 {
    return listed_total() + walked_total();
}

// Cluster i of the pass: `clusters` first, then the second walk's.
fn cluster_at(i: u32) -> Cluster {
#ifdef WALKED
    let listed = listed_total();
    if i >= listed {
        return walked_clusters[i - listed];
    }
#endif
    // One list (the common case) starts at 0: no division per cluster.
    if params.lists <= 1u {
        return clusters[i];
    }
    return clusters[params.list * list_length() + i];
}

@compute @workgroup_size(1)
fn prepare() {
    let groups = (cluster_total() + WORKGROUP_SIZE - 1u) / WORKGROUP_SIZE;
    let max_dim = max(params.max_per_dimension, 1u);
    let x = min(groups, max_dim);
    var y = 0u;
    if x > 0u {
        y = min((groups + x - 1u) / x, max_dim);
    }
    dispatch_out[0] = x;
    dispatch_out[1] = y;
    dispatch_out[2] = 1u;
    for (var i = 0u; i < COUNT_WORDS; i += 1u) {
        atomicStore(&raster_counts[i], 0u);
    }
    atomicStore(&raster_counts[3], capacity());
#ifdef OCCLUSION
    let range = slot_range();
    atomicStore(&raster_counts[3], range.y);
    // Where this pass's software clusters start (0 in the first pass): sw_raster's
    // `accumulate` reads it.
    atomicStore(&raster_counts[7], range.x);
    atomicStore(&raster_counts[10], range.y - range.x);
#ifndef SECOND_PASS
    atomicStore(&occluded_count[0], 0u);
    atomicStore(&occluded_count[1], 0u);
#endif
#endif
#ifdef STREAMING
    // A cull that appends (a shadow view's) keeps the requests of the culls before it.
    if params.append_requests == 0u {
        atomicStore(&page_request_count[0], 0u);
        atomicStore(&page_request_count[1], 0u);
    }
#endif
    atomicStore(&hw_args[0], HW_VERTICES);
    atomicStore(&hw_args[1], 0u);
    atomicStore(&hw_args[2], 0u);
    atomicStore(&hw_args[3], 0u);
}

// Software when the sphere (world space) lies wholly beyond the near plane and the
// screen box of its view-space bounding box is under the threshold in both axes. The
// box's nearest face is as near as the sphere, so every corner projects with w > 0.
// The near plane is the view's (view-space depth `near`), not `frustum[4]`: a shadow
// cascade's view keeps a caster plane there.
fn is_software(center: vec3<f32>, radius: f32) -> bool {
    let c = (view.view * vec4(center, 1.0)).xyz;
    if -c.z - view.near <= radius {
        return false;
    }
    var lo = vec2(F32_MAX);
    var hi = vec2(-F32_MAX);
    for (var k = 0u; k < 8u; k += 1u) {
        let offset = vec3(
            select(-radius, radius, (k & 1u) != 0u),
            select(-radius, radius, (k & 2u) != 0u),
            select(-radius, radius, (k & 4u) != 0u),
        );
        let clip = view.projection * vec4(c + offset, 1.0);
        let ndc = clip.xy / clip.w;
        let screen = vec2(
            (ndc.x * 0.5 + 0.5) * view.viewport_size.x,
            (0.5 - ndc.y * 0.5) * view.viewport_size.y,
        );
        lo = min(lo, screen);
        hi = max(hi, screen);
    }
    let size = hi - lo;
    return size.x < params.sw_threshold_px && size.y < params.sw_threshold_px;
}

@compute @workgroup_size(64)
fn cull(@builtin(workgroup_id) wg: vec3<u32>, @builtin(local_invocation_index) t: u32) {
    let i = linear_workgroup(wg, dispatch_in[0]) * WORKGROUP_SIZE + t;
    if i >= cluster_total() {
        return;
    }
    let cluster = cluster_at(i);
    // A cluster of the second walk: the first pass never saw it.
    let walked = i >= listed_total();
    let instance = instance_at(cluster.instance);
    let meshlet = meshlets[cluster.meshlet];
    let scale = instance_max_scale(instance);
    let bounds = meshlet_bounds(meshlet);
    let center = instance_transform_point(instance, bounds.xyz);
    let radius = bounds.w * scale;
#ifdef STREAMING
    mark_page_in_use(i, cluster, meshlet, instance, scale);
#endif
    if !sphere_in_frustum(view, center, radius) {
        return;
    }
    atomicAdd(&raster_counts[4], 1u);

    var own_sphere = bounds;
    var own_error = 0.0;
    if meshlet.source_group != MESHLET_NO_GROUP {
        let group = meshlet_groups[meshlet.source_group];
        own_sphere = group.lod_sphere;
        own_error = group.error;
    }
    var parent_sphere = vec4(0.0);
    var parent_error = F32_MAX;
    if meshlet.parent_group != MESHLET_NO_GROUP {
        let group = meshlet_groups[meshlet.parent_group];
        parent_sphere = group.lod_sphere;
        parent_error = group.error;
    }
    if !lod_cut(view, instance.world_from_local, scale, own_sphere, own_error, parent_sphere,
        parent_error, params.lod_threshold_px) {
        return;
    }
#ifdef STREAMING
    if meshlet.source_group != MESHLET_NO_GROUP {
        let missing = page_errors[meshlet.source_group];
        if missing > 0.0 {
            let centre = (instance.world_from_local * vec4(own_sphere.xyz, 1.0)).xyz;
            let px = project_error_to_pixels(view, centre, own_sphere.w * scale, missing * scale);
            if error_perceptible(px, params.lod_threshold_px) {
                want_page(meshlet.source_group, px);
            }
        }
    }
#endif

#ifdef OCCLUSION
    // The cut the test saw: counted only when it runs (a frame that tests nothing runs
    // `cull` compiled without OCCLUSION where it can, which counts nothing here).
    if params.test_occlusion != 0u {
        atomicAdd(&raster_counts[8], 1u);
    }
#ifdef PER_INSTANCE
    let at = per_instance_word(cluster.instance, 0u);
    let in_bounds = at + 1u < arrayLength(&per_instance);
    // The first pass counts its cut; the second, the cut of what the second walk found.
    if in_bounds && (!is_second_pass() || walked) {
        atomicAdd(&per_instance[at], 1u);
    }
#endif
    if params.test_occlusion != 0u && is_occluded(instance, bounds) {
        atomicAdd(&raster_counts[9], 1u);
#ifdef PER_INSTANCE
        if in_bounds && (!is_second_pass() || walked) {
            atomicAdd(&per_instance[at + 1u], 1u);
        }
#endif
#ifndef SECOND_PASS
        let k = atomicAdd(&occluded_count[1], 1u);
        if k < arrayLength(&occluded) {
            occluded[k] = cluster;
            atomicAdd(&occluded_count[0], 1u);
        }
#endif
        return;
    }
#ifdef PER_INSTANCE
    // A first-pass candidate found visible after all.
    if in_bounds && is_second_pass() && !walked {
        atomicSub(&per_instance[at + 1u], 1u);
    }
#endif
    let range = slot_range();
    let software = params.hardware == 0u || is_software(center, radius);
#else
    let range = vec2(0u, capacity());
    let software = params.hardware == 0u || is_software(center, radius);
#endif
    // One reservation per cluster, whichever side it goes to: the two sides can never
    // meet, and past the capacity the cluster is dropped and counted.
    let total = atomicAdd(&raster_counts[2], 1u);
    let cap = range.y;
    if total >= range.y - range.x {
        return;
    }
    let triangles = meshlet_triangle_count(meshlet);
    if software {
        let s = atomicAdd(&raster_counts[0], 1u);
        raster_clusters[range.x + s] = cluster;
        atomicAdd(&raster_counts[5], triangles);
    } else {
        let h = atomicAdd(&hw_args[1], 1u);
        atomicAdd(&raster_counts[1], 1u);
        raster_clusters[cap - 1u - h] = cluster;
        atomicAdd(&raster_counts[6], triangles);
    }
}
