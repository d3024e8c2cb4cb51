#import meshlight::no_such_module::helper

@compute @workgroup_size(1)
fn main() {
    helper();
}
