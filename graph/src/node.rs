//! A pass as the graph keeps it once added: the instance, its bound slots and, for a
//! choice, the implementations compile may keep instead. The builder makes nodes;
//! compile and the executor read them, so the type sits below all three.

use crate::choice::Choice;
use crate::contract::{Slot, StageContract};
use crate::pass::Pass;
use crate::resource::{AnyHandle, TextureRange};

/// A pass as the graph keeps it: its instance name, implementation and bound slots.
pub(crate) struct PassNode {
    pub name: String,
    pub pass: Box<dyn Pass>,
    /// The stage contract with unbound optional slots removed.
    pub contract: StageContract,
    /// Every slot of the stage, bound or not.
    pub stage_slots: Vec<&'static str>,
    /// In contract slot order.
    pub bindings: Vec<AnyHandle>,
    /// Per slot, the texture range it binds (`None`: the whole resource).
    pub ranges: Vec<Option<TextureRange>>,
    /// (frame input the pass reads, the frame input supplied for it): see
    /// `Bindings::input`.
    pub inputs: Vec<(String, String)>,
    /// The stage's other implementations, when the pass was added as a [`Choice`]:
    /// compile keeps `pass` or one of these.
    pub(crate) alternatives: Option<Choice>,
}

impl PassNode {
    /// The frame input supplied for the pass's input `read`.
    pub fn supplied_input<'a>(&'a self, read: &'a str) -> &'a str {
        self.inputs
            .iter()
            .find(|(r, _)| r == read)
            .map_or(read, |(_, s)| s.as_str())
    }

    /// Each bound slot with the resource version it binds, in contract order: what most
    /// compile steps walk.
    pub fn bound_slots(&self) -> impl Iterator<Item = (&Slot, &AnyHandle)> {
        self.contract.slots.iter().zip(&self.bindings)
    }
}
