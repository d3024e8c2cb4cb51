//! Turning a [`Pipeline`] into a [`GraphBuilder`] through the code-first API, so both
//! paths share every check: resources declared in file order, then each pass built by
//! the registry and added with its bindings.

use crate::builder::{Bindings, GraphBuilder, History};
use crate::error::{GraphError, Result};
use crate::file::pipeline::{EntryKind, PassEntry, Pipeline, ResourceEntry};
use crate::file::{Params, Registry};
use crate::pass::Pass;
use crate::problem::ResourceProblem;
use crate::resource::{BufferDesc, Element, Handle, TextureDesc, TextureRange};
use std::collections::BTreeMap;

/// A pipeline entry's pass: one implementation, or several for compile to pick from.
pub(crate) enum Built {
    One(Box<dyn Pass>),
    Choice(crate::choice::Choice),
}

impl Built {
    /// The stage contract of what was built (a choice's candidates share one).
    pub(crate) fn contract(&self) -> crate::contract::StageContract {
        match self {
            Built::One(p) => p.implementation().contract,
            Built::Choice(c) => c.candidates[0].implementation().contract,
        }
    }
}

/// The pass `p` as the registry builds it with its parameters (`"$name"` read from the
/// pipeline's `[params]`), errors naming the pass.
pub(crate) fn build_pass(pipeline: &Pipeline, p: &PassEntry, registry: &Registry) -> Result<Built> {
    let ferr = |message: String| GraphError::PipelineFile {
        file: pipeline.file().to_string(),
        message,
    };
    if registry.implementations(&p.stage).is_empty() {
        let stages = registry.stage_names();
        return Err(GraphError::UnknownStage {
            file: pipeline.file().to_string(),
            pass: p.name.clone(),
            stage: p.stage.clone(),
            known: if stages.is_empty() {
                "none are registered".into()
            } else {
                stages.join(", ")
            },
        });
    }
    let mut table = p.params.clone();
    substitute_params(&mut table, &pipeline.params, &pipeline.views)
        .map_err(|m| ferr(format!("pass `{}`: {m}", p.name)))?;
    let params = Params::new(table);
    let with_pass = |e| match e {
        GraphError::Parameter { message, .. } => GraphError::Parameter {
            pass: p.name.clone(),
            message,
        },
        other => other,
    };
    Ok(
        match registry
            .build_choice(&p.stage, &p.implementation, &params)
            .map_err(with_pass)?
        {
            Some(choice) => Built::Choice(choice),
            None => Built::One(
                registry
                    .build(&p.stage, &p.implementation, &params)
                    .map_err(with_pass)?,
            ),
        },
    )
}

/// Declares every resource of `pipeline`, then builds and adds every pass.
pub(crate) fn build(pipeline: &Pipeline, registry: &Registry) -> Result<GraphBuilder> {
    let file = pipeline.file();
    let ferr = |message: String| GraphError::PipelineFile {
        file: file.to_string(),
        message,
    };
    let mut g = GraphBuilder::new();
    for (name, value) in &pipeline.params {
        g.size_param(name, *value);
    }
    let (resources, passes) = expanded(pipeline)?;
    for r in &resources {
        declare(&mut g, r, &pipeline.params).map_err(|refusal| match refusal {
            Refusal::Text(m) => ferr(format!("resource `{}`: {m}", r.name)),
            Refusal::Problem(problem) => GraphError::PipelineResource {
                file: file.to_string(),
                resource: r.name.clone(),
                problem,
            },
        })?;
    }
    for p in &passes {
        let pass = build_pass(pipeline, p, registry)?;
        let mut bindings = Bindings::new();
        for (read, supplied) in &p.inputs {
            bindings = bindings.input(read, supplied);
        }
        for (slot, target) in &p.bind {
            if target.is_empty() {
                bindings = bindings.unbind(slot);
                continue;
            }
            let bad = |m: String| ferr(format!("pass `{}` slot `{slot}`: {m}", p.name));
            let (target_res, range) = match target.split_once('#') {
                Some((res, view)) => (res, Some(parse_range(view).map_err(bad)?)),
                None => (target.as_str(), None),
            };
            bindings = match target_res.split_once('@') {
                Some((res, v)) => {
                    let v: u32 = v.parse().map_err(|e: std::num::ParseIntError| {
                        let why = match e.kind() {
                            std::num::IntErrorKind::PosOverflow => format!(
                                "the version after @ in `{target}` is too large (at most {})",
                                u32::MAX
                            ),
                            _ => format!("`{target}` needs a version number after @"),
                        };
                        bad(why)
                    })?;
                    let h = g
                        .resource_at(res, v)
                        .ok_or_else(|| GraphError::UnknownResource {
                            pass: p.name.clone(),
                            slot: slot.clone(),
                            resource: res.to_string(),
                        })?;
                    match range {
                        Some(r) => bindings.bind_range(slot, h, r),
                        None => bindings.bind(slot, h),
                    }
                }
                None => match range {
                    Some(r) => bindings.bind_named_range(slot, target_res, r),
                    None => bindings.bind_named(slot, target_res),
                },
            };
        }
        match pass {
            Built::One(pass) => g.add_boxed_pass(&p.name, pass, bindings)?,
            Built::Choice(choice) => g.add_choice(&p.name, choice, bindings)?,
        };
    }
    Ok(g)
}

