//! A pipeline as data: the `[params]`, `[[resource]]` and `[[pass]]` entries of a pipeline
//! file, which a caller changes through methods (a parameter set, a pass's implementation
//! swapped, a resource added and bound) before [`Pipeline::build`] turns it into a
//! [`GraphBuilder`]. A renderer that ships its frame as a file applies its settings here,
//! so the frame exists once, as the file, and nothing ever edits the file's text.

use crate::builder::GraphBuilder;
use crate::error::{GraphError, Result};
use crate::file::Registry;
use serde::{Deserialize, Serialize};
use std::collections::{BTreeMap, BTreeSet};
use std::path::Path;

/// A pipeline file as parsed, before its passes are built.
///
/// A renderer ships its frame as a file and applies its settings through these methods;
/// `auto` picks the first implementation the registry prefers that the adapter runs:
///
/// ```
/// use meshlight_graph::file::{Params, Pipeline, Registry};
/// use meshlight_graph::*;
///
/// /// A stage `fill` with two implementations that write `list` (recording nothing here).
/// struct Fill(&'static str);
/// impl Pass for Fill {
///     fn implementation(&self) -> Implementation {
///         let list = Slot::buffer("list", Access::StorageWrite, Element::U32, "");
///         Implementation::new(self.0, StageContract { stage: "fill", slots: vec![list] })
///     }
///     fn setup(&self, _: &mut SetupContext) -> Result<()> {
///         Ok(())
///     }
///     fn record(&self, _: &mut RecordContext<'_>) -> Result<()> {
///         Ok(())
///     }
/// }
///
/// const FRAME: &str = r#"
/// [params]
/// n = 1024
///
/// [[resource]]
/// name = "list"
/// kind = "exported"
/// buffer = { element = "u32", count_param = "n" }
///
/// [[pass]]
/// name = "fill"
/// stage = "fill"
/// implementation = "auto"
/// "#;
///
/// # fn main() -> Result<()> {
/// let mut registry = Registry::new();
/// registry.register("fill", "fast", |_: &Params| Ok(Fill("fast")));
/// registry.register("fill", "simple", |_: &Params| Ok(Fill("simple")));
/// registry.prefer("fill", &["fast", "simple"]);
///
/// let options = CompileOptions::new(wgpu::Features::empty());
/// let mut frame = Pipeline::parse(FRAME, "frame.toml")?;
/// let plan = frame.build(&registry)?.compile(&options)?.plan;
/// assert_eq!(plan.passes[0].implementation, "fast");
///
/// // Settings: a size and a stage's implementation, changed without editing text.
/// frame.set_param("n", 4096)?;
/// assert_eq!(frame.set_implementation("fill", "simple"), 1);
/// let plan = frame.build(&registry)?.compile(&options)?.plan;
/// assert_eq!(plan.passes[0].implementation, "simple");
/// let list = plan.resources.iter().find(|r| r.info.name == "list").unwrap();
/// assert!(matches!(&list.info.desc, ResourceDesc::Buffer(b) if b.size == 4 * 4096));
/// # Ok(())
/// # }
/// ```
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct Pipeline {
    /// Shown in dumps.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub name: Option<String>,
    /// Size parameters: `[params] cluster_slots = 65536`; buffers name one with
    /// `count_param` instead of `count`, pass parameters with `"$name"`.
    #[serde(default)]
    pub params: BTreeMap<String, u64>,
    /// View sets: `[views] cascades = 4`. A `[[resource]]` or `[[pass]]` with
    /// `views = "cascades"` stands for one entry per view of the set, `{view}` in its name,
    /// bindings and inputs replaced by the view's number (0, 1, …); a set of 0 views
    /// leaves its entries out. A pass over a set whose name holds no `{view}` is one pass
    /// for all the set's views (a walk that culls every view at once), which reads the
    /// set's size as a parameter `"$cascades"`.
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub views: BTreeMap<String, u32>,
    /// The `[[resource]]` entries, in file order.
    #[serde(default, rename = "resource")]
    pub resources: Vec<ResourceEntry>,
    /// The `[[pass]]` entries, in file order: the order passes are added to the graph.
    #[serde(default, rename = "pass")]
    pub passes: Vec<PassEntry>,
    /// Where the pipeline came from, as errors name it.
    #[serde(skip)]
    file: String,
}

