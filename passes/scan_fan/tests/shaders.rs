//! Both shaders of the crate compose and validate with every def variant a pass can ask
//! for (no GPU needed).

use meshlight_pass_scan_fan::{SHADER, ScanDefs, VECTOR_SHADER, VectorDefs};
use meshlight_shaders::{Capabilities, PassShader, ShaderDefs, ShaderLibrary, validate};

fn check(shader: &PassShader, defs: &impl ShaderDefs, caps: Capabilities) {
    let mut lib = ShaderLibrary::new(caps).unwrap();
    let module = lib
        .compose(shader, &defs.shader_defs())
        .unwrap_or_else(|e| panic!("{}: {e}", shader.name));
    validate(shader.name, &module, caps).unwrap_or_else(|e| panic!("{}: {e}", shader.name));
    assert!(!module.entry_points.is_empty(), "{}", shader.name);
}

#[test]
fn vector_shader_variants_compose_and_validate() {
    for items_per_thread in [1, 2, 4, 8, 16, 32] {
        for subgroups in [false, true] {
            for gpu_count in [false, true] {
                let caps = if subgroups {
                    Capabilities::SUBGROUP
                } else {
                    Capabilities::empty()
                };
                let defs = VectorDefs {
                    items_per_thread,
                    subgroups,
                    gpu_count,
                };
                check(&VECTOR_SHADER, &defs, caps);
            }
        }
    }
}

#[test]
fn staged_and_direct_shader_variants_compose_and_validate() {
    for items_per_thread in [1, 2, 4, 8, 16] {
        for subgroups in [false, true] {
            for direct in [false, true] {
                let defs = ScanDefs {
                    items_per_thread,
                    subgroups,
                    gpu_count: true,
                    direct,
                };
                check(&SHADER, &defs, Capabilities::SUBGROUP);
            }
        }
    }
}
