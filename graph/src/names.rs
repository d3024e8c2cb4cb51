//! How wgpu's flags, features and formats are named in messages, dumps and the plan's
//! JSON, so every place that prints one prints the same words.

use serde::{Serialize, Serializer};

/// Feature names, comma-separated, for error messages.
pub fn feature_names(f: wgpu::Features) -> String {
    f.iter_names()
        .map(|(n, _)| n)
        .collect::<Vec<_>>()
        .join(", ")
}

/// The names of the flags set, in declaration order.
pub(crate) fn flag_names<B: bitflags::Flags>(flags: &B) -> Vec<String> {
    flags.iter_names().map(|(n, _)| n.to_string()).collect()
}

pub(crate) fn ser_features<S: Serializer>(f: &wgpu::Features, s: S) -> Result<S::Ok, S::Error> {
    // Features print as their names; `iter_names` is stable in declaration order.
    let names: Vec<String> = f.iter_names().map(|(n, _)| n.to_string()).collect();
    names.serialize(s)
}
pub(crate) fn ser_buffer_usages<S: Serializer>(
    u: &wgpu::BufferUsages,
    s: S,
) -> Result<S::Ok, S::Error> {
    flag_names(u).serialize(s)
}
pub(crate) fn ser_texture_usages<S: Serializer>(
    u: &wgpu::TextureUsages,
    s: S,
) -> Result<S::Ok, S::Error> {
    flag_names(u).serialize(s)
}
pub(crate) fn ser_format<S: Serializer>(f: &wgpu::TextureFormat, s: S) -> Result<S::Ok, S::Error> {
    format_name(*f).serialize(s)
}
pub(crate) fn ser_opt_format<S: Serializer>(
    f: &Option<wgpu::TextureFormat>,
    s: S,
) -> Result<S::Ok, S::Error> {
    f.map(format_name).serialize(s)
}

/// A texture format as written in WGSL and pipeline files (`rgba8unorm`, `r32uint`, …).
pub(crate) fn format_name(f: wgpu::TextureFormat) -> String {
    format!("{f:?}").to_lowercase()
}