/// What a `[[resource]]` entry declares: a transient, imported, exported or history
/// resource.
#[derive(Debug, Deserialize, Serialize, Clone, Copy, PartialEq, Eq)]
#[serde(rename_all = "snake_case")]
pub enum EntryKind {
    /// Lives within a frame, pooled.
    Transient,
    /// Owned by the caller, handed to every frame.
    Imported,
    /// Transient, kept after the frame for the caller to read back.
    Exported,
    /// Written this frame, read next frame as `<name>.prev`.
    History,
}

/// A buffer of `count` (or `count_param`) elements.
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct BufferEntry {
    /// A known element name (`u32`, `u64`, `f32`, `vec4<f32>`, `DispatchIndirectArgs`,
    /// `DrawIndirectArgs`, `u8`) or any name with `element_size`.
    pub element: String,
    /// Bytes per element, for element names the graph does not know.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub element_size: Option<u32>,
    /// A fixed element count.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub count: Option<u64>,
    /// A size parameter from `[params]` giving the element count.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub count_param: Option<String>,
}

/// How many mip levels a texture entry has: a count, or `"full"`, the whole chain down
/// to 1 × 1 for whatever size its parameters give, so a file sized by parameters never
/// carries a mip count that only fits one size.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize, Serialize)]
#[serde(try_from = "MipLevelsText", into = "MipLevelsText")]
pub enum MipLevels {
    /// This many levels.
    Count(u32),
    /// `floor(log2(max(width, height))) + 1` levels.
    Full,
}

impl Default for MipLevels {
    fn default() -> Self {
        MipLevels::Count(1)
    }
}

impl MipLevels {
    /// The level count for a `width × height` texture.
    pub fn resolve(self, width: u32, height: u32) -> u32 {
        match self {
            MipLevels::Count(n) => n,
            MipLevels::Full => 32 - width.max(height).max(1).leading_zeros(),
        }
    }
}

/// `mip_levels` as written: a number or a word.
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(untagged)]
enum MipLevelsText {
    Count(u32),
    Word(String),
}

impl TryFrom<MipLevelsText> for MipLevels {
    type Error = String;
    fn try_from(t: MipLevelsText) -> std::result::Result<Self, String> {
        match t {
            MipLevelsText::Count(n) => Ok(MipLevels::Count(n)),
            MipLevelsText::Word(w) if w == "full" => Ok(MipLevels::Full),
            MipLevelsText::Word(w) => Err(format!(
                "`mip_levels = \"{w}\"`: give a number of levels, or \"full\" for the whole chain"
            )),
        }
    }
}

impl From<MipLevels> for MipLevelsText {
    fn from(m: MipLevels) -> Self {
        match m {
            MipLevels::Count(n) => MipLevelsText::Count(n),
            MipLevels::Full => MipLevelsText::Word("full".into()),
        }
    }
}

/// A 2-D texture (or array), its size fixed or read from `[params]`.
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct TextureEntry {
    /// The format's WGSL spelling (`rgba8unorm`, `r32float`, `depth32float`, …).
    pub format: String,
    /// A fixed width, or `width_param`: a size parameter from `[params]` (read when the
    /// pipeline is built, so a renderer sets the viewport through the parameters).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub width: Option<u32>,
    /// The size parameter giving the width.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub width_param: Option<String>,
    /// A fixed height.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub height: Option<u32>,
    /// The size parameter giving the height.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub height_param: Option<String>,
    /// Mip levels: a count (1 when left out) or `"full"`.
    #[serde(default)]
    pub mip_levels: MipLevels,
    /// Array layers (1: a plain 2-D texture).
    #[serde(default = "one")]
    pub layers: u32,
}

fn one() -> u32 {
    1
}

