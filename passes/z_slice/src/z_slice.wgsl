// Per clusterable object, the range of depth slices of the froxel grid its bounds touch,
// appended as one instance per (object, slice) for the count and populate draws.
// `prepare` resets the counters, publishes the grid and zeroes count_raster's counts; `slice` runs one
// thread per object of the bound list (a direct dispatch: its length is known on the
// CPU), and its last workgroup to arrive turns the totals into draw and dispatch
// arguments, so the stage is two dependent dispatches, neither indirect. `cpu::cpu_z_slice` (Rust) is the reference: every
// float operation below has its mirror there, in the same order.

#import meshlight::light::{ClusterableObject, ClusterGrid, z_slice_of_depth, CLUSTERABLE_SPOT_LIGHT, CLUSTERABLE_PROBE, CLUSTERABLE_DECAL, CLUSTERABLE_TYPE_COUNT}
#import meshlight::view::{View, sphere_in_frustum}
#import meshlight::dispatch::{fold_dispatch, linear_workgroup}
#import z_slice::instance::{SliceInstance}

// The uniform block, declared once for Rust and WGSL by `GpuParams` in lib.rs.
#import z_slice::params::Params

// The objects to assign; `object_count[0]` of them are valid.
@group(0) @binding(0) var<storage, read> objects: array<ClusterableObject>;
// [0]: how many of `objects` are valid.
@group(0) @binding(1) var<storage, read> object_count: array<u32>;
// The (object, slice) list; its length is the capacity unless `params.capacity` is lower.
@group(0) @binding(2) var<storage, read_write> slice_instances: array<SliceInstance>;
// The eight count words of the contract (see lib.rs).
@group(0) @binding(3) var<storage, read_write> slice_counts: array<atomic<u32>>;
// draw_indirect arguments: [quad vertices, instances written, 0, 0].
@group(0) @binding(4) var<storage, read_write> slice_draw_args: array<u32>;
// dispatch_workgroups_indirect arguments: a workgroup per 64 instances written, [x, y, 1].
@group(0) @binding(5) var<storage, read_write> slice_dispatch_args: array<u32>;
// The grid this frame was sliced with, for the passes after this one.
@group(0) @binding(6) var<storage, read_write> cluster_grid: ClusterGrid;
// [0]: workgroups of `slice` that have added their counts; zeroed by `prepare`.
@group(0) @binding(7) var<storage, read_write> arrivals: array<atomic<u32>>;
// Per froxel and kind, count_raster's counts: zeroed by `prepare`.
@group(0) @binding(8) var<storage, read_write> cluster_counts: array<u32>;
@group(0) @binding(9) var<uniform> view: View;
@group(0) @binding(10) var<uniform> grid: ClusterGrid;
@group(0) @binding(11) var<uniform> params: Params;

const WORKGROUP_SIZE: u32 = 64u;
// Instances per workgroup in the dispatch arguments: the compute walks of the later
// stages take up to this many (object, slice) instances per workgroup.
const INSTANCES_PER_GROUP: u32 = 64u;
const COUNT_WORDS: u32 = 8u;
const WORD_REQUESTED: u32 = 0u;
const WORD_CAPACITY: u32 = 1u;
const WORD_INVALID: u32 = 2u;
const WORD_CULLED: u32 = 3u;
const WORD_VISIBLE: u32 = 4u;

// Ranges above this (infinity included) are this: it lies beyond any far distance, and
// every product below stays finite, so no 0 × ∞ turns into NaN.
const RANGE_LIMIT: f32 = 1e30;
// A direction shorter than this (squared) has no axis to normalise.
const MIN_DIRECTION_SQUARED: f32 = 1e-12;
const SQRT_2: f32 = 1.4142135;
const SQRT_3: f32 = 1.7320508;

const OUTCOME_VISIBLE: u32 = 0u;
const OUTCOME_INVALID: u32 = 1u;
const OUTCOME_CULLED: u32 = 2u;

// The view-space depth interval an object's bounds cover, or why it has none.
struct Extent {
    outcome: u32,
    near_depth: f32,
    far_depth: f32,
}

// Neither NaN nor infinite, by the bits: comparisons with NaN may be folded away.
fn is_finite(x: f32) -> bool {
    return (bitcast<u32>(x) & 0x7f800000u) != 0x7f800000u;
}