/// What stands for a view's number in the entries of a view set.
const VIEW: &str = "{view}";

/// The pipeline's resources and passes with each view set's entries written out once
/// per view (`{view}` replaced by its number in names, bindings, inputs and string
/// parameters), in file order.
fn expanded(pipeline: &Pipeline) -> Result<(Vec<ResourceEntry>, Vec<PassEntry>)> {
    let ferr = |message: String| GraphError::PipelineFile {
        file: pipeline.file().to_string(),
        message,
    };
    let views = |what: &str, name: &str, set: &Option<String>, uses_view: bool| match set {
        None if uses_view => Err(ferr(format!(
            "{what} `{name}` writes `{VIEW}` but runs over no view set; add `views = \"<set>\"` naming one of [views]"
        ))),
        None => Ok(None),
        Some(set) if !name.contains(VIEW) && what == "resource" => Err(ferr(format!(
            "{what} `{name}` runs over view set `{set}`, but its name holds no `{VIEW}`, so its views would share one name; name it like `{name}_{VIEW}`"
        ))),
        Some(set) => match pipeline.views.get(set) {
            Some(&count) => Ok(Some(count)),
            None => Err(ferr(format!(
                "{what} `{name}` runs over view set `{set}`, which [views] does not declare; add `{set} = <views>` to [views]"
            ))),
        },
    };
    // `"$name"` reads [params] first, then [views]: one name in both would be ambiguous.
    if let Some(name) = pipeline
        .views
        .keys()
        .find(|v| pipeline.params.contains_key(*v))
    {
        return Err(ferr(format!(
            "`{name}` is both a size parameter ([params]) and a view set ([views]), so `\"${name}\"` would be ambiguous; rename one"
        )));
    }
    let mut resources = Vec::new();
    for r in &pipeline.resources {
        match views("resource", &r.name, &r.views, r.name.contains(VIEW))? {
            None => resources.push(r.clone()),
            Some(count) => resources.extend((0..count).map(|k| ResourceEntry {
                name: r.name.replace(VIEW, &k.to_string()),
                views: None,
                ..r.clone()
            })),
        }
    }
    // Consecutive entries over one view set form a block, written out view by view
    // (view 0's passes, then view 1's, ...): each view's passes run together, so they
    // may share lists that each view refills.
    let mut passes = Vec::new();
    let mut block: Vec<&PassEntry> = Vec::new();
    let mut block_count = 0;
    let flush = |block: &mut Vec<&PassEntry>, count: u32, passes: &mut Vec<PassEntry>| {
        for k in 0..count {
            passes.extend(block.iter().map(|p| view_pass(p, k)));
        }
        block.clear();
    };
    for p in &pipeline.passes {
        let uses_view = |text: &str| text.contains(VIEW);
        let written = uses_view(&p.name)
            || p.bind.values().any(|t| uses_view(t))
            || p.inputs.values().any(|t| uses_view(t))
            || p.params.values().any(|v| v.as_str().is_some_and(uses_view));
        let count = views("pass", &p.name, &p.views, written)?;
        // An entry over a set whose name holds no `{view}` is one pass for every view
        // of the set (it reads the set's size as `"$<set>"`): it must not write `{view}`.
        let whole_set = count.is_some() && !uses_view(&p.name);
        if whole_set && written {
            return Err(ferr(format!(
                "pass `{}` runs once for the whole view set `{}` (its name holds no `{VIEW}`), so `{VIEW}` in its bindings, inputs or params names no view; name it like `{}_{VIEW}` to run it per view",
                p.name,
                p.views.as_deref().unwrap_or_default(),
                p.name
            )));
        }
        if block.first().is_some_and(|b| b.views != p.views) || count.is_none() || whole_set {
            flush(&mut block, block_count, &mut passes);
        }
        match count {
            None => passes.push(p.clone()),
            Some(0) if whole_set => {}
            Some(_) if whole_set => passes.push(PassEntry {
                views: None,
                ..p.clone()
            }),
            Some(count) => {
                block.push(p);
                block_count = count;
            }
        }
    }
    flush(&mut block, block_count, &mut passes);
    Ok((resources, passes))
}