/// A 64-bit visibility target of `width × height` values, held as a `u64` buffer or an
/// `R64Uint` texture as the rasteriser that clears it writes (see
/// `GraphBuilder::create_visibility64`), so swapping that rasteriser is one line.
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct VisibilityEntry {
    /// A fixed width.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub width: Option<u32>,
    /// The size parameter giving the width.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub width_param: Option<String>,
    /// A fixed height.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub height: Option<u32>,
    /// The size parameter giving the height.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub height_param: Option<String>,
}

/// One `[[resource]]`: a name, a kind and exactly one of a buffer, a texture or a
/// visibility target.
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct ResourceEntry {
    /// The resource's name; slots of the same name bind it unless told otherwise.
    pub name: String,
    /// Transient, imported, exported or history.
    pub kind: EntryKind,
    /// A buffer.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub buffer: Option<BufferEntry>,
    /// A texture.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub texture: Option<TextureEntry>,
    /// A 64-bit visibility target.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub visibility: Option<VisibilityEntry>,
    /// Imported only: the usages the caller creates it with (`STORAGE`, `COPY_SRC`, …).
    /// The names are checked on every kind, so a misspelt one is never ignored.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub usage: Vec<String>,
    /// The view set (`[views]`) it exists once per view of; its name holds `{view}`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub views: Option<String>,
}

impl ResourceEntry {
    /// A buffer of `kind` holding `count` elements of `element` (a known element name,
    /// or any name with `element_size`).
    pub fn buffer(
        name: &str,
        kind: EntryKind,
        element: &str,
        element_size: Option<u32>,
        count: u64,
    ) -> Self {
        Self::of(
            name,
            kind,
            BufferEntry {
                element: element.to_string(),
                element_size,
                count: Some(count),
                count_param: None,
            },
        )
    }

    /// A texture of `kind` in `format` (WGSL spelling) sized by the parameters
    /// `width_param` and `height_param`.
    pub fn texture_sized_by(
        name: &str,
        kind: EntryKind,
        format: &str,
        width_param: &str,
        height_param: &str,
    ) -> Self {
        Self {
            name: name.to_string(),
            kind,
            buffer: None,
            texture: Some(TextureEntry {
                format: format.to_string(),
                width: None,
                width_param: Some(width_param.to_string()),
                height: None,
                height_param: Some(height_param.to_string()),
                mip_levels: MipLevels::default(),
                layers: 1,
            }),
            visibility: None,
            usage: Vec::new(),
            views: None,
        }
    }

    fn of(name: &str, kind: EntryKind, buffer: BufferEntry) -> Self {
        Self {
            name: name.to_string(),
            kind,
            buffer: Some(buffer),
            texture: None,
            visibility: None,
            usage: Vec::new(),
            views: None,
        }
    }

    /// The usages an imported resource is created with, as wgpu names the flags
    /// (`STORAGE`, `RENDER_ATTACHMENT`, …).
    pub fn with_usage(mut self, usage: &[&str]) -> Self {
        self.usage = usage.iter().map(|u| u.to_string()).collect();
        self
    }
}

/// One `[[pass]]`: an instance of a stage implementation with its parameters and slot
/// bindings.
#[derive(Clone, Debug, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct PassEntry {
    /// The pass instance's name in the graph, unique in the pipeline.
    pub name: String,
    /// The stage it implements.
    pub stage: String,
    /// The implementation's name, or `auto`.
    pub implementation: String,
    /// The implementation's parameters (`"$name"` reads a size parameter).
    #[serde(default, skip_serializing_if = "toml::Table::is_empty")]
    pub params: toml::Table,
    /// slot → `resource` (its current version), `resource@N` (an explicit version), with
    /// `#mip=2`-style texture ranges.
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub bind: BTreeMap<String, String>,
    /// Frame input the pass reads → the frame input supplied for it
    /// (`inputs = { view = "cascade_view_{view}" }`): see `Bindings::input`.
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub inputs: BTreeMap<String, String>,
    /// The view set (`[views]`) it runs once per view of, its name holding `{view}`; or,
    /// with no `{view}` in its name, the set it runs once for, over all its views.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub views: Option<String>,
}