fn is_finite3(v: vec3<f32>) -> bool {
    return is_finite(v.x) && is_finite(v.y) && is_finite(v.z);
}

fn capacity() -> u32 {
    return min(params.capacity, arrayLength(&slice_instances));
}

fn object_total() -> u32 {
    return min(object_count[0], arrayLength(&objects));
}

// How far a spherical sector (apex at the origin, unit axis, radius `range`, half-angle
// as cos/sin) reaches along a unit direction at cosine `cos_to_axis` from its axis:
// `range` when the direction lies inside the cone, else the cap's edge, never below the
// apex.
fn sector_reach(range: f32, cos_to_axis: f32, cos_angle: f32, sin_angle: f32) -> f32 {
    if cos_to_axis >= cos_angle {
        return range;
    }
    let sin_to_axis = sqrt(max(1.0 - cos_to_axis * cos_to_axis, 0.0));
    return max(range * (cos_to_axis * cos_angle + sin_to_axis * sin_angle), 0.0);
}

fn object_extent(object: ClusterableObject) -> Extent {
    let invalid = Extent(OUTCOME_INVALID, 0.0, 0.0);
    let culled = Extent(OUTCOME_CULLED, 0.0, 0.0);
    let p = object.position_range.xyz;
    let range_bits = bitcast<u32>(object.position_range.w);
    let magnitude = range_bits & 0x7fffffffu;
    let is_nan = magnitude > 0x7f800000u;
    let is_negative = range_bits != magnitude && magnitude != 0u;
    if object.kind >= CLUSTERABLE_TYPE_COUNT || !is_finite3(p) || is_nan || is_negative {
        return invalid;
    }
    let m = view.view;
    var axis_z = 0.0;
    if object.kind == CLUSTERABLE_SPOT_LIGHT || object.kind == CLUSTERABLE_DECAL {
        let d = object.direction_cos_angle.xyz;
        if !is_finite3(d) || d.x * d.x + d.y * d.y + d.z * d.z < MIN_DIRECTION_SQUARED {
            return invalid;
        }
        if object.kind == CLUSTERABLE_SPOT_LIGHT
            && !(is_finite(object.direction_cos_angle.w) && is_finite(object.sin_angle)) {
            return invalid;
        }
        let v = m[0].xyz * d.x + m[1].xyz * d.y + m[2].xyz * d.z;
        axis_z = v.z / sqrt(v.x * v.x + v.y * v.y + v.z * v.z);
    }
    // Range 0 (either sign) affects nothing: not drawn, and not an error.
    if magnitude == 0u {
        return culled;
    }
    let range = min(object.position_range.w, RANGE_LIMIT);
    // A sphere around the object for the frustum test, and how far the object reaches
    // from its centre's depth towards the camera and away from it.
    var bound = range;
    var reach_near = range;
    var reach_far = range;
    if object.kind == CLUSTERABLE_SPOT_LIGHT {
        let cos_angle = object.direction_cos_angle.w;
        reach_near = sector_reach(range, axis_z, cos_angle, object.sin_angle);
        reach_far = sector_reach(range, -axis_z, cos_angle, object.sin_angle);
    } else if object.kind == CLUSTERABLE_PROBE {
        let reach = range * (abs(m[0].z) + abs(m[1].z) + abs(m[2].z));
        reach_near = reach;
        reach_far = reach;
        bound = range * SQRT_3;
    } else if object.kind == CLUSTERABLE_DECAL {
        let across = sqrt(max(1.0 - axis_z * axis_z, 0.0));
        let reach = range * abs(axis_z) + range * SQRT_2 * across;
        reach_near = reach;
        reach_far = reach;
        bound = range * SQRT_3;
    }
    if !sphere_in_frustum(view, p, bound) {
        return culled;
    }
    let depth = -(m[0].z * p.x + m[1].z * p.y + m[2].z * p.z + m[3].z);
    let far_depth = depth + reach_far;
    // Wholly nearer than the near plane: behind the camera, or between it and the plane.
    if far_depth < view.near {
        return culled;
    }
    return Extent(OUTCOME_VISIBLE, depth - reach_near, far_depth);
}

