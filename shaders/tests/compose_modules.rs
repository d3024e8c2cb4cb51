//! Every shared module composes through naga_oil and validates under the capabilities
//! it needs.

use meshlight_shaders::{
    Capabilities, PassShader, ShaderError, ShaderLibrary, shared_modules, validate,
};

const EVERY_MODULE: PassShader = PassShader {
    name: "uses_every_module",
    source: include_str!("wgsl/uses_every_module.wgsl"),
    file_path: "shaders/tests/wgsl/uses_every_module.wgsl",
};

const VISBUFFER64: PassShader = PassShader {
    name: "uses_visbuffer64",
    source: include_str!("wgsl/uses_visbuffer64.wgsl"),
    file_path: "shaders/tests/wgsl/uses_visbuffer64.wgsl",
};

fn int64() -> Capabilities {
    Capabilities::SHADER_INT64 | Capabilities::SHADER_INT64_ATOMIC_MIN_MAX
}

fn compose(library: &mut ShaderLibrary, shader: &PassShader) -> naga::Module {
    library.compose(shader, &[]).unwrap_or_else(|error| panic!("{error}"))
}

#[test]
fn every_shared_module_is_added_under_full_capabilities() {
    let library = ShaderLibrary::new(int64()).unwrap_or_else(|error| panic!("{error}"));
    let expected: Vec<String> = shared_modules().iter().map(|m| m.name.to_owned()).collect();
    assert_eq!(library.shared_module_names(), expected);
}

#[test]
fn every_module_composes_and_validates_without_int64() {
    let mut library = ShaderLibrary::new(Capabilities::empty()).unwrap();
    let module = compose(&mut library, &EVERY_MODULE);
    validate(EVERY_MODULE.name, &module, Capabilities::empty()).unwrap_or_else(|e| panic!("{e}"));
    // Each module's functions survive composition (none was silently dropped).
    let names: Vec<&str> =
        module.functions.iter().filter_map(|(_, f)| f.name.as_deref()).collect();
    for needle in ["sphere_in_frustum", "octahedral_decode", "meshlet_in_lod_cut", "read_bits",
        "instance_transform_normal", "visbuffer_pack", "cluster_aabb", "cone_intersects_sphere"]
    {
        assert!(
            names.iter().any(|name| name.starts_with(needle)),
            "{needle} missing from the composed module: {names:?}"
        );
    }
}

#[test]
fn visbuffer64_composes_with_int64_atomics() {
    let mut library = ShaderLibrary::new(int64()).unwrap();
    let module = compose(&mut library, &VISBUFFER64);
    validate(VISBUFFER64.name, &module, int64()).unwrap_or_else(|e| panic!("{e}"));
}

#[test]
fn visbuffer64_module_needs_int64() {
    // Shows the capability requirement is real: without SHADER_INT64 the composed module
    // does not validate.
    let mut library = ShaderLibrary::new(int64()).unwrap();
    let module = compose(&mut library, &VISBUFFER64);
    assert!(validate(VISBUFFER64.name, &module, Capabilities::empty()).is_err());
}

#[test]
fn importing_visbuffer64_without_int64_names_the_missing_capability() {
    let mut library = ShaderLibrary::new(Capabilities::empty()).unwrap();
    assert!(!library.shared_module_names().iter().any(|n| n == "meshlight::visbuffer64"));
    match library.compose(&VISBUFFER64, &[]) {
        Err(ShaderError::MissingCapability { shader, module, missing }) => {
            assert_eq!(shader, "uses_visbuffer64");
            assert_eq!(module, "meshlight::visbuffer64");
            assert!(missing.contains("SHADER_INT64"), "{missing}");
        }
        other => panic!("expected MissingCapability, got {other:?}"),
    }
}
