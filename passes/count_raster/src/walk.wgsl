#define_import_path count_raster::walk

// The walk of light clustering, once for both stages that run it: over z_slice's
// (object, slice) instances, each covering the tile rectangle `froxel_rect` gives it, every
// froxel of that rectangle tested with `object_touches_froxel`. What happens at a froxel
// the object touches depends on the stage:
//
// - count_raster (`count.wgsl`): one more object of its kind, an atomic add.
// - populate (`populate.wgsl`, which defines POPULATE): a place claimed in the
//   (froxel, kind) list and the object's index written there.
//
// `raster`: one quad per instance on a viewport of one pixel per tile, colour writes off;
// the fragment visits its froxel. `compute`: workgroups share their lanes out over the
// tiles of their share of the instances (at most 64) a round. Both stages and both
// implementations call `visit_froxel`, so every pair is decided by the same code.
//
// populate: a claim takes one from the list's count (`atomicSub`), so the count itself is
// the cursor, counting down: the place is how many were counted minus how many were left,
// and the number counted is known without it, from the prefix sum (the next list's
// offset, or the total, minus this one's). No cursor buffer has to be zeroed first. A list
// only ever receives as many entries as its count: a place past it (should the GPU decide
// a pair here otherwise than in the count stage) is claimed and not written, so no list
// spills into the next; places at or past the capacity are claimed, never written.

#import meshlight::view::View
#import meshlight::light::{ClusterableObject, ClusterGrid, cluster_index, CLUSTERABLE_TYPE_COUNT}
#import meshlight::froxel::{ViewObject, TileRect, view_object, froxel_aabb, froxel_rect, object_touches_froxel, froxel_quad_corner, walk_rounds, walk_instance, walk_layout, walk_tile, WALK_GROUP}
#import z_slice::instance::{SliceInstance}

// The objects `slice_instances` refers to.
@group(0) @binding(0) var<storage, read> objects: array<ClusterableObject>;
// z_slice's (object, slice) list.
@group(0) @binding(1) var<storage, read> slice_instances: array<SliceInstance>;
// z_slice's count words: [0] instances requested, [1] the list's capacity.
@group(0) @binding(2) var<storage, read> slice_counts: array<u32>;
// The grid z_slice sliced with.
@group(0) @binding(3) var<storage, read> cluster_grid: ClusterGrid;
// Per froxel and kind: `cluster_counts[froxel * CLUSTERABLE_TYPE_COUNT + kind]`.
// count_raster: zeroed by z_slice's `prepare`, then counted. populate: in, count_raster's
// counts; during the walk, places left to claim (wrapping below zero when the walk finds
// more pairs than were counted); out (after `settle`), the entries each list holds.
@group(0) @binding(4) var<storage, read_write> cluster_counts: array<atomic<u32>>;
@group(0) @binding(5) var<uniform> view: View;

#ifdef POPULATE
// The uniform block, declared once for Rust and WGSL by `ListParams` in lib.rs.
#import count_raster::list_params::ListParams

// Exclusive prefix sum of count_raster's counts: where each (froxel, kind) list starts.
@group(0) @binding(6) var<storage, read> cluster_offsets: array<u32>;
// The lists, back to back: object indices.
@group(0) @binding(7) var<storage, read_write> cluster_objects: array<u32>;
// [0]: entries every list together needs (the prefix sum's total).
@group(0) @binding(8) var<storage, read> list_total: array<u32>;
// [0] entries needed, [1] the capacity: overflow when [0] > [1].
@group(0) @binding(9) var<storage, read_write> list_counts: array<u32>;
@group(0) @binding(10) var<uniform> list_params: ListParams;

// Entries the lists may hold.
fn list_capacity() -> u32 {
    return min(list_params.capacity, arrayLength(&cluster_objects));
}

// Lists bound: one per (froxel, kind).
fn list_count() -> u32 {
    return min(arrayLength(&cluster_offsets), arrayLength(&cluster_counts));
}

