//! The bindings a composed shader declares, read from its naga module, so a pass writes
//! each binding once: in WGSL. A global whose name is a slot binds that slot, one named
//! like a scratch resource binds the scratch, a `var<uniform>` takes the bytes the pass
//! gives under the variable's name; the access (read-only or read-write storage, write-only
//! texture) and the stages that use it come from the module.

use crate::access::Access;
use crate::layout::{BindingLayout, BindingSource, LayoutEntry};

/// naga_oil appends this and an encoded module path to the names of items that come from
/// an imported module; the name before it is the one written in WGSL.
const IMPORTED_NAME_SUFFIX: &str = "X_naga_oil_mod_X";

/// What kind of resource a WGSL global is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum GlobalKind {
    Uniform,
    /// A storage buffer; `element` is the stride of a runtime-sized array (`array<T>`).
    Buffer {
        writes: bool,
        element: Option<u32>,
    },
    /// A sampled texture.
    Sampled,
    /// A storage texture.
    StorageTexture {
        reads: bool,
        writes: bool,
    },
    Sampler,
}

/// One resource global of a composed module.
#[derive(Clone, Debug)]
pub(crate) struct ShaderGlobal {
    /// The name as written in WGSL (naga_oil's decoration removed).
    pub name: String,
    pub group: u32,
    pub binding: u32,
    pub kind: GlobalKind,
    /// The entry points that use it, with their stage.
    pub used_by: Vec<(String, wgpu::ShaderStages)>,
}

/// Every resource global of `module` and the entry points that use it.
pub(crate) fn globals(module: &naga::Module) -> Result<Vec<ShaderGlobal>, String> {
    let info = naga::valid::Validator::new(
        naga::valid::ValidationFlags::empty(),
        naga::valid::Capabilities::all(),
    )
    .validate(module)
    .map_err(|e| format!("the composed module does not validate: {}", e.as_inner()))?;
    let mut out = Vec::new();
    for (handle, global) in module.global_variables.iter() {
        let Some(binding) = &global.binding else {
            continue;
        };
        let name = global.name.as_deref().unwrap_or("");
        let name = name.split(IMPORTED_NAME_SUFFIX).next().unwrap_or(name);
        let kind = match (global.space, &module.types[global.ty].inner) {
            (naga::AddressSpace::Uniform, _) => GlobalKind::Uniform,
            (naga::AddressSpace::Storage { access }, inner) => GlobalKind::Buffer {
                writes: access.contains(naga::StorageAccess::STORE),
                element: match inner {
                    naga::TypeInner::Array {
                        size: naga::ArraySize::Dynamic,
                        stride,
                        ..
                    } => Some(*stride),
                    _ => None,
                },
            },
            (_, naga::TypeInner::Sampler { .. }) => GlobalKind::Sampler,
            (
                _,
                naga::TypeInner::Image {
                    class: naga::ImageClass::Storage { access, .. },
                    ..
                },
            ) => GlobalKind::StorageTexture {
                reads: access.contains(naga::StorageAccess::LOAD),
                writes: access.intersects(naga::StorageAccess::STORE | naga::StorageAccess::ATOMIC),
            },
            (_, naga::TypeInner::Image { .. }) => GlobalKind::Sampled,
            _ => continue,
        };
        let used_by = module
            .entry_points
            .iter()
            .enumerate()
            .filter(|(i, _)| !info.get_entry_point(*i)[handle].is_empty())
            .map(|(_, ep)| (ep.name.clone(), stage(ep.stage)))
            .collect();
        out.push(ShaderGlobal {
            name: name.to_string(),
            group: binding.group,
            binding: binding.binding,
            kind,
            used_by,
        });
    }
    Ok(out)
}

fn stage(stage: naga::ShaderStage) -> wgpu::ShaderStages {
    match stage {
        naga::ShaderStage::Vertex => wgpu::ShaderStages::VERTEX,
        naga::ShaderStage::Fragment => wgpu::ShaderStages::FRAGMENT,
        naga::ShaderStage::Compute => wgpu::ShaderStages::COMPUTE,
        naga::ShaderStage::Task => wgpu::ShaderStages::TASK,
        naga::ShaderStage::Mesh => wgpu::ShaderStages::MESH,
        _ => wgpu::ShaderStages::all(),
    }
}

