#define_import_path fill_clusters::list

// The candidate list of the stage, as both implementations write it (fill.wgsl a
// workgroup per instance, hierarchy.wgsl per accepted leaf): the same slots and words,
// so `cull_lod` reads either alike.
//
// The buffers may hold several lists (`lists` parts of equal length, one per view of a
// walk over several views, or one per pass of a view set): list k's clusters start at
// k × `list_length(lists)`, and its two words are cluster_count[2k] and [2k + 1]. One
// list is the case lists = 1.

#import meshlight::meshlet::Cluster

// The cluster lists: written below the capacity only.
@group(0) @binding(1) var<storage, read_write> clusters: array<Cluster>;
// Per list: [2k] clusters written = min(requested, capacity), [2k + 1] clusters requested.
@group(0) @binding(2) var<storage, read_write> cluster_count: array<atomic<u32>>;

// The clusters each of `lists` lists holds: an equal part of the bound buffer.
fn list_length(lists: u32) -> u32 {
    return arrayLength(&clusters) / max(lists, 1u);
}

// The slots a list may fill: the pass's `capacity` param, clamped to the list's length.
fn cluster_capacity(capacity: u32, lists: u32) -> u32 {
    return min(capacity, list_length(lists));
}