/// View `k`'s pass of an entry that runs over a view set: `{view}` replaced by `k` in
/// its name, bindings, inputs and string params.
pub(crate) fn view_pass(p: &PassEntry, k: u32) -> PassEntry {
    let view = |text: &String| text.replace(VIEW, &k.to_string());
    let mut pass = p.clone();
    pass.name = view(&p.name);
    pass.views = None;
    pass.bind.values_mut().for_each(|t| *t = view(t));
    pass.inputs.values_mut().for_each(|t| *t = view(t));
    for (_, v) in pass.params.iter_mut() {
        if let toml::Value::String(text) = v {
            // A param that is the view alone is its index, a number (`layer =
            // "{view}"`); in a longer text it is spelled out.
            *v = if text == VIEW {
                toml::Value::Integer(i64::from(k))
            } else {
                toml::Value::String(text.replace(VIEW, &k.to_string()))
            };
        }
    }
    pass
}

/// `mip=N`, `mips=A..B`, `layer=N`, `layers=A..B`, joined with `,`: the part of a texture
/// a slot binds, written after `#` (`pyramid#mip=2`, `shadow#layer=1,mip=0`).
fn parse_range(text: &str) -> std::result::Result<TextureRange, String> {
    let mut range = TextureRange::mips(0, u32::MAX);
    let span = |v: &str| -> Option<(u32, u32)> {
        match v.split_once("..") {
            Some((a, b)) => {
                let (a, b): (u32, u32) = (a.trim().parse().ok()?, b.trim().parse().ok()?);
                (b > a).then_some((a, b - a))
            }
            None => v.trim().parse().ok().map(|n| (n, 1)),
        }
    };
    for part in text.split(',') {
        let (key, value) = part.split_once('=').ok_or_else(|| {
            format!("`#{text}`: expected `mip=N`, `mips=A..B`, `layer=N` or `layers=A..B`")
        })?;
        let (first, count) = span(value).ok_or_else(|| {
            format!("`#{text}`: `{value}` is not a number or a non-empty range A..B")
        })?;
        match key.trim() {
            "mip" | "mips" => {
                range.base_mip = first;
                range.mip_count = count;
            }
            "layer" | "layers" => {
                range.base_layer = first;
                range.layer_count = count;
            }
            other => {
                return Err(format!(
                    "`#{text}`: unknown view key `{other}`; use mip, mips, layer or layers"
                ));
            }
        }
    }
    Ok(range)
}

/// Pass parameters written `"$name"` take the value of size parameter `name`, so one
/// `[params]` entry (the viewport, say) reaches resources and passes alike; a name that
/// [params] does not declare but [views] does reads the set's number of views.
fn substitute_params(
    table: &mut toml::Table,
    params: &BTreeMap<String, u64>,
    views: &BTreeMap<String, u32>,
) -> std::result::Result<(), String> {
    for (key, value) in table.iter_mut() {
        if let toml::Value::String(s) = value
            && let Some(name) = s.strip_prefix('$')
        {
            let v = params
                .get(name)
                .copied()
                .or_else(|| views.get(name).map(|&n| u64::from(n)))
                .ok_or_else(|| {
                    format!(
                        "parameter `{key}` refers to `${name}`, which neither [params] nor [views] declares"
                    )
                })?;
            let v = &v;
            let v = i64::try_from(*v)
                .map_err(|_| format!("`${name}` = {v} is too large for parameter `{key}`"))?;
            *value = toml::Value::Integer(v);
        }
    }
    Ok(())
}