/// What a layout's reflection needs to know about the pass.
pub(crate) struct Names {
    pub stage: &'static str,
    /// The contract slots bound to this pass, with their access and element size (0 for
    /// a texture).
    pub slots: Vec<(&'static str, Access, u32)>,
    /// Every slot of the contract, bound or not.
    pub all_slots: Vec<&'static str>,
    /// The pass's scratch resources.
    pub scratch: Vec<String>,
}

/// A mismatch between a shader and the slots it binds.
#[derive(Clone, Debug, PartialEq, Eq)]
pub(crate) struct Mismatch {
    pub variable: String,
    pub message: String,
}

/// `layout` (group `group`) with every binding the program's `entries` use filled in from
/// `globals`: explicit entries stay as declared; each other global binds the slot or
/// scratch resource of its name, or a uniform.
pub(crate) fn expand(
    layout: &BindingLayout,
    group: u32,
    globals: &[ShaderGlobal],
    entries: &[&str],
    names: &Names,
) -> Result<BindingLayout, Mismatch> {
    let mut out = BindingLayout {
        reflect: false,
        ..layout.clone()
    };
    for g in globals.iter().filter(|g| g.group == group) {
        let stages = g
            .used_by
            .iter()
            .filter(|(e, _)| entries.contains(&e.as_str()))
            .fold(wgpu::ShaderStages::NONE, |s, (_, st)| s | *st);
        if stages.is_empty() {
            if g.kind == GlobalKind::Uniform {
                out.unused_uniforms.push(g.name.clone().into());
            }
            continue;
        }
        // An explicit entry stands, whatever the variable is called there: the form for
        // a binding whose name cannot match (one variable, two slots by mode). A uniform
        // is the exception: its name is how the pass gives its bytes, so it must be the
        // variable's.
        if let Some(e) = layout.entries.iter().find(|e| e.binding == g.binding) {
            if let BindingSource::Uniform(name) = &e.source
                && *name != g.name
            {
                return Err(mismatch(
                    g,
                    format!(
                        "the layout names the uniform at binding {} `{name}`, but the shader calls it `{}`; give the layout the variable's name",
                        g.binding, g.name
                    ),
                ));
            }
            continue;
        }
        let entry = |source| LayoutEntry {
            binding: g.binding,
            source,
            visibility: Some(stages),
            read_only: false,
            write_only: false,
        };
        let mut e = match g.kind {
            GlobalKind::Uniform => entry(BindingSource::Uniform(g.name.clone().into())),
            GlobalKind::Sampler => {
                return Err(mismatch(
                    g,
                    format!(
                        "a sampler cannot be bound by name; declare it with `.sampler({}, kind)` on the layout",
                        g.binding
                    ),
                ));
            }
            _ => {
                if let Some(&(slot, access, element)) =
                    names.slots.iter().find(|(s, ..)| *s == g.name)
                {
                    check_slot(g, slot, access, element)?;
                    entry(BindingSource::Slot(slot))
                } else if names.scratch.contains(&g.name) {
                    entry(BindingSource::Scratch(
                        g.name.clone().into(),
                        scratch_access(g.kind),
                    ))
                } else if names.all_slots.contains(&g.name.as_str()) {
                    return Err(mismatch(
                        g,
                        format!(
                            "the shader uses slot `{}`, which is optional and not bound here; bind it, or compile the variant without it (its def)",
                            g.name
                        ),
                    ));
                } else {
                    return Err(mismatch(
                        g,
                        format!(
                            "`{}` (binding {}) matches no slot of stage `{}` ({}) and no scratch resource ({}); name the variable after a slot, declare a scratch resource of that name, or declare the binding on the layout",
                            g.name,
                            g.binding,
                            names.stage,
                            names.all_slots.join(", "),
                            if names.scratch.is_empty() {
                                "none".to_string()
                            } else {
                                names.scratch.join(", ")
                            }
                        ),
                    ));
                }
            }
        };
        match g.kind {
            GlobalKind::Buffer { writes: false, .. } => e.read_only = true,
            GlobalKind::StorageTexture {
                reads: false,
                writes: true,
            } => e.write_only = true,
            GlobalKind::StorageTexture {
                reads: true,
                writes: false,
            } => e.read_only = true,
            _ => {}
        }
        out.entries.push(e);
    }
    out.entries.sort_by_key(|e| e.binding);
    Ok(out)
}

fn mismatch(g: &ShaderGlobal, message: String) -> Mismatch {
    Mismatch {
        variable: g.name.clone(),
        message,
    }
}

/// A shader may read what a slot lets it write, never write what the slot only reads;
/// a buffer's element must be the slot's.
fn check_slot(g: &ShaderGlobal, slot: &str, access: Access, element: u32) -> Result<(), Mismatch> {
    let writes = match g.kind {
        GlobalKind::Buffer { writes, .. } => writes,
        GlobalKind::StorageTexture { writes, .. } => writes,
        _ => false,
    };
    if writes && !access.writes() {
        return Err(mismatch(
            g,
            format!(
                "slot `{slot}` is {} but the shader declares it writable; declare it `read` in WGSL, or give the slot a writing access",
                access.name()
            ),
        ));
    }
    // A buffer of records may also be read as 4-byte words (indirect arguments as
    // `array<atomic<u32>>`); any other stride must be the record's.
    if let GlobalKind::Buffer {
        element: Some(stride),
        ..
    } = g.kind
        && element > 0
        && stride != element
        && !(stride == 4 && element.is_multiple_of(4))
    {
        return Err(mismatch(
            g,
            format!(
                "slot `{slot}` holds elements of {element} bytes but the shader reads an array of {stride}-byte elements; make the WGSL element type match the slot's"
            ),
        ));
    }
    Ok(())
}

fn scratch_access(kind: GlobalKind) -> Access {
    match kind {
        GlobalKind::Buffer { writes: true, .. }
        | GlobalKind::StorageTexture { writes: true, .. } => Access::StorageReadWrite,
        GlobalKind::Sampled => Access::Sampled,
        _ => Access::StorageRead,
    }
}