impl PassEntry {
    /// A pass of `stage` named `name`, of implementation `implementation`, with no
    /// parameters, bindings or inputs.
    pub fn new(name: &str, stage: &str, implementation: &str) -> Self {
        Self {
            name: name.to_string(),
            stage: stage.to_string(),
            implementation: implementation.to_string(),
            params: toml::Table::new(),
            bind: BTreeMap::new(),
            inputs: BTreeMap::new(),
            views: None,
        }
    }
    /// The parameter `key` as written.
    pub fn param(&self, key: &str) -> Option<&toml::Value> {
        self.params.get(key)
    }
    /// The string parameter `key`, where it is one.
    pub fn param_str(&self, key: &str) -> Option<&str> {
        self.param(key).and_then(toml::Value::as_str)
    }
    /// Sets parameter `key`, replacing what the file wrote.
    pub fn set_param(&mut self, key: &str, value: impl Into<toml::Value>) {
        self.params.insert(key.to_string(), value.into());
    }
    /// The resource (and version or range, as written) bound to `slot` explicitly.
    pub fn binding(&self, slot: &str) -> Option<&str> {
        self.bind.get(slot).map(String::as_str)
    }
    /// Binds `slot` to `resource` (written as in a file: `name`, `name@N`, `name#mip=1`).
    pub fn bind(&mut self, slot: &str, resource: &str) {
        self.bind.insert(slot.to_string(), resource.to_string());
    }
    /// Removes the explicit binding of `slot`; the slot then binds the resource of its
    /// own name, if any (optional slots stay unbound without one).
    pub fn unbind(&mut self, slot: &str) -> Option<String> {
        self.bind.remove(slot)
    }
}

/// The resource name a binding target refers to: `name@2#mip=1` and `name.prev` name
/// `name`'s entry.
pub(crate) fn target_resource(target: &str) -> &str {
    let name = target.split(['#', '@']).next().unwrap_or(target);
    name.strip_suffix(".prev").unwrap_or(name)
}

impl Pipeline {
    /// Parses a pipeline file's text; `file` names it in errors.
    pub fn parse(text: &str, file: &str) -> Result<Self> {
        let mut p: Pipeline = toml::from_str(text).map_err(|e| GraphError::PipelineFile {
            file: file.to_string(),
            message: e.to_string(),
        })?;
        p.file = file.to_string();
        Ok(p)
    }

    /// Reads and parses the pipeline file at `path` (a regular file of bounded size; see
    /// [`crate::file::read_pipeline_text`]).
    pub fn load(path: &Path) -> Result<Self> {
        let text = crate::file::read_pipeline_text(path)?;
        Self::parse(&text, &path.display().to_string())
    }

    /// The file the pipeline came from, as errors name it.
    pub fn file(&self) -> &str {
        &self.file
    }

    fn error(&self, message: String) -> GraphError {
        GraphError::PipelineFile {
            file: self.file.clone(),
            message,
        }
    }

    /// The value of size parameter `name`.
    pub fn param(&self, name: &str) -> Option<u64> {
        self.params.get(name).copied()
    }

    /// Sets a size parameter the pipeline declares; an undeclared one is an error (a
    /// misspelt name would otherwise be ignored).
    pub fn set_param(&mut self, name: &str, value: u64) -> Result<()> {
        match self.params.get_mut(name) {
            Some(v) => {
                *v = value;
                Ok(())
            }
            None => Err(self.error(format!(
                "the caller sets parameter `{name}`, which the pipeline does not declare; add `{name} = <default>` to its [params]"
            ))),
        }
    }

    /// [`Self::set_param`] for each of `params`.
    pub fn set_params<N: AsRef<str>>(
        &mut self,
        params: impl IntoIterator<Item = (N, u64)>,
    ) -> Result<()> {
        params
            .into_iter()
            .try_for_each(|(name, value)| self.set_param(name.as_ref(), value))
    }

