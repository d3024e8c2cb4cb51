//! Every shared module composes through naga_oil and validates under the capabilities
//! it needs.

use meshlight_shaders::{
    Capabilities, PassShader, ShaderDef, ShaderError, ShaderLibrary, pass_shader, shared_modules,
    validate,
};

const EVERY_MODULE: PassShader = pass_shader!("uses_every_module", "wgsl/uses_every_module.wgsl");

const VISBUFFER64: PassShader = pass_shader!("uses_visbuffer64", "wgsl/uses_visbuffer64.wgsl");

fn int64() -> Capabilities {
    Capabilities::SHADER_INT64 | Capabilities::SHADER_INT64_ATOMIC_MIN_MAX
}

fn compose(library: &mut ShaderLibrary, shader: &PassShader) -> naga::Module {
    library
        .compose(shader, &[])
        .unwrap_or_else(|error| panic!("{error}"))
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
    let names: Vec<&str> = module
        .functions
        .iter()
        .filter_map(|(_, f)| f.name.as_deref())
        .collect();
    for needle in [
        "sphere_in_frustum",
        "octahedral_decode",
        "lod_cut",
        "error_perceptible",
        "error_to_pixels",
        "meshlet_triangle",
        "read_bits",
        "instance_transform_normal",
        "visbuffer_pack",
        "froxel_aabb",
        "froxel_rect",
        "box_touches_aabb",
        "cone_touches_sphere",
    ] {
        assert!(
            names.iter().any(|name| name.starts_with(needle)),
            "{needle} missing from the composed module: {names:?}"
        );
    }
}

