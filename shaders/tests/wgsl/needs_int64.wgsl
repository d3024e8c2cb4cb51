// Parses, but uses u64, which only validates with SHADER_INT64.

@group(0) @binding(0) var<storage, read_write> out: array<u64>;

@compute @workgroup_size(1)
fn main() {
    out[0] = 1lu;
}
