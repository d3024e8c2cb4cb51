//! A pass's shader variants checked without a GPU: each composes and validates under
//! the capabilities of the device it is meant for, and one is refused without them.

use meshlight_shaders::{Capabilities, PassShader, ShaderDef, ShaderError, ShaderLibrary};

/// Composes `shader` with `defs` for a device of `caps` and validates the module, as a
/// pass building that variant's pipeline would.
pub fn compose_and_validate(
    shader: &PassShader,
    defs: &[(&'static str, ShaderDef)],
    caps: Capabilities,
) -> Result<(), ShaderError> {
    let module = ShaderLibrary::new(caps)?.compose(shader, defs)?;
    meshlight_shaders::validate(shader.name, &module, caps).map(|_| ())
}

/// The value of `const NAME: type = value;` at the start of a line of `shader`'s own
/// source, for tests that check a WGSL constant against the Rust one it mirrors. A
/// literal's suffix (`64u`, `2i`, `0.5f`) is dropped before parsing.
pub fn wgsl_constant<T>(shader: &PassShader, name: &str) -> T
where
    T: std::str::FromStr,
    T::Err: std::fmt::Debug,
{
    let line = shader
        .source
        .lines()
        .find(|l| {
            l.strip_prefix("const ")
                .and_then(|l| l.strip_prefix(name))
                .is_some_and(|rest| rest.starts_with(':'))
        })
        .unwrap_or_else(|| panic!("no `const {name}` in {}", shader.name));
    let literal = line
        .split('=')
        .nth(1)
        .unwrap_or_else(|| panic!("`{line}` has no value"));
    let literal = literal
        .trim()
        .trim_end_matches(';')
        .trim_end_matches(['u', 'i', 'f']);
    literal
        .parse()
        .unwrap_or_else(|e| panic!("`{literal}` (const {name}) does not parse: {e:?}"))
}