    /// Sets a size parameter, declaring it when the pipeline does not.
    pub fn declare_param(&mut self, name: &str, value: u64) {
        self.params.insert(name.to_string(), value);
    }

    /// The resource entry named `name`.
    pub fn resource(&self, name: &str) -> Option<&ResourceEntry> {
        self.resources.iter().find(|r| r.name == name)
    }

    /// Adds a resource before every pass, so slots of its name bind it by default; a
    /// name the pipeline already declares is an error.
    pub fn add_resource(&mut self, entry: ResourceEntry) -> Result<()> {
        if self.resource(&entry.name).is_some() {
            return Err(self.error(format!(
                "the caller adds resource `{}`, which the pipeline already declares; bind the existing one or pick another name",
                entry.name
            )));
        }
        self.resources.push(entry);
        Ok(())
    }

    /// Removes the resource named `name` and every explicit binding to it, so the slots
    /// that bound it are left unbound (an optional slot) or refused when the pipeline is
    /// built (a required one, naming it). Returns whether the pipeline declared it.
    pub fn remove_resource(&mut self, name: &str) -> bool {
        let before = self.resources.len();
        self.resources.retain(|r| r.name != name);
        for p in &mut self.passes {
            p.bind.retain(|_, target| target_resource(target) != name);
        }
        self.resources.len() < before
    }

    /// The pass named `name`.
    pub fn pass(&self, name: &str) -> Option<&PassEntry> {
        self.passes.iter().find(|p| p.name == name)
    }

    /// The pass named `name`, to change; an unknown name is an error listing the passes.
    pub fn pass_mut(&mut self, name: &str) -> Result<&mut PassEntry> {
        match self.passes.iter().position(|p| p.name == name) {
            Some(i) => Ok(&mut self.passes[i]),
            None => {
                let known = self
                    .passes
                    .iter()
                    .map(|p| p.name.as_str())
                    .collect::<Vec<_>>()
                    .join(", ");
                Err(self.error(format!("it has no pass `{name}` (passes: {known})")))
            }
        }
    }

