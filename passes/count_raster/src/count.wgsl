// Counts, per froxel and object kind, the clusterable objects that touch it. Each
// (object, slice) instance of `z_slice` covers the tile rectangle `froxel_rect` gives it;
// every froxel of that rectangle is tested with `object_touches_froxel`.
//
// `raster`: one quad per instance on a viewport of one pixel per tile, colour writes off;
// the fragment shader tests and counts. `compute`: workgroups share their lanes out over
// the tiles of their share of the instances (at most 64) a round. Both call `count_froxel`, so they count the same pairs.

#import meshlight::view::View
#import meshlight::light::{ClusterableObject, ClusterGrid, cluster_index, CLUSTERABLE_TYPE_COUNT}
#import meshlight::froxel::{ViewObject, TileRect, view_object, froxel_aabb, froxel_rect, rect_is_empty, object_touches_froxel, froxel_quad_corner, walk_rounds, walk_instance, walk_layout, walk_tile, WALK_GROUP}

// One (object, slice) pair of `z_slice`'s list.
struct SliceInstance {
    object: u32,
    slice: u32,
}

// The objects `slice_instances` refers to.
@group(0) @binding(0) var<storage, read> objects: array<ClusterableObject>;
// z_slice's (object, slice) list.
@group(0) @binding(1) var<storage, read> slice_instances: array<SliceInstance>;
// z_slice's count words: [0] instances requested, [1] the list's capacity.
@group(0) @binding(2) var<storage, read> slice_counts: array<u32>;
// The grid z_slice sliced with.
@group(0) @binding(3) var<storage, read> cluster_grid: ClusterGrid;
// Per froxel and kind: `cluster_counts[froxel * CLUSTERABLE_TYPE_COUNT + kind]`; zeroed
// by z_slice's `prepare`.
@group(0) @binding(4) var<storage, read_write> cluster_counts: array<atomic<u32>>;
@group(0) @binding(5) var<uniform> view: View;


fn instances_written() -> u32 {
    return min(min(slice_counts[0], slice_counts[1]), arrayLength(&slice_instances));
}

fn count_froxel(o: ViewObject, froxel: vec3<u32>) {
    if object_touches_froxel(o, froxel_aabb(view, cluster_grid, froxel)) {
        let at = cluster_index(cluster_grid, froxel) * CLUSTERABLE_TYPE_COUNT + o.kind;
        if at < arrayLength(&cluster_counts) {
            atomicAdd(&cluster_counts[at], 1u);
        }
    }
}

struct Varyings {
    @builtin(position) position: vec4<f32>,
    @location(0) @interpolate(flat) instance: u32,
}

@vertex
fn count_vs(@builtin(vertex_index) vertex: u32, @builtin(instance_index) instance: u32) -> Varyings {
    let pair = slice_instances[instance];
    let o = view_object(view, objects[pair.object]);
    let rect = froxel_rect(view, cluster_grid, o, pair.slice);
    return Varyings(froxel_quad_corner(cluster_grid, rect, vertex), instance);
}

@fragment
fn count_fs(in: Varyings) {
    let pair = slice_instances[in.instance];
    let o = view_object(view, objects[pair.object]);
    count_froxel(o, vec3(vec2<u32>(in.position.xy), pair.slice));
}

@compute @workgroup_size(64)
fn count_cs(
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
            count_froxel(view_object(view, objects[w.object]), vec3(w.tile, w.slice));
        }
    }
}
