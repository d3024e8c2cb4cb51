#define_import_path fill_clusters::list

// The candidate list of the stage, as both implementations write it (fill.wgsl a
// workgroup per instance, hierarchy.wgsl per accepted leaf): the same slots and words,
// so `cull_lod` reads either alike.

#import meshlight::meshlet::Cluster

// The cluster list: written below the capacity only.
@group(0) @binding(1) var<storage, read_write> clusters: array<Cluster>;
// [0] clusters written = min(requested, capacity), [1] clusters requested.
@group(0) @binding(2) var<storage, read_write> cluster_count: array<atomic<u32>>;

// The slots the list may fill: the pass's `capacity` param, clamped to the bound list's
// length.
fn cluster_capacity(capacity: u32) -> u32 {
    return min(capacity, arrayLength(&clusters));
}
