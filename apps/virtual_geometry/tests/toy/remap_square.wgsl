// A toy `remap_dispatch`: the workgroup count as a square grid, s × s with
// s = ceil(sqrt(n)), so x · y ≥ n; the rasteriser's workgroups past the count return.

struct Params {
    count_word: u32,
    max_per_dimension: u32,
    _pad: vec2<u32>,
}

@group(0) @binding(0) var<storage, read> count: array<u32>;
@group(0) @binding(1) var<storage, read_write> args: array<u32, 3>;
@group(0) @binding(2) var<uniform> params: Params;

@compute @workgroup_size(1)
fn square() {
    let n = count[params.count_word];
    var side = u32(ceil(sqrt(f32(n))));
    // f32 rounding: grow until the square holds n (n = 0 gives 0, nothing runs).
    while side * side < n {
        side += 1u;
    }
    args[0] = side;
    args[1] = side;
    args[2] = 1u;
}