// A lane per word of `cluster_counts` (grid-stride past the dispatch), which it zeroes;
// the first lane also resets the counters and publishes the grid.
@compute @workgroup_size(64)
fn prepare(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    for (var i = id.x; i < arrayLength(&cluster_counts); i += groups.x * WORKGROUP_SIZE) {
        cluster_counts[i] = 0u;
    }
    if id.x != 0u {
        return;
    }
    atomicStore(&arrivals[0], 0u);
    for (var i = 0u; i < COUNT_WORDS; i += 1u) {
        atomicStore(&slice_counts[i], 0u);
    }
    atomicStore(&slice_counts[WORD_CAPACITY], capacity());
    cluster_grid = grid;
}

// The workgroup's counts, summed in workgroup memory so each workgroup adds to the global
// words once: a million objects adding one each to the same word serialised on it.
var<workgroup> group_counts: array<atomic<u32>, 8>;
// Where the workgroup's instances start in the list.
var<workgroup> group_base: u32;
// Whether this workgroup was the last to add its counts.
var<workgroup> group_last: bool;

@compute @workgroup_size(64)
fn slice(
    @builtin(workgroup_id) wg: vec3<u32>,
    @builtin(num_workgroups) groups: vec3<u32>,
    @builtin(local_invocation_index) t: u32,
) {
    if t < COUNT_WORDS {
        atomicStore(&group_counts[t], 0u);
    }
    workgroupBarrier();
    let i = linear_workgroup(wg, groups.x) * WORKGROUP_SIZE + t;
    var first = 0u;
    var n = 0u;
    var local = 0u;
    if i < object_total() {
        let object = objects[i];
        let extent = object_extent(object);
        if extent.outcome == OUTCOME_INVALID {
            atomicAdd(&group_counts[WORD_INVALID], 1u);
        } else if extent.outcome == OUTCOME_CULLED {
            atomicAdd(&group_counts[WORD_CULLED], 1u);
        } else {
            atomicAdd(&group_counts[WORD_VISIBLE + object.kind], 1u);
            first = z_slice_of_depth(grid, extent.near_depth);
            // `max`: log2 is not correctly rounded, so two depths an ulp apart must not cross.
            let last = max(z_slice_of_depth(grid, extent.far_depth), first);
            n = last - first + 1u;
            // One reservation per object keeps its slices together.
            local = atomicAdd(&group_counts[WORD_REQUESTED], n);
        }
    }
    workgroupBarrier();
    if t == 0u {
        group_base = atomicAdd(&slice_counts[WORD_REQUESTED], atomicLoad(&group_counts[WORD_REQUESTED]));
        for (var w = WORD_INVALID; w < COUNT_WORDS; w += 1u) {
            let c = atomicLoad(&group_counts[w]);
            if c > 0u {
                atomicAdd(&slice_counts[w], c);
            }
        }
    }
    // The counts are added before the arrival is: the last workgroup to arrive reads
    // every workgroup's.
    storageBarrier();
    if t == 0u {
        group_last = atomicAdd(&arrivals[0], 1u) + 1u == groups.x * groups.y;
    }
    workgroupBarrier();
    // Past the capacity the instances are counted, not written.
    let base = group_base + local;
    let cap = capacity();
    var room = 0u;
    if base < cap {
        room = cap - base;
    }
    for (var k = 0u; k < min(n, room); k += 1u) {
        slice_instances[base + k] = SliceInstance(i, first + k);
    }
    if workgroupUniformLoad(&group_last) {
        storageBarrier();
        if t == 0u {
            finish();
        }
    }
}

// The draw and dispatch arguments from the totals, once every object has counted.
fn finish() {
    let written = min(atomicLoad(&slice_counts[WORD_REQUESTED]), atomicLoad(&slice_counts[WORD_CAPACITY]));
    slice_draw_args[0] = params.quad_vertices;
    slice_draw_args[1] = written;
    slice_draw_args[2] = 0u;
    slice_draw_args[3] = 0u;
    let d = fold_dispatch((written + INSTANCES_PER_GROUP - 1u) / INSTANCES_PER_GROUP, params.max_per_dimension);
    slice_dispatch_args[0] = d.x;
    slice_dispatch_args[1] = d.y;
    slice_dispatch_args[2] = d.z;
}