/// A texture dimension: fixed, or from a size parameter.
fn dimension(
    what: &str,
    fixed: Option<u32>,
    param: &Option<String>,
    params: &BTreeMap<String, u64>,
) -> std::result::Result<u32, String> {
    match (fixed, param) {
        (Some(v), None) => Ok(v),
        (None, Some(p)) => {
            let v = params
                .get(p)
                .ok_or_else(|| format!("`{what}_param = \"{p}\"` names no entry of [params]"))?;
            u32::try_from(*v).map_err(|_| format!("{what} `{p}` = {v} does not fit 32 bits"))
        }
        _ => Err(format!("give exactly one of `{what}` or `{what}_param`")),
    }
}

/// Why [`declare`] refused an entry: a typed problem, or a message about the entry's
/// shape.
enum Refusal {
    Text(String),
    Problem(ResourceProblem),
}

impl From<String> for Refusal {
    fn from(m: String) -> Self {
        Refusal::Text(m)
    }
}
impl From<&str> for Refusal {
    fn from(m: &str) -> Self {
        Refusal::Text(m.to_string())
    }
}
impl From<ResourceProblem> for Refusal {
    fn from(p: ResourceProblem) -> Self {
        Refusal::Problem(p)
    }
}

/// Refuses an extent with a zero dimension, whether written or read from `[params]`.
fn nonzero_extent(
    what: &'static str,
    width: u32,
    height: u32,
    mip_levels: u32,
    layers: u32,
) -> std::result::Result<(), ResourceProblem> {
    if [width, height, mip_levels, layers].contains(&0) {
        return Err(ResourceProblem::ZeroExtent {
            what,
            width,
            height,
            mip_levels,
            layers,
        });
    }
    Ok(())
}

fn declare(
    g: &mut GraphBuilder,
    r: &ResourceEntry,
    params: &BTreeMap<String, u64>,
) -> std::result::Result<(), Refusal> {
    if let Some(v) = &r.visibility {
        if r.buffer.is_some() || r.texture.is_some() {
            return Err(
                "give exactly one of `buffer = {..}`, `texture = {..}` or `visibility = {..}`"
                    .into(),
            );
        }
        // Held as a buffer or a texture, as the rasteriser decides: a name either knows.
        if let Some(n) = r.usage.iter().find(|n| {
            wgpu::BufferUsages::from_name(n).is_none()
                && wgpu::TextureUsages::from_name(n).is_none()
        }) {
            return Err(ResourceProblem::UnknownUsage {
                kind: "buffer or texture",
                usage: n.clone(),
                known: format!(
                    "{}; {}",
                    known_names(wgpu::BufferUsages::all().iter_names()),
                    known_names(wgpu::TextureUsages::all().iter_names())
                ),
            }
            .into());
        }
        let width = dimension("width", v.width, &v.width_param, params)?;
        let height = dimension("height", v.height, &v.height_param, params)?;
        nonzero_extent("visibility target", width, height, 1, 1)?;
        match r.kind {
            EntryKind::Transient => drop(g.create_visibility64(&r.name, width, height)),
            EntryKind::Exported => {
                let h = g.create_visibility64(&r.name, width, height);
                g.export(h);
            }
            other => {
                return Err(format!(
                    "a visibility target is `transient` or `exported`, not {other:?}; declare a {} as `buffer` or `texture` instead",
                    if other == EntryKind::Imported {
                        "caller-owned one"
                    } else {
                        "history"
                    }
                )
                .into());
            }
        }
        return Ok(());
    }
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
                    )
                    .into());
                }
            };
            let usage = usage_flags::<wgpu::BufferUsages>(&r.usage, "buffer")?;
            // A count from a parameter may be 0 for a while (no instances yet) and is
            // checked where it is resolved; one written in the file never changes.
            if element.size == 0 || b.count == Some(0) {
                return Err(ResourceProblem::EmptyBuffer {
                    count: b.count,
                    element_size: element.size,
                }
                .into());
            }
            let desc = match (b.count, &b.count_param) {
                (Some(n), None) => BufferDesc::array(element, n),
                (None, Some(p)) => BufferDesc::array_param(element, p),
                _ => return Err("give exactly one of `count` or `count_param`".into()),
            };
            let buffer = Declarers {
                create: GraphBuilder::create_buffer,
                import: GraphBuilder::import_buffer,
                history: GraphBuilder::history_buffer,
            };
            buffer.declare(g, r, desc, usage);
        }
        (None, Some(t)) => {
            let usage = usage_flags::<wgpu::TextureUsages>(&r.usage, "texture")?;
            let format = parse_format(&t.format)?;
            let width = dimension("width", t.width, &t.width_param, params)?;
            let height = dimension("height", t.height, &t.height_param, params)?;
            let desc = TextureDesc {
                format,
                width,
                height,
                mip_levels: t.mip_levels.resolve(width, height),
                layers: t.layers,
            };
            nonzero_extent(
                "texture",
                desc.width,
                desc.height,
                desc.mip_levels,
                desc.layers,
            )?;
            let texture = Declarers {
                create: GraphBuilder::create_texture,
                import: GraphBuilder::import_texture,
                history: GraphBuilder::history_texture,
            };
            texture.declare(g, r, desc, usage);
        }
        _ => {
            return Err(
                "give exactly one of `buffer = {..}`, `texture = {..}` or `visibility = {..}`"
                    .into(),
            );
        }
    }
    Ok(())
}

