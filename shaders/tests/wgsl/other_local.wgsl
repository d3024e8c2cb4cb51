#import test_crate::helpers::twice
@compute @workgroup_size(1)
fn main() { _ = twice(1u); }
