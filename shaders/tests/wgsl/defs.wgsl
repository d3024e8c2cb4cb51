// Writes a value that depends on shader defs, so composing with different defs must give
// different modules.

@group(0) @binding(0) var<storage, read_write> out: array<u32>;

@compute @workgroup_size(1)
fn main() {
#ifdef DOUBLE
    out[0] = 2000u;
#else
    out[0] = 1000u;
#endif
    out[1] = #{SCALE};
#if LEVEL == 3
    out[2] = 333u;
#else
    out[2] = 444u;
#endif
}
