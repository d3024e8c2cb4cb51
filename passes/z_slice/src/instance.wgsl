#define_import_path z_slice::instance

// The list z_slice writes and the walking stages (count_raster, populate) read, one
// layout for all of them (`cpu::SliceInstance` on the Rust side).

// One (object, slice) pair of the list.
struct SliceInstance {
    // Index into `objects`.
    object: u32,
    // Depth slice, 0 ..< dims.z.
    slice: u32,
}
