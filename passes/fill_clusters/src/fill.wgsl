// One workgroup per instance: an instance whose mesh's bounding sphere touches the
// frustum reserves one contiguous range of the cluster list with a single atomicAdd and
// writes (instance, meshlet) for each of its meshlets, in meshlet order, threads striding
// so consecutive threads write consecutive clusters. A second, one-thread dispatch
// finalises the count of clusters written. `cpu::cpu_fill` (Rust) is the reference.

#import meshlight::dispatch::linear_workgroup
#import meshlight::meshlet::{Mesh, Cluster}
#import meshlight::instance::{Instance, instance_transform_sphere}
#import meshlight::instance_table::{instance_at, instance_total}
#import meshlight::scene_buffers::meshes
#import meshlight::view::{View, sphere_in_frustum}
#import fill_clusters::list::{clusters, cluster_count, cluster_capacity, list_length}

// The uniform block, declared once for Rust and WGSL by `GpuParams` in lib.rs.
#import fill_clusters::fill_params::Params

// The instances (`instance_at`, meshlight::instance_table) and the scene's meshes, for
// each instance's bounding sphere (meshlight::scene_buffers); the cluster list and its
// count (fill_clusters::list).
@group(0) @binding(3) var<uniform> view: View;
@group(0) @binding(4) var<uniform> params: Params;

const WORKGROUP_SIZE: u32 = 64u;

// The first slot of the workgroup's range, reserved by thread 0.
var<workgroup> range_start: u32;

fn capacity() -> u32 {
    return cluster_capacity(params.capacity, params.lists);
}

// The first cluster of this pass's list, and the index of its `requested` word.
fn list_base() -> u32 {
    return params.list * list_length(params.lists);
}

fn requested_word() -> u32 {
    return 2u * params.list + 1u;
}

// Zeroes this pass's list's words, where the buffers hold other lists too (with one
// list, the graph clears the buffer).
@compute @workgroup_size(1)
fn prepare() {
    atomicStore(&cluster_count[requested_word() - 1u], 0u);
    atomicStore(&cluster_count[requested_word()], 0u);
}

@compute @workgroup_size(64)
fn fill(@builtin(workgroup_id) wg: vec3<u32>, @builtin(local_invocation_index) t: u32) {
    let index = linear_workgroup(wg, params.groups_x);
    // Every thread reaches the barrier: visibility only decides how many clusters the
    // workgroup asks for (0 when the instance is outside the frustum or past the count).
    var count = 0u;
    var first_meshlet = 0u;
    if index < min(params.instance_count, instance_total()) {
        let instance = instance_at(index);
        let sphere = instance_transform_sphere(instance, meshes[instance.mesh].bounding_sphere);
        if sphere_in_frustum(view, sphere.xyz, sphere.w) {
            count = instance.meshlet_count;
            first_meshlet = instance.first_meshlet;
        }
    }
    if t == 0u && count > 0u {
        range_start = atomicAdd(&cluster_count[requested_word()], count);
    }
    workgroupBarrier();
    if count == 0u {
        return;
    }
    let start = range_start;
    let cap = capacity();
    if start >= cap {
        return;
    }
    // The part of the range below the capacity; nothing is written past it.
    let written = min(count, cap - start);
    let base = list_base() + start;
    for (var k = t; k < written; k += WORKGROUP_SIZE) {
        clusters[base + k] = Cluster(index, first_meshlet + k);
    }
}

@compute @workgroup_size(1)
fn finish() {
    let requested = atomicLoad(&cluster_count[requested_word()]);
    atomicStore(&cluster_count[requested_word() - 1u], min(requested, capacity()));
}
