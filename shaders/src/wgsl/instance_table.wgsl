#define_import_path meshlight::instance_table

// The scene's instances as the passes read them: one binding, or two when the table is
// larger than one storage binding may be (the GPU scene then fills the first binding to
// the limit and puts the rest in `instances_high`). A pass importing this module binds
// slot `instances` at binding 30 and, when the def `INSTANCES_HIGH` is set, slot
// `instances_high` at binding 31 (slots of those names; see `meshlight_gpu_scene::instance_table`),
// and reads every instance through `instance_at`, so no pass sees the split.

#import meshlight::instance::Instance

@group(0) @binding(30) var<storage, read> instances: array<Instance>;
#ifdef INSTANCES_HIGH
@group(0) @binding(31) var<storage, read> instances_high: array<Instance>;
#endif

// How many instances the bindings hold together.
fn instance_total() -> u32 {
#ifdef INSTANCES_HIGH
    return arrayLength(&instances) + arrayLength(&instances_high);
#else
    return arrayLength(&instances);
#endif
}

// Instance `i` of the whole table. The first binding holds instances 0 to its length
// (full whenever a second exists); the second holds the rest. Past the end, as any
// runtime-sized array read, the result is some instance of the table or zeros.
fn instance_at(i: u32) -> Instance {
#ifdef INSTANCES_HIGH
    let low = arrayLength(&instances);
    if i >= low {
        return instances_high[i - low];
    }
#endif
    return instances[i];
}
