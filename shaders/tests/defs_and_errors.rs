//! Shader defs change the composed module; every failure is a typed error that points at
//! the shader, the file and the line.

use meshlight_shaders::{
    Capabilities, PassShader, ShaderDef, ShaderDefs, ShaderError, ShaderLibrary, pass_shader,
};

const DEFS: PassShader = pass_shader!("defs", "wgsl/defs.wgsl");

/// The u32 literals the module's entry point stores, in expression order.
fn stored_literals(module: &naga::Module) -> Vec<u32> {
    let entry = &module.entry_points[0].function;
    entry
        .expressions
        .iter()
        .filter_map(|(_, expression)| match expression {
            naga::Expression::Literal(naga::Literal::U32(value)) if *value >= 100 => Some(*value),
            _ => None,
        })
        .collect()
}

struct TestDefs {
    double: bool,
    scale: u32,
    level: i32,
}

impl ShaderDefs for TestDefs {
    fn shader_defs(&self) -> Vec<(&'static str, ShaderDef)> {
        vec![
            ("DOUBLE", ShaderDef::Bool(self.double)),
            ("SCALE", ShaderDef::UInt(self.scale)),
            ("LEVEL", ShaderDef::Int(self.level)),
        ]
    }
}

fn compose(defs: &TestDefs) -> naga::Module {
    let mut library = ShaderLibrary::new(Capabilities::empty()).unwrap();
    library
        .compose(&DEFS, &defs.shader_defs())
        .unwrap_or_else(|error| panic!("{error}"))
}

/// A Compose error's fields, and its Display form (what `?` users see).
struct ComposeError {
    shader: String,
    file: String,
    message: String,
    display: String,
}

/// Composes `shader` with `defs` on a library without extra capabilities, which must
/// refuse it with a Compose error.
fn compose_error(shader: &PassShader, defs: &[(&'static str, ShaderDef)]) -> ComposeError {
    let mut library = ShaderLibrary::new(Capabilities::empty()).unwrap();
    let result = library.compose(shader, defs);
    let display = result.as_ref().err().map(ToString::to_string);
    match result {
        Err(ShaderError::Compose {
            shader,
            file,
            message,
        }) => ComposeError {
            shader,
            file,
            message,
            display: display.unwrap_or_default(),
        },
        other => panic!("expected a Compose error, got {other:?}"),
    }
}

#[test]
fn a_switch_selects_its_branch() {
    let on = compose(&TestDefs {
        double: true,
        scale: 500,
        level: 3,
    });
    let off = compose(&TestDefs {
        double: false,
        scale: 500,
        level: 3,
    });
    assert_eq!(stored_literals(&on), vec![2000, 500, 333]);
    // Bool(false) must behave as absent, although naga_oil alone would take it as defined.
    assert_eq!(stored_literals(&off), vec![1000, 500, 333]);
}

#[test]
fn values_are_substituted_and_compared() {
    let module = compose(&TestDefs {
        double: false,
        scale: 777,
        level: 4,
    });
    assert_eq!(stored_literals(&module), vec![1000, 777, 444]);
}

#[test]
fn the_pass_shader_macro_labels_the_file_with_the_crate() {
    assert_eq!(DEFS.file_path, "meshlight-shaders/wgsl/defs.wgsl");
    assert!(DEFS.source.contains("#ifdef DOUBLE"));
}

#[test]
fn a_def_given_twice_with_different_values_is_rejected() {
    let defs = [
        ("SCALE", ShaderDef::UInt(1)),
        ("LEVEL", ShaderDef::Int(3)),
        ("SCALE", ShaderDef::UInt(2)),
    ];
    let error = compose_error(&DEFS, &defs);
    assert_eq!(error.shader, "defs");
    assert!(error.message.contains("SCALE"), "{}", error.message);
}

#[test]
fn a_missing_import_names_the_shader_and_the_module() {
    let shader = pass_shader!("missing_import", "wgsl/missing_import.wgsl");
    let error = compose_error(&shader, &[]);
    assert_eq!(error.shader, "missing_import");
    assert_eq!(error.file, "meshlight-shaders/wgsl/missing_import.wgsl");
    assert!(
        error.message.contains("meshlight::no_such_module"),
        "{}",
        error.message
    );
}

#[test]
fn invalid_wgsl_reports_file_and_line() {
    let shader = pass_shader!("broken", "wgsl/broken.wgsl");
    let ComposeError {
        message, display, ..
    } = compose_error(&shader, &[]);
    assert!(
        message.contains("meshlight-shaders/wgsl/broken.wgsl:6:"),
        "{message}"
    );
    assert!(
        message.contains("x = ;"),
        "the offending line is quoted: {message}"
    );
    // The Display form carries the same text, for `?` users.
    assert!(display.contains("broken.wgsl:6:"));
}

#[test]
fn a_module_invalid_for_the_capabilities_is_a_validation_error() {
    let shader = pass_shader!("needs_int64", "wgsl/needs_int64.wgsl");
    let mut without = ShaderLibrary::new(Capabilities::empty()).unwrap();
    match without.compose(&shader, &[]) {
        Err(ShaderError::Validate { shader, message }) => {
            assert_eq!(shader, "needs_int64");
            // The validator has no span for a type, so the message names the capability.
            assert!(message.contains("SHADER_INT64"), "{message}");
        }
        other => panic!("expected a Validate error, got {other:?}"),
    }
    let mut with = ShaderLibrary::new(Capabilities::SHADER_INT64).unwrap();
    with.compose(&shader, &[])
        .unwrap_or_else(|error| panic!("{error}"));
}
