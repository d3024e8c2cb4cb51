// One thread turns a workgroup count written by an earlier pass into the arguments of a
// 2-D indirect dispatch whose x and y both stay under the per-dimension limit. The count
// itself stays where it was: the consumer's workgroups compute their linear index
// (y * x_size + x) and those at or past the count return at once.

#import meshlight::dispatch::fold_dispatch
// The uniform block, declared once for Rust and WGSL by `GpuParams` in lib.rs.
#import remap_dispatch::params::Params

// The workgroup count, at word `params.count_word`.
@group(0) @binding(0) var<storage, read> count: array<u32>;
// The dispatch arguments: x, y, z.
@group(0) @binding(1) var<storage, read_write> args: array<u32, 3>;
@group(0) @binding(2) var<uniform> params: Params;

@compute @workgroup_size(1)
fn remap() {
    let d = fold_dispatch(count[params.count_word], params.max_per_dimension);
    args[0] = d.x;
    args[1] = d.y;
    args[2] = d.z;
}