    /// The passes of `stage`, in order.
    pub fn passes_of<'p>(&'p self, stage: &'p str) -> impl Iterator<Item = &'p PassEntry> + 'p {
        self.passes.iter().filter(move |p| p.stage == stage)
    }

    /// The passes of `stage`, in order, to change.
    pub fn passes_of_mut<'p>(
        &'p mut self,
        stage: &'p str,
    ) -> impl Iterator<Item = &'p mut PassEntry> + 'p {
        self.passes.iter_mut().filter(move |p| p.stage == stage)
    }

    /// Whether any pass implements `stage`.
    pub fn has_stage(&self, stage: &str) -> bool {
        self.passes_of(stage).next().is_some()
    }

    /// Sets parameter `key` of every pass of `stage`; returns how many passes there are.
    pub fn set_stage_param(
        &mut self,
        stage: &str,
        key: &str,
        value: impl Into<toml::Value>,
    ) -> usize {
        let value = value.into();
        self.passes_of_mut(stage)
            .map(|p| p.set_param(key, value.clone()))
            .count()
    }

    /// Runs every pass of `stage` with `implementation` (or `auto`); returns how many
    /// passes there are. An implementation the registry lacks is refused when the
    /// pipeline is built, with the stage's known ones.
    pub fn set_implementation(&mut self, stage: &str, implementation: &str) -> usize {
        self.passes_of_mut(stage)
            .map(|p| p.implementation = implementation.to_string())
            .count()
    }

    /// Binds `resource` to `slot` of every pass of `stage` (an extra resource a stage
    /// reads in every pass, such as a second binding of a table); returns how many
    /// passes there are.
    pub fn bind_stage(&mut self, stage: &str, slot: &str, resource: &str) -> usize {
        self.passes_of_mut(stage)
            .map(|p| p.bind(slot, resource))
            .count()
    }

    /// Removes the passes `remove` picks, then every resource no remaining pass binds
    /// (by name or explicitly), and the explicit bindings of remaining passes to a
    /// resource that only removed passes wrote: what only the removed passes made goes
    /// with them, and an optional slot that read it is left unbound. A required slot left
    /// without its resource is refused when the pipeline is built, naming it. `registry`
    /// gives each pass's contract, to know which slots bind by name. Returns the names of
    /// the removed passes and resources.
    pub fn remove_passes(
        &mut self,
        registry: &Registry,
        remove: impl Fn(&PassEntry) -> bool,
    ) -> Result<Removed> {
        let (gone, kept): (Vec<PassEntry>, Vec<PassEntry>) = std::mem::take(&mut self.passes)
            .into_iter()
            .partition(remove);
        self.passes = kept;
        let mut written_by_kept = BTreeSet::new();
        let mut bound_by_kept = BTreeSet::new();
        for p in &self.passes {
            for (slot, writes) in self.slots_of(p, registry)? {
                let resource = p.binding(slot).map_or(slot, target_resource).to_string();
                if writes {
                    written_by_kept.insert(resource.clone());
                }
                bound_by_kept.insert(resource);
            }
        }
        let mut written_by_gone = BTreeSet::new();
        for p in &gone {
            for (slot, writes) in self.slots_of(p, registry)? {
                if writes {
                    written_by_gone
                        .insert(p.binding(slot).map_or(slot, target_resource).to_string());
                }
            }
        }
        // A resource only removed passes wrote holds nothing now: it goes, and so do the
        // explicit bindings to it.
        let orphans: BTreeSet<String> = written_by_gone
            .difference(&written_by_kept)
            .filter(|r| {
                self.resource(r)
                    .is_some_and(|e| matches!(e.kind, EntryKind::Transient | EntryKind::Exported))
            })
            .cloned()
            .collect();
        for p in &mut self.passes {
            p.bind
                .retain(|_, target| !orphans.contains(target_resource(target)));
        }
        let mut resources = Vec::new();
        self.resources.retain(|r| {
            let keep = bound_by_kept.contains(&r.name) && !orphans.contains(&r.name);
            if !keep {
                resources.push(r.name.clone());
            }
            keep
        });
        Ok(Removed {
            passes: gone.into_iter().map(|p| p.name).collect(),
            resources,
        })
    }

    /// Each slot of `pass`'s stage contract (from the registry, with the pass's own
    /// parameters) with whether the pass writes through it.
    fn slots_of(&self, pass: &PassEntry, registry: &Registry) -> Result<Vec<(&'static str, bool)>> {
        // An entry over a view set is built as its first view: params like
        // `layer = "{view}"` only mean something once the view is known.
        let first_view;
        let pass = match pass.views {
            Some(_) => {
                first_view = crate::file::build::view_pass(pass, 0);
                &first_view
            }
            None => pass,
        };
        let contract = crate::file::build::build_pass(self, pass, registry)?.contract();
        Ok(contract
            .slots
            .iter()
            .map(|s| (s.name, s.writes()))
            .collect())
    }

    /// The graph this pipeline declares, its passes built by `registry`.
    pub fn build(&self, registry: &Registry) -> Result<GraphBuilder> {
        crate::file::build::build(self, registry)
    }

    /// The pipeline as TOML text, for a caller that keeps or shows the pipeline it
    /// built (comments of the original file are not kept).
    pub fn to_toml(&self) -> String {
        toml::to_string(self).unwrap_or_default()
    }
}

/// What [`Pipeline::remove_passes`] removed.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Removed {
    /// The passes, by name.
    pub passes: Vec<String>,
    /// The resources no remaining pass uses, by name.
    pub resources: Vec<String>,
}

/// Reads and parses the pipeline file at `path` with `registry`'s stages.
pub fn load_pipeline(path: &Path, registry: &Registry) -> Result<GraphBuilder> {
    Pipeline::load(path)?.build(registry)
}

/// Parses a pipeline file's text (`file` names it in errors) with `registry`'s stages.
pub fn parse_pipeline(text: &str, file: &str, registry: &Registry) -> Result<GraphBuilder> {
    Pipeline::parse(text, file)?.build(registry)
}
