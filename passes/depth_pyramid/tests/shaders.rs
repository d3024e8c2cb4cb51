//! pyramid.wgsl composes and validates in every variant a pass can ask for (no GPU),
//! the R64Uint texture form included, which lavapipe cannot run.

use meshlight_pass_depth_pyramid::{PyramidDefs, SHADER};
use meshlight_shaders::{Capabilities, ShaderDefs, ShaderLibrary, validate};

fn entries(defs: PyramidDefs, caps: Capabilities) -> Vec<String> {
    let mut lib = ShaderLibrary::new(caps).unwrap_or_else(|e| panic!("{e}"));
    let module = lib
        .compose(&SHADER, &defs.shader_defs())
        .unwrap_or_else(|e| panic!("{defs:?}: {e}"));
    validate(SHADER.name, &module, caps).unwrap_or_else(|e| panic!("{defs:?}: {e}"));
    module.entry_points.iter().map(|e| e.name.clone()).collect()
}

#[test]
fn the_buffer_form_validates_without_64_bit_integers() {
    for single_pass in [false, true] {
        let defs = PyramidDefs {
            single_pass,
            texture: false,
        };
        let mut want = vec!["tiles", "top"];
        if single_pass {
            want.push("single_pass");
        }
        assert_eq!(entries(defs, Capabilities::empty()), want);
    }
}

#[test]
fn the_texture_form_validates_with_64_bit_texture_reads() {
    let caps = Capabilities::SHADER_INT64 | Capabilities::TEXTURE_INT64_ATOMIC;
    for single_pass in [false, true] {
        for texture in [false, true] {
            let defs = PyramidDefs {
                single_pass,
                texture,
            };
            let mut lib = ShaderLibrary::new(caps).unwrap();
            let module = lib
                .compose(&SHADER, &defs.shader_defs())
                .unwrap_or_else(|e| panic!("{defs:?}: {e}"));
            validate(SHADER.name, &module, caps).unwrap_or_else(|e| panic!("{defs:?}: {e}"));
            // `VIS_TEXTURE` switches the visibility binding to an r64uint storage texture.
            let visibility = module
                .global_variables
                .iter()
                .find(|(_, g)| g.name.as_deref() == Some("visibility"))
                .map(|(_, g)| &module.types[g.ty].inner)
                .expect("a `visibility` global");
            let is_r64_texture = matches!(
                visibility,
                naga::TypeInner::Image {
                    class: naga::ImageClass::Storage {
                        format: naga::StorageFormat::R64Uint,
                        ..
                    },
                    ..
                }
            );
            assert_eq!(is_r64_texture, texture, "{defs:?}: {visibility:?}");
        }
    }
}
