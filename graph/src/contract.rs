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
    Buffer { element: Option<Element> },
    /// A texture; when `format` is set, the bound texture must have it.
    Texture {
        #[serde(serialize_with = "crate::plan::ser_opt_format")]
        format: Option<wgpu::TextureFormat>,
    },
}

#[derive(Clone, Debug, Serialize)]
pub struct Slot {
    pub name: &'static str,
    pub access: Access,
    pub kind: SlotKind,
    /// One line for dumps and error messages.
    pub doc: &'static str,
    /// An optional slot may stay unbound; the pass checks `RecordContext::is_bound`.
    pub optional: bool,
}

impl Slot {
    pub fn buffer(name: &'static str, access: Access, element: Element, doc: &'static str) -> Self {
        Self {
            name,
            access,
            kind: SlotKind::Buffer {
                element: Some(element),
            },
            doc,
            optional: false,
        }
    }
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
            doc,
            optional: false,
        }
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
    pub stage: &'static str,
    pub slots: Vec<Slot>,
}

impl StageContract {
    pub fn slot(&self, name: &str) -> Option<&Slot> {
        self.slots.iter().find(|s| s.name == name)
    }
    pub fn slot_names(&self) -> Vec<&'static str> {
        self.slots.iter().map(|s| s.name).collect()
    }
}
