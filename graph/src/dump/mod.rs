//! Deterministic dumps of a compiled plan: DOT, JSON, Mermaid, an SVG drawing and a
//! self-contained HTML page, and a frame's GPU timings as a Chrome trace. Everything
//! iterates in plan order, so equal plans give equal bytes.

mod dot;
mod html;
mod mermaid;
mod svg;
mod trace;

pub use dot::to_dot;
pub use html::{Report, to_html, to_html_report};
pub use mermaid::to_mermaid;
pub use svg::to_svg;
pub use trace::to_chrome_trace;

use crate::exec::FrameStats;
use crate::plan::Plan;
use crate::resource::ResourceKind;
use serde::Serialize;

#[derive(Serialize)]
struct JsonDump<'a> {
    plan: &'a Plan,
    last_frame: Option<&'a FrameStats>,
}

/// The plan (order, culled passes, lifetimes, pool slots, usages) and the last frame's timings.
pub fn to_json(plan: &Plan, last_frame: Option<&FrameStats>) -> String {
    serde_json::to_string_pretty(&JsonDump { plan, last_frame })
        .expect("plan serialises: no maps with non-string keys")
}

/// A node for one version of a resource, as read or written by some pass.
pub(crate) fn version_nodes(plan: &Plan) -> Vec<(usize, u32)> {
    let mut v: Vec<(usize, u32)> = Vec::new();
    for p in &plan.passes {
        for s in &p.slots {
            if s.reads() {
                v.push((s.resource, s.version));
            }
            if let Some(w) = s.writes_version {
                v.push((s.resource, w));
            }
        }
    }
    v.sort();
    v.dedup();
    v
}

pub(crate) fn kind_tag(kind: &ResourceKind) -> &'static str {
    match kind {
        ResourceKind::Transient => "transient",
        ResourceKind::Imported { .. } => "imported",
        ResourceKind::History { .. } => "history",
        ResourceKind::HistoryPrev { .. } => "history (prev)",
        ResourceKind::Exported => "exported",
        ResourceKind::Scratch { .. } => "scratch",
    }
}

/// Rank (row) of each pass, for the drawings: 0 for a pass that depends on none, else one past the deepest pass
/// it depends on. Culled passes take part, so they sit beside what they would have read.
pub(crate) fn pass_ranks(plan: &Plan) -> Vec<u32> {
    let mut rank = vec![0u32; plan.passes.len()];
    // Edges go from earlier to later passes of a valid plan: relaxing them as often as
    // there are passes settles every chain.
    for _ in 0..plan.passes.len() {
        let mut changed = false;
        for e in &plan.edges {
            if e.from != e.to && rank[e.to] <= rank[e.from] {
                rank[e.to] = rank[e.from] + 1;
                changed = true;
            }
        }
        if !changed {
            break;
        }
    }
    rank
}