// What count_raster counted for `list`, from the exclusive prefix sum: the next list's
// offset, or the total after the last list, minus this list's (u32, wrapping as the sums do).
fn counted_in(list: u32) -> u32 {
    var end = list_total[0];
    if list + 1u < list_count() {
        end = cluster_offsets[list + 1u];
    }
    return end - cluster_offsets[list];
}

// Claims a place in `list` and writes `object` there when the place was counted and lies
// below the capacity.
fn claim_place(list: u32, object: u32) {
    if list < list_count() {
        // Places left before this claim: `counted` down to 1 for the counted ones,
        // then 0 and (wrapped) above `counted` for any past them.
        let left = atomicSub(&cluster_counts[list], 1u);
        let counted = counted_in(list);
        let place = counted - left;
        let at = cluster_offsets[list] + place;
        if left > 0u && left <= counted && at < list_capacity() {
            cluster_objects[at] = object;
        }
    }
}
#endif

fn instances_written() -> u32 {
    return min(min(slice_counts[0], slice_counts[1]), arrayLength(&slice_instances));
}

// The stage's work at `froxel` for `object` (seen from the view as `o`).
fn visit_froxel(o: ViewObject, object: u32, froxel: vec3<u32>) {
    if object_touches_froxel(o, froxel_aabb(view, cluster_grid, froxel)) {
        let list = cluster_index(cluster_grid, froxel) * CLUSTERABLE_TYPE_COUNT + o.kind;
#ifdef POPULATE
        claim_place(list, object);
#else
        if list < arrayLength(&cluster_counts) {
            atomicAdd(&cluster_counts[list], 1u);
        }
#endif
    }
}

// What a quad's vertex gets.
struct QuadVertex {
    @builtin(vertex_index) corner: u32,
    @builtin(instance_index) pair: u32,
}

struct Varyings {
    @builtin(position) position: vec4<f32>,
    @location(0) @interpolate(flat) instance: u32,
}

// `raster`: the corner of instance `pair`'s tile rectangle.
fn quad_vertex(v: QuadVertex) -> Varyings {
    let pair = slice_instances[v.pair];
    let o = view_object(view, objects[pair.object]);
    let rect = froxel_rect(view, cluster_grid, o, pair.slice);
    return Varyings(froxel_quad_corner(cluster_grid, rect, v.corner), v.pair);
}

// `raster`: the froxel of one pixel of an instance's quad.
fn quad_fragment(in: Varyings) {
    let pair = slice_instances[in.instance];
    let o = view_object(view, objects[pair.object]);
    visit_froxel(o, pair.object, vec3(vec2<u32>(in.position.xy), pair.slice));
}

// What a lane of the compute walk gets.
struct WalkLane {
    @builtin(workgroup_id) workgroup: vec3<u32>,
    @builtin(num_workgroups) workgroups: vec3<u32>,
    @builtin(local_invocation_index) index: u32,
}

// `compute`, a workgroup of WALK_GROUP lanes: a direct dispatch of a fixed size, each
// workgroup walking its share of the instances (at most 64) a round.
fn compute_walk(lane: WalkLane) {
    let t = lane.index;
    let written = instances_written();
    let rounds = walk_rounds(lane.workgroups, written);
    for (var round = 0u; round < rounds; round += 1u) {
        let instance = walk_instance(lane.workgroup, lane.workgroups, round, t, written);
        var pair = SliceInstance(0u, 0u);
        var rect = TileRect(vec2(1u, 0u), vec2(0u));
        if instance < written {
            pair = slice_instances[instance];
            rect = froxel_rect(view, cluster_grid, view_object(view, objects[pair.object]), pair.slice);
        }
        let total = walk_layout(t, pair.object, pair.slice, rect);
        for (var i = t; i < total; i += WALK_GROUP) {
            let w = walk_tile(i);
            visit_froxel(view_object(view, objects[w.object]), w.object, vec3(w.tile, w.slice));
        }
    }
}
