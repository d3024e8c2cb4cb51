// populate's entry points: the walk of count_raster's `walk.wgsl`, claiming at each froxel
// an object touches a place in its list (POPULATE), and `settle`, which afterwards sets
// each count to the entries really written (never past the capacity, never an unwritten
// place) and writes the needed and available entries for the growth readback.

#define POPULATE
#import count_raster::walk::{QuadVertex, Varyings, WalkLane, quad_vertex, quad_fragment, compute_walk}
#import count_raster::walk::{cluster_counts, cluster_offsets, list_total, list_counts, list_capacity, list_count, counted_in}

const WORKGROUP_SIZE: u32 = 64u;

@vertex
fn populate_vs(v: QuadVertex) -> Varyings {
    return quad_vertex(v);
}

@fragment
fn populate_fs(in: Varyings) {
    quad_fragment(in);
}

@compute @workgroup_size(64)
fn populate_cs(lane: WalkLane) {
    compute_walk(lane);
}

// After the walk: each count becomes the entries written (the places claimed, at most
// the places counted and the room below the capacity), and the needed and available
// entries go out for the readback.
@compute @workgroup_size(64)
fn settle(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) groups: vec3<u32>) {
    let capacity = list_capacity();
    for (var list = id.x; list < list_count(); list += groups.x * WORKGROUP_SIZE) {
        let counted = counted_in(list);
        // Wraps to above `counted` when more were claimed than counted.
        let claimed = counted - atomicLoad(&cluster_counts[list]);
        let offset = min(cluster_offsets[list], capacity);
        atomicStore(&cluster_counts[list], min(min(claimed, counted), capacity - offset));
    }
    if id.x == 0u {
        list_counts[0] = list_total[0];
        list_counts[1] = capacity;
    }
}
