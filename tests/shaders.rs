//! Every pass entry point, with every shader-def variant it uses, composes through
//! naga_oil against the shared library and validates.

use meshlight::shaders::{Capabilities, PassShader, ShaderDefs, ShaderLibrary, validate};

fn all_caps() -> Capabilities {
    Capabilities::SHADER_INT64 | Capabilities::SHADER_INT64_ATOMIC_MIN_MAX | Capabilities::SUBGROUP
}

fn check(shader: &PassShader, defs: &dyn ShaderDefs) {
    let mut lib = ShaderLibrary::new(all_caps()).unwrap();
    let module = lib
        .compose(shader, &defs.shader_defs())
        .unwrap_or_else(|e| panic!("{}: {e}", shader.name));
    validate(shader.name, &module, all_caps()).unwrap_or_else(|e| panic!("{}: {e}", shader.name));
    assert!(
        !module.entry_points.is_empty(),
        "{} has no entry points",
        shader.name
    );
}

#[test]
fn virtual_geometry_shaders_compose_and_validate() {
    for shader in [
        &meshlight::fill_clusters::SHADER,
        &meshlight::fill_clusters::hierarchy::SHADER,
        &meshlight::cull_lod::SHADER,
        &meshlight::remap_dispatch::SHADER,
        &meshlight::hw_raster::SHADER,
        &meshlight::resolve::DEPTH_SHADER,
        &meshlight::resolve::SHADE_SHADER,
        &meshlight::z_slice::SHADER,
    ] {
        check(shader, &());
    }
    for (exact_division, slot_base, big_triangles, two_sided, alpha_mask, depth_only) in [
        (false, false, false, false, false, false),
        (true, false, true, true, true, false),
        (false, true, true, false, true, false),
        (false, false, false, true, false, false),
        (false, false, true, true, true, true),
    ] {
        check(
            &meshlight::sw_raster::SHADER,
            &meshlight::sw_raster::RasterDefs {
                exact_division,
                texture: false,
                slot_base,
                big_triangles,
                two_sided,
                alpha_mask,
                depth_only,
            },
        );
    }
}

#[test]
fn scan_fan_shader_variants_compose_and_validate() {
    use meshlight::scan_fan::ScanDefs;
    for items_per_thread in [1, 2, 4, 8, 16] {
        for subgroups in [false, true] {
            for gpu_count in [false, true] {
                for direct in [false, true] {
                    check(
                        &meshlight::scan_fan::SHADER,
                        &ScanDefs {
                            items_per_thread,
                            subgroups,
                            gpu_count,
                            direct,
                        },
                    );
                }
            }
        }
    }
}

#[test]
fn the_software_raster_needs_int64_atomics() {
    // Without the capability the composer must refuse it, not hand wgpu an invalid module.
    let mut lib = ShaderLibrary::new(Capabilities::empty()).unwrap();
    let composed = lib.compose(&meshlight::sw_raster::SHADER, &[]);
    let validated = composed.and_then(|m| validate("sw_raster::raster", &m, Capabilities::empty()));
    assert!(validated.is_err());
}
