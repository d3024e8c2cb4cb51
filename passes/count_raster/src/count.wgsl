// count_raster's entry points: the walk of `walk.wgsl` (shared with populate), counting
// at each froxel an object touches.

#import count_raster::walk::{QuadVertex, Varyings, WalkLane, quad_vertex, quad_fragment, compute_walk}

@vertex
fn count_vs(v: QuadVertex) -> Varyings {
    return quad_vertex(v);
}

@fragment
fn count_fs(in: Varyings) {
    quad_fragment(in);
}

@compute @workgroup_size(64)
fn count_cs(lane: WalkLane) {
    compute_walk(lane);
}
