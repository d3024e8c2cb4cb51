//! The composer: shared modules added once, pass shaders composed and validated on demand.

use std::collections::HashMap;

use naga::valid::{Capabilities, ModuleInfo, ValidationFlags, Validator};
use naga_oil::compose::{
    ComposableModuleDescriptor, Composer, ComposerError, ComposerErrorInner, NagaModuleDescriptor,
    ShaderDefValue,
};

use crate::{ShaderDef, ShaderError, SharedModule, shared_modules};

/// A pass crate's own WGSL entry-point file, embedded with `include_str!`.
///
/// `file_path` only labels diagnostics; use a path relative to the workspace
/// (e.g. `passes/sw_raster/src/raster.wgsl`) so errors point at the file to open.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct PassShader {
    /// A stable name, used as the pipeline label and in errors.
    pub name: &'static str,
    /// The WGSL source, usually `include_str!("raster.wgsl")`.
    pub source: &'static str,
    /// Where the source lives, for diagnostics.
    pub file_path: &'static str,
    /// The crate's own modules the shader imports (`#import <name>`), added to the
    /// library the first time a shader needs them; shaders of one crate share code
    /// through them as all crates share the modules of this one.
    pub modules: &'static [LocalModule],
}

/// A WGSL module of one pass crate, imported by its shaders as `#import <name>`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct LocalModule {
    /// The import path; equals the file's `#define_import_path`.
    pub name: &'static str,
    /// The WGSL text.
    pub source: &'static str,
    /// Where the text comes from, which every error about it names.
    pub file_path: &'static str,
}

/// Builds a [`PassShader`] from a WGSL file beside the calling source file.
///
/// `pass_shader!("sw_raster", "raster.wgsl")` embeds the file with `include_str!` and
/// labels it with the calling crate's name and the file name. With
/// `modules: [("scan_fan::common", "common.wgsl")]` the shader may import those files of
/// the crate by their import paths; with `params: GpuParams` it may import the struct of
/// that [`crate::uniform_block!`] from the block's module.
#[macro_export]
macro_rules! pass_shader {
    ($name:expr, $file:literal $(, params: $params:ty)? $(, modules: [$(($import:literal, $module:literal)),* $(,)?])? $(,)?) => {
        $crate::PassShader {
            name: $name,
            source: include_str!($file),
            file_path: concat!(env!("CARGO_PKG_NAME"), "/", $file),
            modules: &[$(<$params>::MODULE,)? $($($crate::LocalModule {
                name: $import,
                source: include_str!($module),
                file_path: concat!(env!("CARGO_PKG_NAME"), "/", $module),
            }),*)?],
        }
    };
}

/// The shared library: a naga_oil composer with every shared module the device can use
/// added once, in dependency order.
///
/// Composing needs `&mut self` because naga_oil caches each module's IR per set of defs.
pub struct ShaderLibrary {
    composer: Composer,
    capabilities: Capabilities,
    added: Vec<&'static SharedModule>,
    /// Crate-local modules added so far, by import path.
    local: HashMap<&'static str, LocalModule>,
    /// Modules left out because the device lacks what they need, so an import of one is
    /// reported as a missing capability instead of a missing module.
    unavailable: Vec<&'static SharedModule>,
}

impl std::fmt::Debug for ShaderLibrary {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("ShaderLibrary")
            .field("capabilities", &self.capabilities)
            .field("modules", &self.shared_module_names())
            .finish_non_exhaustive()
    }
}

impl ShaderLibrary {
    /// Creates the library for a device with these naga capabilities (derive them from
    /// the device's wgpu features, e.g. `SHADER_INT64 | SHADER_INT64_ATOMIC_MIN_MAX`).
    ///
    /// Shared modules needing capabilities outside `capabilities` are left out; a pass
    /// importing one gets [`ShaderError::MissingCapability`].
    pub fn new(capabilities: Capabilities) -> Result<Self, ShaderError> {
        let mut composer = Composer::default().with_capabilities(capabilities);
        let mut added = Vec::new();
        let mut unavailable = Vec::new();
        for module in shared_modules() {
            if !capabilities.contains(module.capabilities) {
                unavailable.push(module);
                continue;
            }
            add_module(&mut composer, module.name, module.source, module.file_path)?;
            added.push(module);
        }
        Ok(Self {
            composer,
            capabilities,
            added,
            local: HashMap::new(),
            unavailable,
        })
    }

    /// The capabilities the library composes and validates under.
    pub fn capabilities(&self) -> Capabilities {
        self.capabilities
    }

