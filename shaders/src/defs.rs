//! Typed shader defs, so pass code never scatters bare `"NAME"` strings with loose values.

use naga_oil::compose::ShaderDefValue;

/// A shader-def value, as `#ifdef` / `#if NAME == value` / `#{NAME}` see it in WGSL.
///
/// It mirrors naga_oil's `ShaderDefValue` so that pass crates do not depend on naga_oil.
/// `Bool(false)` is the same as leaving the def out, so `#ifdef NAME` is false for it
/// (naga_oil on its own would count any present def as defined). Test switches with
/// `#ifdef`, not `#if NAME == false`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum ShaderDef {
    /// A switch: `#ifdef NAME` is true only for `Bool(true)`.
    Bool(bool),
    /// A signed constant, substituted by `#{NAME}`.
    Int(i32),
    /// An unsigned constant, substituted by `#{NAME}`; WGSL sees it with a `u` suffix.
    UInt(u32),
}

impl From<bool> for ShaderDef {
    fn from(value: bool) -> Self {
        Self::Bool(value)
    }
}

impl From<i32> for ShaderDef {
    fn from(value: i32) -> Self {
        Self::Int(value)
    }
}

impl From<u32> for ShaderDef {
    fn from(value: u32) -> Self {
        Self::UInt(value)
    }
}

impl From<ShaderDef> for ShaderDefValue {
    fn from(value: ShaderDef) -> Self {
        match value {
            ShaderDef::Bool(v) => ShaderDefValue::Bool(v),
            ShaderDef::Int(v) => ShaderDefValue::Int(v),
            ShaderDef::UInt(v) => ShaderDefValue::UInt(v),
        }
    }
}

/// Implemented by each pass's typed defs struct: the one place its def names are spelled.
///
/// The graph caches pipelines by (shader, defs), so the returned list must be a pure
/// function of `self`.
pub trait ShaderDefs {
    /// The defs to compose the pass shader with.
    fn shader_defs(&self) -> Vec<(&'static str, ShaderDef)>;
}

/// Passes without defs use `()`.
impl ShaderDefs for () {
    fn shader_defs(&self) -> Vec<(&'static str, ShaderDef)> {
        Vec::new()
    }
}

/// Declares a pass's defs struct and its [`ShaderDefs`] impl together, so each def's WGSL
/// name stands once, beside the field that holds its value.
///
/// A field's type is anything [`ShaderDef`] converts from (`bool`, `i32`, `u32`); its
/// def is `ShaderDef::from(field)`, in field order.
///
/// ```
/// meshlight_shaders::shader_defs! {
///     /// The variant of walk.wgsl a pass runs.
///     #[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
///     pub struct WalkDefs {
///         /// `OCCLUSION`: a pyramid is bound.
///         pub occlusion: bool => "OCCLUSION",
///         /// `ITEMS`: elements per lane.
///         pub items: u32 => "ITEMS",
///     }
/// }
/// use meshlight_shaders::{ShaderDef, ShaderDefs};
/// let defs = WalkDefs { occlusion: true, items: 4 };
/// assert_eq!(
///     defs.shader_defs(),
///     vec![("OCCLUSION", ShaderDef::Bool(true)), ("ITEMS", ShaderDef::UInt(4))]
/// );
/// ```
#[macro_export]
macro_rules! shader_defs {
    (
        $(#[$meta:meta])*
        $vis:vis struct $name:ident {
            $(
                $(#[$field_meta:meta])*
                $field_vis:vis $field:ident: $ty:ty => $def:literal
            ),* $(,)?
        }
    ) => {
        $(#[$meta])*
        $vis struct $name {
            $(
                $(#[$field_meta])*
                $field_vis $field: $ty,
            )*
        }

        impl $crate::ShaderDefs for $name {
            fn shader_defs(&self) -> ::std::vec::Vec<(&'static str, $crate::ShaderDef)> {
                ::std::vec![$(($def, $crate::ShaderDef::from(self.$field))),*]
            }
        }
    };
}
