//! Which culling pass of the frame a pass is: two-pass occlusion culling
//! (docs/ARCHITECTURE.md, "Two-pass occlusion culling") runs the walk and the cluster
//! test twice, and both stages name the pass the same way.

use meshlight_graph::file::Params;
use meshlight_graph::{GraphError, Result};

/// The first or the second culling pass of a frame.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Phase {
    /// Every candidate; with a pyramid bound (last frame's), what it hides is set aside
    /// for the second pass.
    #[default]
    First,
    /// What the first pass set aside, against this frame's pyramid.
    Second,
}

impl Phase {
    /// The name a pipeline file gives it: `"first"` or `"second"`.
    pub fn name(self) -> &'static str {
        match self {
            Phase::First => "first",
            Phase::Second => "second",
        }
    }

    /// The `mode` param of a pass's table, `"first"` when absent.
    pub fn from_params(params: &Params) -> Result<Self> {
        match params.string("mode", "first")?.as_str() {
            "first" => Ok(Phase::First),
            "second" => Ok(Phase::Second),
            other => Err(GraphError::parameter(format!(
                "`mode` = \"{other}\" is not a mode; use \"first\" or \"second\""
            ))),
        }
    }
}
