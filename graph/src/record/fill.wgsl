// The graph's buffer fill: zeroes the bound words, so a pass inside a batch clears a
// buffer without leaving the batch's compute pass (a `clear_buffer` needs the encoder).
// One thread per word; a 2-D grid of 256-thread workgroups.

// Words to zero: the whole binding.
@group(0) @binding(0) var<storage, read_write> words: array<u32>;

@compute @workgroup_size(256)
fn fill(
    @builtin(workgroup_id) group: vec3<u32>,
    @builtin(num_workgroups) groups: vec3<u32>,
    @builtin(local_invocation_index) lane: u32,
) {
    let i = (group.y * groups.x + group.x) * 256u + lane;
    if i < arrayLength(&words) {
        words[i] = 0u;
    }
}
