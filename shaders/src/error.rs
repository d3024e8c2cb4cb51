//! One error type for everything that can go wrong between WGSL text and a valid module.

/// Why a shader could not be turned into a valid `naga::Module`.
///
/// Messages come from naga_oil's diagnostic renderer, so they quote the offending file
/// and line, not the mangled names naga_oil uses internally.
#[derive(thiserror::Error, Debug)]
#[non_exhaustive]
pub enum ShaderError {
    /// A shared module of this crate does not parse or does not build; a bug here, not in the pass.
    #[error("shared shader module `{module}` could not be added to the library:\n{message}")]
    AddModule {
        /// The module's import path, e.g. `meshlight::view`.
        module: String,
        /// The rendered diagnostic with file and line.
        message: String,
    },
    /// The pass shader does not preprocess, parse, or resolve its imports.
    #[error(
        "shader `{shader}` ({file}) does not compose; fix the source at the place shown:\n{message}"
    )]
    Compose {
        /// The pass shader's name.
        shader: String,
        /// The pass shader's file path, as given in its [`crate::PassShader`].
        file: String,
        /// The rendered diagnostic with file and line.
        message: String,
    },
    /// The composed module is not valid under the device's capabilities.
    #[error("shader `{shader}` fails validation:\n{message}")]
    Validate {
        /// The pass shader's (or module's) name.
        shader: String,
        /// The validator's message, with file and line where naga_oil can map them.
        message: String,
    },
    /// The pass imports a shared module that needs a capability this device lacks.
    #[error(
        "shader `{shader}` imports `{module}`, which needs the capabilities {missing}; \
         the device does not have them, so pick an implementation of this stage that does not \
         import `{module}`, or run on an adapter with those features"
    )]
    MissingCapability {
        /// The pass shader's name.
        shader: String,
        /// The shared module that could not be offered.
        module: String,
        /// The missing naga capabilities, formatted by bitflags.
        missing: String,
    },
}
