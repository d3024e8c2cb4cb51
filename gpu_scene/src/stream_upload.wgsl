// Streaming's changes written into the scene's buffers in one dispatch
// (`stream_upload.rs`). `source` holds the part count, four words per part (the
// destination buffer, the first word written there, the first word of the part's
// data in `source`, its length in words), then the parts' words. One workgroup per
// part: its threads copy the part's words, 64 apart. The CPU reference is the scene
// itself: afterwards each buffer equals `SceneData`'s copy of it.

@group(0) @binding(0) var<storage, read> source: array<u32>;
@group(0) @binding(1) var<storage, read_write> payload: array<u32>;
@group(0) @binding(2) var<storage, read_write> meshlets: array<u32>;
@group(0) @binding(3) var<storage, read_write> groups: array<u32>;
@group(0) @binding(4) var<storage, read_write> hierarchy_nodes: array<u32>;
@group(0) @binding(5) var<storage, read_write> stream_errors: array<u32>;

const THREADS: u32 = 64u;

@compute @workgroup_size(64)
fn scatter(
    @builtin(workgroup_id) group_id: vec3<u32>,
    @builtin(num_workgroups) groups_launched: vec3<u32>,
    @builtin(local_invocation_index) lane: u32,
) {
    let part = group_id.x + group_id.y * groups_launched.x;
    if part >= source[0] {
        return;
    }
    let at = 1u + 4u * part;
    let buffer = source[at];
    let first = source[at + 1u];
    let start = source[at + 2u];
    let words = source[at + 3u];
    for (var i = lane; i < words; i += THREADS) {
        let word = source[start + i];
        switch buffer {
            case 0u: { payload[first + i] = word; }
            case 1u: { meshlets[first + i] = word; }
            case 2u: { groups[first + i] = word; }
            case 3u: { hierarchy_nodes[first + i] = word; }
            default: { stream_errors[first + i] = word; }
        }
    }
}
