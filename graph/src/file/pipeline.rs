//! Pipeline files: a TOML list of resources and pass instances, turned into a
//! `GraphBuilder` through the code-first API, so both paths share every check.

use crate::builder::{Bindings, GraphBuilder};
use crate::error::{GraphError, Result};
use crate::file::{Params, Registry};
use crate::resource::{BufferDesc, Element, TextureDesc};
use serde::Deserialize;
use std::collections::BTreeMap;
use std::path::Path;

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PipelineFile {
    /// Shown in dumps.
    #[serde(default)]
    pub name: Option<String>,
    #[serde(default, rename = "resource")]
    pub resources: Vec<ResourceEntry>,
    #[serde(default, rename = "pass")]
    pub passes: Vec<PassEntry>,
}

#[derive(Debug, Deserialize, Clone, Copy, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub enum EntryKind {
    Transient,
    Imported,
    Exported,
    History,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BufferEntry {
    /// A known element name (`u32`, `u64`, `f32`, `vec4<f32>`, `DispatchIndirectArgs`,
    /// `DrawIndirectArgs`, `u8`) or any name with `element_size`.
    pub element: String,
    pub element_size: Option<u32>,
    pub count: u64,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TextureEntry {
    pub format: String,
    pub width: u32,
    pub height: u32,
    #[serde(default = "one")]
    pub mip_levels: u32,
}
fn one() -> u32 {
    1
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ResourceEntry {
    pub name: String,
    pub kind: EntryKind,
    pub buffer: Option<BufferEntry>,
    pub texture: Option<TextureEntry>,
    /// Imported only: the usages the caller creates it with (`STORAGE`, `COPY_SRC`, …).
    #[serde(default)]
    pub usage: Vec<String>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PassEntry {
    pub name: String,
    pub stage: String,
    pub implementation: String,
    #[serde(default)]
    pub params: toml::Table,
    /// slot → `resource` (its current version) or `resource@N` (an explicit version).
    #[serde(default)]
    pub bind: BTreeMap<String, String>,
}

pub fn load_pipeline(path: &Path, registry: &Registry) -> Result<GraphBuilder> {
    let text = std::fs::read_to_string(path).map_err(|e| GraphError::PipelineFile {
        file: path.display().to_string(),
        message: format!("cannot read it: {e}"),
    })?;
    parse_pipeline(&text, &path.display().to_string(), registry)
}

pub fn parse_pipeline(text: &str, file: &str, registry: &Registry) -> Result<GraphBuilder> {
    let ferr = |message: String| GraphError::PipelineFile {
        file: file.to_string(),
        message,
    };
    let parsed: PipelineFile = toml::from_str(text).map_err(|e| ferr(e.to_string()))?;
    let mut g = GraphBuilder::new();
    for r in &parsed.resources {
        declare(&mut g, r).map_err(|m| ferr(format!("resource `{}`: {m}", r.name)))?;
    }
    for p in &parsed.passes {
        let pass = registry
            .build(&p.stage, &p.implementation, &Params::new(p.params.clone()))
            .map_err(|e| match e {
                GraphError::Parameter { message, .. } => GraphError::Parameter {
                    pass: p.name.clone(),
                    message,
                },
                other => other,
            })?;
        let mut bindings = Bindings::new();
        for (slot, target) in &p.bind {
            bindings = match target.split_once('@') {
                Some((res, v)) => {
                    let v: u32 = v.parse().map_err(|_| {
                        ferr(format!(
                            "pass `{}` slot `{slot}`: `{target}` needs a version number after @",
                            p.name
                        ))
                    })?;
                    let h = g
                        .resource_at(res, v)
                        .ok_or_else(|| GraphError::UnknownResource {
                            pass: p.name.clone(),
                            slot: slot.clone(),
                            resource: res.to_string(),
                        })?;
                    bindings.bind(slot, h)
                }
                None => bindings.bind_named(slot, target),
            };
        }
        g.add_boxed_pass(&p.name, pass, bindings)?;
    }
    Ok(g)
}

fn declare(g: &mut GraphBuilder, r: &ResourceEntry) -> std::result::Result<(), String> {
    match (&r.buffer, &r.texture) {
        (Some(b), None) => {
            let element = match (Element::from_known_name(&b.element), b.element_size) {
                (_, Some(size)) => Element {
                    name: b.element.clone().into(),
                    size,
                },
                (Some(e), None) => e,
                (None, None) => {
                    return Err(format!(
                        "element `{}` is not a known type; give `element_size` in bytes",
                        b.element
                    ));
                }
            };
            let desc = BufferDesc::array(element, b.count);
            match r.kind {
                EntryKind::Transient => drop(g.create_buffer(&r.name, desc)),
                EntryKind::Exported => {
                    let h = g.create_buffer(&r.name, desc);
                    g.export(h);
                }
                EntryKind::Imported => {
                    let _ = g.import_buffer(&r.name, desc, buffer_usage(&r.usage)?);
                }
                EntryKind::History => drop(g.history_buffer(&r.name, desc)),
            }
        }
        (None, Some(t)) => {
            let format = parse_format(&t.format)?;
            let desc = TextureDesc {
                format,
                width: t.width,
                height: t.height,
                mip_levels: t.mip_levels,
            };
            match r.kind {
                EntryKind::Transient => drop(g.create_texture(&r.name, desc)),
                EntryKind::Exported => {
                    let h = g.create_texture(&r.name, desc);
                    g.export(h);
                }
                EntryKind::Imported => {
                    let _ = g.import_texture(&r.name, desc, texture_usage(&r.usage)?);
                }
                EntryKind::History => drop(g.history_texture(&r.name, desc)),
            }
        }
        _ => return Err("give exactly one of `buffer = {..}` or `texture = {..}`".into()),
    }
    Ok(())
}

fn buffer_usage(names: &[String]) -> std::result::Result<wgpu::BufferUsages, String> {
    names
        .iter()
        .try_fold(wgpu::BufferUsages::empty(), |acc, n| {
            wgpu::BufferUsages::from_name(n)
                .map(|u| acc | u)
                .ok_or_else(|| format!("unknown buffer usage `{n}`"))
        })
}
fn texture_usage(names: &[String]) -> std::result::Result<wgpu::TextureUsages, String> {
    names
        .iter()
        .try_fold(wgpu::TextureUsages::empty(), |acc, n| {
            wgpu::TextureUsages::from_name(n)
                .map(|u| acc | u)
                .ok_or_else(|| format!("unknown texture usage `{n}`"))
        })
}

/// Texture formats by their WGSL spelling (`rgba8unorm`, `r32uint`, `depth32float`, …).
pub fn parse_format(name: &str) -> std::result::Result<wgpu::TextureFormat, String> {
    use wgpu::TextureFormat as F;
    const KNOWN: &[F] = &[
        F::R8Unorm,
        F::R16Float,
        F::R32Uint,
        F::R32Sint,
        F::R32Float,
        F::R64Uint,
        F::Rg32Uint,
        F::Rg32Float,
        F::Rgba8Unorm,
        F::Rgba8UnormSrgb,
        F::Bgra8Unorm,
        F::Rgba16Float,
        F::Rgba32Uint,
        F::Rgba32Float,
        F::Depth32Float,
        F::Depth24Plus,
        F::Depth16Unorm,
    ];
    KNOWN
        .iter()
        .copied()
        .find(|f| crate::plan::format_name(*f) == name.to_lowercase())
        .ok_or_else(|| {
            format!(
                "unknown texture format `{name}`; known: {}",
                KNOWN
                    .iter()
                    .map(|f| crate::plan::format_name(*f))
                    .collect::<Vec<_>>()
                    .join(", ")
            )
        })
}