    /// Composes a pass shader with these defs into a validated `naga::Module`.
    ///
    /// The result depends only on the shader, the defs (in any order) and the
    /// capabilities. A def given twice with different values is an error, since it
    /// would make the pipeline cache key ambiguous.
    pub fn compose(
        &mut self,
        shader: &PassShader,
        defs: &[(&'static str, ShaderDef)],
    ) -> Result<naga::Module, ShaderError> {
        let shader_defs = self.naga_oil_defs(shader, defs)?;
        self.add_local_modules(shader)?;
        self.composer
            .make_naga_module(NagaModuleDescriptor {
                source: shader.source,
                file_path: shader.file_path,
                shader_defs,
                ..Default::default()
            })
            .map_err(|error| self.compose_error(shader, error))
    }

    /// The names of the entry points [`compose`](Self::compose) gives, in source order:
    /// what a pass's tests check to know each variant composes with the stages it runs.
    pub fn entry_point_names(
        &mut self,
        shader: &PassShader,
        defs: &[(&'static str, ShaderDef)],
    ) -> Result<Vec<String>, ShaderError> {
        let module = self.compose(shader, defs)?;
        Ok(module.entry_points.into_iter().map(|e| e.name).collect())
    }

    /// Adds the shader's crate-local modules not added yet; a second module under an
    /// import path already taken by another source is an error.
    fn add_local_modules(&mut self, shader: &PassShader) -> Result<(), ShaderError> {
        for module in shader.modules {
            match self.local.get(module.name) {
                Some(known) if known.source == module.source => continue,
                Some(known) => {
                    return Err(ShaderError::AddModule {
                        module: module.name.to_owned(),
                        message: format!(
                            "{} and {} both define it; give one another import path",
                            known.file_path, module.file_path
                        ),
                    });
                }
                None => {}
            }
            add_module(
                &mut self.composer,
                module.name,
                module.source,
                module.file_path,
            )?;
            self.local.insert(module.name, *module);
        }
        Ok(())
    }

    /// The import paths of the shared modules this library offers, in the order added.
    pub fn shared_module_names(&self) -> Vec<String> {
        self.added
            .iter()
            .map(|module| module.name.to_owned())
            .collect()
    }

    fn naga_oil_defs(
        &self,
        shader: &PassShader,
        defs: &[(&'static str, ShaderDef)],
    ) -> Result<HashMap<String, ShaderDefValue>, ShaderError> {
        let mut map = HashMap::with_capacity(defs.len());
        let mut seen: HashMap<&str, ShaderDef> = HashMap::with_capacity(defs.len());
        for &(name, value) in defs {
            if let Some(previous) = seen.insert(name, value)
                && previous != value
            {
                return Err(ShaderError::Compose {
                    shader: shader.name.to_owned(),
                    file: shader.file_path.to_owned(),
                    message: format!(
                        "shader def `{name}` is given twice, as {previous:?} and {value:?}; \
                         give it once"
                    ),
                });
            }
            // naga_oil treats any present def as defined for `#ifdef`; a false switch
            // must be absent.
            if value != ShaderDef::Bool(false) {
                map.insert(name.to_owned(), value.into());
            }
        }
        Ok(map)
    }

    fn compose_error(&self, shader: &PassShader, error: ComposerError) -> ShaderError {
        if let ComposerErrorInner::ImportNotFound(import, _) = &error.inner
            && let Some(module) = self.unavailable.iter().find(|m| m.name == import)
        {
            return ShaderError::MissingCapability {
                shader: shader.name.to_owned(),
                module: module.name.to_owned(),
                missing: format!("{:?}", module.capabilities.difference(self.capabilities)),
            };
        }
        let message = error.emit_to_string(&self.composer);
        match error.inner {
            ComposerErrorInner::ShaderValidationError(_) => ShaderError::Validate {
                shader: shader.name.to_owned(),
                message,
            },
            _ => ShaderError::Compose {
                shader: shader.name.to_owned(),
                file: shader.file_path.to_owned(),
                message,
            },
        }
    }
}

/// Validates a module with naga's validator under `capabilities`.
///
/// [`ShaderLibrary::compose`] already validates; this is for modules built elsewhere and
/// for getting the `ModuleInfo` some backends need.
pub fn validate(
    name: &str,
    module: &naga::Module,
    capabilities: Capabilities,
) -> Result<ModuleInfo, ShaderError> {
    Validator::new(ValidationFlags::all(), capabilities)
        .validate(module)
        .map_err(|error| {
            let mut message = error.as_inner().to_string();
            let mut source = std::error::Error::source(error.as_inner());
            while let Some(cause) = source {
                message.push_str(&format!("\n  caused by: {cause}"));
                source = cause.source();
            }
            for (_, label) in error.spans() {
                message.push_str(&format!("\n  at: {label}"));
            }
            ShaderError::Validate {
                shader: name.to_owned(),
                message,
            }
        })
}

/// Adds one module to the composer under its import path; a module that does not parse
/// is an error naming it, with naga_oil's report.
fn add_module(
    composer: &mut Composer,
    name: &str,
    source: &str,
    file_path: &str,
) -> Result<(), ShaderError> {
    let added = composer
        .add_composable_module(ComposableModuleDescriptor {
            source,
            file_path,
            as_name: Some(name.to_owned()),
            ..Default::default()
        })
        .map(|_| ());
    added.map_err(|error| ShaderError::AddModule {
        module: name.to_owned(),
        message: error.emit_to_string(composer),
    })
}
