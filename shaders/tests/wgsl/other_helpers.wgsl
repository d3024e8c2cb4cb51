#define_import_path test_crate::helpers
fn twice(x: u32) -> u32 { return x + x; }
