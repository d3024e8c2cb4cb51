#define_import_path meshlight::dispatch

// A workgroup count past the per-dimension limit is dispatched as a 2-D grid: x as wide
// as allowed, y rows; a workgroup's linear index is y * x_size + x, and those at or past
// the count return. `cpu::dispatch` (Rust) mirrors both functions.

// `n` workgroups as indirect arguments [x, y, 1] under `max_per_dimension`: x = min(n, m),
// y = ceil(n / x) capped at m (0 when n = 0, so nothing runs).
fn fold_dispatch(n: u32, max_per_dimension: u32) -> vec3<u32> {
    let m = max(max_per_dimension, 1u);
    let x = min(n, m);
    var y = 0u;
    if x > 0u {
        y = min((n + x - 1u) / x, m);
    }
    return vec3(x, y, 1u);
}

// The linear index of workgroup `wg` in a grid `x_size` workgroups wide.
fn linear_workgroup(wg: vec3<u32>, x_size: u32) -> u32 {
    return wg.y * x_size + wg.x;
}
