//! Stage contracts: the named slots every implementation of a stage shares.
//!
//! Swapping one implementation for another is checked against the contract, so a pipeline
//! that compiled with one software rasteriser compiles with the other.

use crate::access::Access;
use crate::resource::Element;
use serde::Serialize;

/// What kind of resource a slot expects.
#[derive(Clone, Debug, PartialEq, Serialize)]
#[serde(tag = "type", rename_all = "snake_case")]
pub enum SlotKind {
    /// A buffer; when `element` is set, the bound buffer must hold that element type.
    Buffer {
        /// The element type the bound buffer must hold; `None` accepts any.
        element: Option<Element>,
    },
    /// A texture; when `format` is set, the bound texture must have it.
    Texture {
        /// The format the bound texture must have; `None` accepts any.
        #[serde(serialize_with = "crate::names::ser_opt_format")]
        format: Option<wgpu::TextureFormat>,
    },
    /// A 64-bit visibility target: a buffer of `u64` or an `R64Uint` texture. A software
    /// rasteriser on a storage buffer and one on 64-bit texture atomics share a contract
    /// through this, so swapping them stays a one-line change.
    Visibility64,
}

/// One named input or output of a stage, with its access and what it holds.
#[derive(Clone, Debug, Serialize)]
pub struct Slot {
    /// The slot's name: bindings and shader globals refer to it.
    pub name: &'static str,
    /// The access bind groups use.
    pub access: Access,
    /// Further uses in the same pass: the indirect arguments of a dispatch or draw, a copy.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub also: Vec<Access>,
    /// What the bound resource must be.
    pub kind: SlotKind,
    /// One line for dumps and error messages.
    pub doc: &'static str,
    /// An optional slot may stay unbound; the pass checks `RecordContext::is_bound`.
    pub optional: bool,
}

impl Slot {
    /// A buffer slot holding `element`s.
    pub fn buffer(name: &'static str, access: Access, element: Element, doc: &'static str) -> Self {
        Self {
            name,
            access,
            kind: SlotKind::Buffer {
                element: Some(element),
            },
            also: Vec::new(),
            doc,
            optional: false,
        }
    }
    /// A buffer slot the pass only reads (`Access::StorageRead`): most of a contract's
    /// inputs.
    pub fn read(name: &'static str, element: Element, doc: &'static str) -> Self {
        Self::buffer(name, Access::StorageRead, element, doc)
    }
    /// A texture slot, of `format` when one is required.
    pub fn texture(
        name: &'static str,
        access: Access,
        format: Option<wgpu::TextureFormat>,
        doc: &'static str,
    ) -> Self {
        Self {
            name,
            access,
            kind: SlotKind::Texture { format },
            also: Vec::new(),
            doc,
            optional: false,
        }
    }
    /// A 64-bit visibility target (see [`SlotKind::Visibility64`]).
    pub fn visibility64(name: &'static str, access: Access, doc: &'static str) -> Self {
        Self {
            name,
            access,
            kind: SlotKind::Visibility64,
            also: Vec::new(),
            doc,
            optional: false,
        }
    }
    /// Adds a further use in the same pass, e.g. `Access::Indirect` for a buffer a dispatch
    /// appends to and a later dispatch or draw of the pass takes its arguments from.
    pub fn also(mut self, access: Access) -> Self {
        self.also.push(access);
        self
    }
    /// Every access, the binding one first.
    pub fn accesses(&self) -> impl Iterator<Item = Access> + Clone + '_ {
        std::iter::once(self.access).chain(self.also.iter().copied())
    }
    /// True when the pass depends on earlier contents. A slot whose uses include one that
    /// overwrites or clears (storage-write, cleared-read-write, a target) reads only what
    /// the pass itself wrote through its other uses (the indirect arguments it appended).
    pub fn reads(&self) -> bool {
        crate::access::reads_earlier(self.accesses())
    }
    /// True when any use writes, so binding it makes a new version of the resource.
    pub fn writes(&self) -> bool {
        self.accesses().any(Access::writes)
    }
    /// `storage-read-write+indirect`, for dumps and messages.
    pub fn access_name(&self) -> String {
        self.accesses()
            .map(Access::name)
            .collect::<Vec<_>>()
            .join("+")
    }
    /// Marks the slot optional: left unbound (and with no resource of its name), the pass
    /// runs without it.
    pub fn optional(mut self) -> Self {
        self.optional = true;
        self
    }
}

/// The slots of one stage kind, shared by all its implementations.
#[derive(Clone, Debug, Serialize)]
pub struct StageContract {
    /// The stage kind, e.g. `sw_raster`; pipeline files and the registry name it.
    pub stage: &'static str,
    /// The slots, in the order bindings and bind groups list them.
    pub slots: Vec<Slot>,
}

impl StageContract {
    /// The slot named `name`, if the stage has one.
    pub fn slot(&self, name: &str) -> Option<&Slot> {
        self.slots.iter().find(|s| s.name == name)
    }
    /// The slot names, in order, for messages.
    pub fn slot_names(&self) -> Vec<&'static str> {
        self.slots.iter().map(|s| s.name).collect()
    }
}
