// Writes each froxel's object lists: the same instances, rectangles and froxel test as
// `count_raster` (through `meshlight::froxel`), but where the count stage added one, this
// stage claims a place in the (froxel, kind) list and writes the object's index there.
// A claim takes one from the list's count (`atomicSub`), so the count itself is the
// cursor, counting down: the place is how many were counted minus how many were left,
// and the number counted is known without it, from the prefix sum (the next list's
// offset, or the total, minus this one's). No cursor buffer has to be zeroed first.
// Places at or past the capacity are claimed, never written.
//
// A list only ever receives as many entries as its count: a place past it (should the
// GPU decide a pair here otherwise than in the count stage) is claimed and not written,
// so no list spills into the next. `settle` then sets each count to the entries really
// written: never past the capacity, never an unwritten place; it also writes the needed
// and available entries for the growth readback.
//
// `raster`: one quad per instance on a viewport of one pixel per tile, colour writes
// off. `compute`: workgroups share their lanes out over the tiles of their
// share of the instances (at most 64) a round.

#import meshlight::view::View
#import meshlight::light::{ClusterableObject, ClusterGrid, cluster_index, CLUSTERABLE_TYPE_COUNT}
#import meshlight::froxel::{ViewObject, TileRect, view_object, froxel_aabb, froxel_rect, rect_is_empty, object_touches_froxel, froxel_quad_corner, walk_rounds, walk_instance, walk_layout, walk_tile, WALK_GROUP}

struct SliceInstance {
    object: u32,
    slice: u32,
}

struct Params {
    // Entries the list may hold; clamped to the bound list's length.
    capacity: u32,
    _pad0: u32,
    _pad1: u32,
    _pad2: u32,
}

// The objects `slice_instances` refers to.
@group(0) @binding(0) var<storage, read> objects: array<ClusterableObject>;
// z_slice's (object, slice) list.
@group(0) @binding(1) var<storage, read> slice_instances: array<SliceInstance>;
// z_slice's count words: [0] instances requested, [1] the list's capacity.
@group(0) @binding(2) var<storage, read> slice_counts: array<u32>;
@group(0) @binding(3) var<storage, read> cluster_grid: ClusterGrid;
// Exclusive prefix sum of count_raster's counts: where each (froxel, kind) list starts.
@group(0) @binding(4) var<storage, read> cluster_offsets: array<u32>;
// In: count_raster's counts; during the walk: places left to claim (wrapping below
// zero when the walk finds more pairs than were counted). Out (after `settle`): the
// entries each list holds.
@group(0) @binding(11) var<storage, read_write> cluster_counts: array<atomic<u32>>;
// The lists, back to back: object indices.
@group(0) @binding(6) var<storage, read_write> cluster_objects: array<u32>;
// [0]: entries every list together needs (the prefix sum's total).
@group(0) @binding(7) var<storage, read> list_total: array<u32>;
// [0] entries needed, [1] the capacity: overflow when [0] > [1].
@group(0) @binding(8) var<storage, read_write> list_counts: array<u32>;
@group(0) @binding(9) var<uniform> view: View;
@group(0) @binding(10) var<uniform> params: Params;

const WORKGROUP_SIZE: u32 = 64u;

fn capacity() -> u32 {
    return min(params.capacity, arrayLength(&cluster_objects));
}

fn instances_written() -> u32 {
    return min(min(slice_counts[0], slice_counts[1]), arrayLength(&slice_instances));
}

fn add_to_froxel(o: ViewObject, object: u32, froxel: vec3<u32>) {
    if object_touches_froxel(o, froxel_aabb(view, cluster_grid, froxel)) {
        let list = cluster_index(cluster_grid, froxel) * CLUSTERABLE_TYPE_COUNT + o.kind;
        if list < lists() {
            // Places left before this claim: `counted` down to 1 for the counted ones,
            // then 0 and (wrapped) above `counted` for any past them.
            let left = atomicSub(&cluster_counts[list], 1u);
            let counted = counted_in(list);
            let place = counted - left;
            let at = cluster_offsets[list] + place;
            if left > 0u && left <= counted && at < capacity() {
                cluster_objects[at] = object;
            }
        }
    }
}

fn lists() -> u32 {
    return min(arrayLength(&cluster_offsets), arrayLength(&cluster_counts));
}

// What count_raster counted for `list`, from the exclusive prefix sum: the next list's
// offset, or the total after the last list, minus this list's (u32, wrapping as the sums do).
fn counted_in(list: u32) -> u32 {
    var end = list_total[0];
    if list + 1u < lists() {
        end = cluster_offsets[list + 1u];
    }
    return end - cluster_offsets[list];
}

// After the walk: each count becomes the entries written (the places claimed, at most
// the places counted and the room below the capacity), and the needed and available
// entries go out for the readback.
@compute @workgroup_size(64)
fn settle(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    for (var list = id.x; list < lists(); list += groups.x * WORKGROUP_SIZE) {
        let counted = counted_in(list);
        // Wraps to above `counted` when more were claimed than counted.
        let claimed = counted - atomicLoad(&cluster_counts[list]);
        let offset = min(cluster_offsets[list], capacity());
        atomicStore(&cluster_counts[list], min(min(claimed, counted), capacity() - offset));
    }
    if id.x == 0u {
        list_counts[0] = list_total[0];
        list_counts[1] = capacity();
    }
}

struct Varyings {
    @builtin(position) position: vec4<f32>,
    @location(0) @interpolate(flat) instance: u32,
}

@vertex
fn populate_vs(@builtin(vertex_index) vertex: u32, @builtin(instance_index) instance: u32) -> Varyings {
    let pair = slice_instances[instance];
    let o = view_object(view, objects[pair.object]);
    let rect = froxel_rect(view, cluster_grid, o, pair.slice);
    return Varyings(froxel_quad_corner(cluster_grid, rect, vertex), instance);
}

@fragment
fn populate_fs(in: Varyings) {
    let pair = slice_instances[in.instance];
    let o = view_object(view, objects[pair.object]);
    add_to_froxel(o, pair.object, vec3(vec2<u32>(in.position.xy), pair.slice));
}

@compute @workgroup_size(64)
fn populate_cs(
    @builtin(workgroup_id) wg: vec3<u32>,
    @builtin(num_workgroups) groups: vec3<u32>,
    @builtin(local_invocation_index) t: u32,
) {
    let written = instances_written();
    // A direct dispatch of a fixed size: each workgroup walks its share of the instances
    // (at most 64) a round.
    let rounds = walk_rounds(groups, written);
    for (var round = 0u; round < rounds; round += 1u) {
        let instance = walk_instance(wg, groups, round, t, written);
        var pair = SliceInstance(0u, 0u);
        var rect = TileRect(vec2(1u, 0u), vec2(0u));
        if instance < written {
            pair = slice_instances[instance];
            rect = froxel_rect(view, cluster_grid, view_object(view, objects[pair.object]), pair.slice);
        }
        let total = walk_layout(t, pair.object, pair.slice, rect);
        for (var i = t; i < total; i += WALK_GROUP) {
            let w = walk_tile(i);
            add_to_froxel(view_object(view, objects[w.object]), w.object, vec3(w.tile, w.slice));
        }
    }
}
