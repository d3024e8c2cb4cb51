// Not valid WGSL: the statement on line 6 misses its semicolon's expression.

@compute @workgroup_size(1)
fn main() {
    var x = 1u;
    x = ;
}
