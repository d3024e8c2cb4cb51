// Per-cluster culling: frustum, LOD cut, then the split between the software and the
// hardware rasteriser in one shared slot buffer (software from the left, hardware from
// the right). `prepare` (one thread) turns the cluster count into an indirect dispatch
// and resets the counters; `cull` runs one thread per cluster. `cpu::cpu_cull` (Rust) is
// the reference; every float operation below has its mirror there, in the same order.

#import meshlight::math::F32_MAX
#import meshlight::meshlet::{Meshlet, MeshletGroup, Cluster, meshlet_bounds, meshlet_triangle_count, lod_cut, MESHLET_NO_GROUP}
#import meshlight::instance::{Instance, instance_max_scale, instance_transform_point}
#import meshlight::view::{View, sphere_in_frustum}

struct Params {
    // Slots the raster list may use; clamped to the bound list's length.
    capacity: u32,
    // The per-dimension workgroup limit the indirect dispatch must stay under.
    max_per_dimension: u32,
    // A cluster is in the LOD cut when its own error projects to at most this many
    // pixels and its parent's to more.
    lod_threshold_px: f32,
    // Clusters whose screen box is narrower and shorter than this go to software.
    sw_threshold_px: f32,
    // 0: every cluster of the cut goes to software (no hardware rasteriser).
    hardware: u32,
    _pad0: u32,
    _pad1: u32,
    _pad2: u32,
}

// The candidate clusters, `fill_clusters`' list.
@group(0) @binding(0) var<storage, read> clusters: array<Cluster>;
// [0]: how many of `clusters` are valid.
@group(0) @binding(1) var<storage, read> cluster_count: array<u32>;
// The scene's instances, meshlets and simplification groups.
@group(0) @binding(2) var<storage, read> instances: array<Instance>;
@group(0) @binding(3) var<storage, read> meshlets: array<Meshlet>;
@group(0) @binding(4) var<storage, read> meshlet_groups: array<MeshletGroup>;
// Software clusters in slots 0, 1, …; hardware clusters in slots C-1, C-2, ….
@group(0) @binding(5) var<storage, read_write> raster_clusters: array<Cluster>;
// The eight count words of the contract (see lib.rs).
@group(0) @binding(6) var<storage, read_write> raster_counts: array<atomic<u32>>;
// draw_indirect arguments of the hardware rasteriser: [384, hardware clusters, 0, 0].
@group(0) @binding(7) var<storage, read_write> hw_args: array<atomic<u32>>;
// The cull dispatch [x, y, 1], written by `prepare`...
@group(0) @binding(8) var<storage, read_write> dispatch_out: array<u32>;
// ... and read by `cull` to linearise its workgroup id.
@group(0) @binding(9) var<storage, read> dispatch_in: array<u32>;
@group(0) @binding(10) var<uniform> view: View;
@group(0) @binding(11) var<uniform> params: Params;

const WORKGROUP_SIZE: u32 = 64u;
// Vertices of one hardware-rasterised cluster: 128 triangles × 3.
const HW_VERTICES: u32 = 384u;

fn capacity() -> u32 {
    return min(params.capacity, arrayLength(&raster_clusters));
}

fn cluster_total() -> u32 {
    return min(cluster_count[0], arrayLength(&clusters));
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
    for (var i = 0u; i < 8u; i += 1u) {
        atomicStore(&raster_counts[i], 0u);
    }
    atomicStore(&raster_counts[3], capacity());
    atomicStore(&hw_args[0], HW_VERTICES);
    atomicStore(&hw_args[1], 0u);
    atomicStore(&hw_args[2], 0u);
    atomicStore(&hw_args[3], 0u);
}

// Software when the sphere (world space) lies wholly beyond the near plane and the
// screen box of its view-space bounding box is under the threshold in both axes. The
// box's nearest face is as near as the sphere, so every corner projects with w > 0.
fn is_software(center: vec3<f32>, radius: f32) -> bool {
    let near = view.frustum[4];
    if dot(near.xyz, center) + near.w <= radius {
        return false;
    }
    let c = (view.view * vec4(center, 1.0)).xyz;
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
    let i = (wg.y * dispatch_in[0] + wg.x) * WORKGROUP_SIZE + t;
    if i >= cluster_total() {
        return;
    }
    let cluster = clusters[i];
    let instance = instances[cluster.instance];
    let meshlet = meshlets[cluster.meshlet];
    let scale = instance_max_scale(instance);
    let bounds = meshlet_bounds(meshlet);
    let center = instance_transform_point(instance, bounds.xyz);
    let radius = bounds.w * scale;
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

    let software = params.hardware == 0u || is_software(center, radius);
    // One reservation per cluster, whichever side it goes to: the two sides can never
    // meet, and past the capacity the cluster is dropped and counted.
    let total = atomicAdd(&raster_counts[2], 1u);
    let cap = capacity();
    if total >= cap {
        return;
    }
    let triangles = meshlet_triangle_count(meshlet);
    if software {
        let s = atomicAdd(&raster_counts[0], 1u);
        raster_clusters[s] = cluster;
        atomicAdd(&raster_counts[5], triangles);
    } else {
        let h = atomicAdd(&hw_args[1], 1u);
        atomicAdd(&raster_counts[1], 1u);
        raster_clusters[cap - 1u - h] = cluster;
        atomicAdd(&raster_counts[6], triangles);
    }
}