/// The instance table is one binding (30), or two (30 and 31) under `INSTANCES_HIGH`.
#[test]
fn the_instance_table_adds_its_second_binding_only_when_split() {
    let bindings = |defs: &[(&'static str, ShaderDef)]| {
        let mut library = ShaderLibrary::new(Capabilities::empty()).unwrap();
        let module = library
            .compose(&EVERY_MODULE, defs)
            .unwrap_or_else(|e| panic!("{e}"));
        validate(EVERY_MODULE.name, &module, Capabilities::empty())
            .unwrap_or_else(|e| panic!("{e}"));
        let mut bound: Vec<u32> = module
            .global_variables
            .iter()
            .filter_map(|(_, g)| g.binding.as_ref().map(|b| b.binding))
            .filter(|b| *b >= 30)
            .collect();
        bound.sort();
        bound
    };
    assert_eq!(bindings(&[]), [30]);
    assert_eq!(
        bindings(&[("INSTANCES_HIGH", ShaderDef::Bool(true))]),
        [30, 31]
    );
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
    assert!(
        !library
            .shared_module_names()
            .iter()
            .any(|n| n == "meshlight::visbuffer64")
    );
    match library.compose(&VISBUFFER64, &[]) {
        Err(ShaderError::MissingCapability {
            shader,
            module,
            missing,
        }) => {
            assert_eq!(shader, "uses_visbuffer64");
            assert_eq!(module, "meshlight::visbuffer64");
            assert!(missing.contains("SHADER_INT64"), "{missing}");
        }
        other => panic!("expected MissingCapability, got {other:?}"),
    }
}

/// One expression per shared module; using any item makes naga_oil build and validate
/// the whole module, so a broken function anywhere in it fails here.
const ONE_USE_PER_MODULE: &[(&str, &str)] = &[
    ("meshlight::math", "math::saturate(0.5)"),
    ("meshlight::view", "view::ndc_to_uv(vec2(0.0))"),
    (
        "meshlight::octahedral",
        "octahedral::unpack_octahedral_normal(0u)",
    ),
    (
        "meshlight::meshlet",
        "meshlet::meshlet_level(meshlet::Meshlet())",
    ),
    (
        "meshlight::instance",
        "instance::instance_max_scale(instance::Instance())",
    ),
    (
        "meshlight::dispatch",
        "dispatch::linear_workgroup(dispatch::fold_dispatch(5u, 2u), 2u)",
    ),
    (
        "meshlight::instance_table",
        "instance_table::instance_at(instance_table::instance_total())",
    ),
    (
        "meshlight::scene_buffers",
        "arrayLength(&scene_buffers::payload)",
    ),
    (
        "meshlight::cluster_triangle",
        "cluster_triangle::cluster_triangle(meshlight::meshlet::Cluster(), 0u).corners.x",
    ),
    (
        "meshlight::texture",
        "texture::sample_texture(vec2(0u, 0x80000002u), vec2(0.5), vec2(0.0), vec2(0.0)).a",
    ),
    (
        "meshlight::surface",
        "surface::cut_out(meshlight::meshlet::Cluster(), 0u, vec2(0.5), vec2(8.0), mat4x4<f32>())",
    ),
    (
        "meshlight::occlusion",
        "occlusion::occlusion_level(vec4(0u, 0u, 5u, 9u))",
    ),
    (
        "meshlight::visbuffer",
        "visbuffer::visbuffer_pack(0.5, 1u, 2u)",
    ),
    (
        "meshlight::visbuffer64",
        "visbuffer64::visbuffer64_pack(0.5, 1u, 2u)",
    ),
    (
        "meshlight::light",
        "light::cluster_index(light::ClusterGrid(), vec3(0u))",
    ),
    (
        "meshlight::froxel",
        "froxel::froxel_aabb(meshlight::view::View(), meshlight::light::ClusterGrid(), vec3(0u))",
    ),
];

#[test]
fn each_module_composes_on_its_own() {
    // Importing one module alone also catches a module that only worked because an
    // earlier import brought in what it uses.
    let mut library = ShaderLibrary::new(int64()).unwrap();
    for module in shared_modules() {
        let (_, expression) = ONE_USE_PER_MODULE
            .iter()
            .find(|(name, _)| *name == module.name)
            .unwrap_or_else(|| panic!("add a use of {} to ONE_USE_PER_MODULE", module.name));
        let source = format!(
            "#import {}\n@compute @workgroup_size(1)\nfn main() {{\n    _ = {expression};\n}}\n",
            module.name
        );
        let shader = PassShader {
            name: module.name,
            source: Box::leak(source.into_boxed_str()),
            file_path: "generated",
            modules: &[],
        };
        let composed = compose(&mut library, &shader);
        validate(module.name, &composed, module.capabilities).unwrap_or_else(|e| panic!("{e}"));
    }
}

#[test]
fn composing_is_deterministic() {
    // naga_oil keeps hash maps inside; two libraries (with different hash seeds) must
    // still produce the same module, or the pipeline cache would miss.
    let first = compose(
        &mut ShaderLibrary::new(Capabilities::empty()).unwrap(),
        &EVERY_MODULE,
    );
    let mut library = ShaderLibrary::new(Capabilities::empty()).unwrap();
    let second = compose(&mut library, &EVERY_MODULE);
    let third = compose(&mut library, &EVERY_MODULE);
    assert_eq!(format!("{first:?}"), format!("{second:?}"));
    assert_eq!(format!("{second:?}"), format!("{third:?}"));
}

/// A crate's own module, imported by its shader and added to the library on first use.
#[test]
fn a_crate_local_module_is_imported_by_its_path() {
    const SHADER: PassShader = pass_shader!(
        "test::uses_local",
        "wgsl/uses_local.wgsl",
        modules: [("test_crate::helpers", "wgsl/local_helpers.wgsl")]
    );
    let mut library = ShaderLibrary::new(Capabilities::empty()).unwrap();
    // Twice: the module is added once and reused.
    for _ in 0..2 {
        let module = library
            .compose(&SHADER, &[])
            .unwrap_or_else(|e| panic!("{e}"));
        validate(SHADER.name, &module, Capabilities::empty()).unwrap_or_else(|e| panic!("{e}"));
        assert!(
            module
                .functions
                .iter()
                .any(|(_, f)| f.name.as_deref().is_some_and(|n| n.starts_with("twice")))
        );
    }
    // Another source under the same import path is refused, naming both files.
    const OTHER: PassShader = pass_shader!(
        "test::other_local",
        "wgsl/other_local.wgsl",
        modules: [("test_crate::helpers", "wgsl/other_helpers.wgsl")]
    );
    let err = library.compose(&OTHER, &[]).unwrap_err().to_string();
    assert!(
        err.contains("test_crate::helpers")
            && err.contains("wgsl/local_helpers.wgsl")
            && err.contains("wgsl/other_helpers.wgsl"),
        "{err}"
    );
}

/// `meshlight::occlusion::instance_sphere_rect` projects as the importing pass's test
/// needs: naga_oil composes the module with the shader's defs, so without `SECOND_PASS`
/// it reads last frame's view-projection and the instance's previous transform, and with
/// it this frame's.
#[test]
fn instance_sphere_rect_follows_the_importing_shaders_second_pass() {
    const SHADER: PassShader = PassShader {
        name: "uses_instance_sphere_rect",
        source: "#import meshlight::occlusion::instance_sphere_rect
#import meshlight::instance::Instance
#import meshlight::view::View

@group(0) @binding(0) var<uniform> view: View;
@group(0) @binding(1) var<storage, read> instances: array<Instance>;
@group(0) @binding(2) var<storage, read_write> out: array<u32>;

@compute @workgroup_size(1)
fn main() {
    let rect = instance_sphere_rect(instances[0], view, vec4(0.0, 0.0, -2.0, 0.5));
    out[0] = select(0u, 1u, rect.testable);
}
",
        file_path: "generated",
        modules: &[],
    };
    // One library for both variants: naga_oil's cache of the module's IR must tell them
    // apart.
    let mut library = ShaderLibrary::new(Capabilities::empty()).unwrap();
    // The members of the function's `instance` (argument 0) and `view` (argument 1) it
    // reads.
    let mut read = |defs: &[(&'static str, ShaderDef)]| {
        let module = library
            .compose(&SHADER, defs)
            .unwrap_or_else(|e| panic!("{e}"));
        validate(SHADER.name, &module, Capabilities::empty()).unwrap_or_else(|e| panic!("{e}"));
        let (_, function) = module
            .functions
            .iter()
            .find(|(_, f)| {
                f.name
                    .as_deref()
                    .is_some_and(|n| n.starts_with("instance_sphere_rect"))
            })
            .expect("instance_sphere_rect in the composed module");
        let members = |argument: u32| -> Vec<String> {
            let ty = function.arguments[argument as usize].ty;
            let naga::TypeInner::Struct { members, .. } = &module.types[ty].inner else {
                panic!("argument {argument} is not a struct");
            };
            let mut names: Vec<String> = function
                .expressions
                .iter()
                .filter_map(|(_, e)| match e {
                    naga::Expression::AccessIndex { base, index }
                        if matches!(
                            function.expressions[*base],
                            naga::Expression::FunctionArgument(a) if a == argument
                        ) =>
                    {
                        members[*index as usize].name.clone()
                    }
                    _ => None,
                })
                .collect();
            names.sort();
            names.dedup();
            names
        };
        (members(0), members(1))
    };
    let (instance, view) = read(&[]);
    assert_eq!(instance, ["previous_world_from_local"]);
    assert!(
        view.contains(&"previous_view_projection".to_owned())
            && !view.contains(&"view_projection".to_owned()),
        "first pass reads {view:?}"
    );
    let (instance, view) = read(&[("SECOND_PASS", ShaderDef::Bool(true))]);
    assert!(instance.is_empty(), "second pass reads {instance:?}");
    assert!(
        view.contains(&"view_projection".to_owned())
            && !view.contains(&"previous_view_projection".to_owned()),
        "second pass reads {view:?}"
    );
}
