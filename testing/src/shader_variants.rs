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