/// The builder's three ways to declare a buffer, or a texture: the entry's kind picks
/// one, the same way for both forms.
struct Declarers<D, U, K> {
    create: fn(&mut GraphBuilder, &str, D) -> Handle<K>,
    import: fn(&mut GraphBuilder, &str, D, U) -> Handle<K>,
    history: fn(&mut GraphBuilder, &str, D) -> History<K>,
}

impl<D, U, K> Declarers<D, U, K> {
    /// Declares `r` as `desc`; `usage` is read only by an imported entry.
    fn declare(&self, g: &mut GraphBuilder, r: &ResourceEntry, desc: D, usage: U) {
        match r.kind {
            EntryKind::Transient => drop((self.create)(g, &r.name, desc)),
            EntryKind::Exported => {
                let h = (self.create)(g, &r.name, desc);
                g.export(h);
            }
            EntryKind::Imported => drop((self.import)(g, &r.name, desc, usage)),
            EntryKind::History => drop((self.history)(g, &r.name, desc)),
        }
    }
}

/// An entry's `usage` names as the wgpu flags of its `kind` (`buffer` or `texture`); a
/// name the flags lack is refused with the ones they have.
fn usage_flags<F: bitflags::Flags + Copy>(
    names: &[String],
    kind: &'static str,
) -> std::result::Result<F, ResourceProblem> {
    names.iter().try_fold(F::empty(), |acc, n| {
        F::from_name(n)
            .map(|u| acc.union(u))
            .ok_or_else(|| ResourceProblem::UnknownUsage {
                kind,
                usage: n.clone(),
                known: known_names(F::all().iter_names()),
            })
    })
}

/// The flag names a `usage` list may hold, as wgpu spells them.
fn known_names<T>(names: impl Iterator<Item = (&'static str, T)>) -> String {
    names.map(|(n, _)| n).collect::<Vec<_>>().join(", ")
}

/// How a pipeline entry writes `format` (what [`parse_format`] reads back), for a caller
/// that adds a texture of a format it holds.
pub fn format_text(format: wgpu::TextureFormat) -> String {
    crate::names::format_name(format)
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
        F::Bgra8UnormSrgb,
        F::Rgb10a2Unorm,
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
        .find(|f| crate::names::format_name(*f) == name.to_lowercase())
        .ok_or_else(|| {
            format!(
                "unknown texture format `{name}`; known: {}",
                KNOWN
                    .iter()
                    .map(|f| crate::names::format_name(*f))
                    .collect::<Vec<_>>()
                    .join(", ")
            )
        })
}
