//! Graphviz DOT: passes as boxes, resource versions as ellipses, edges labelled with the
//! access; culled passes greyed, history resources double-ringed, imports bold; each of
//! the plan's batches a cluster around its passes (compute batches shaded).
//!
//! Laid out top to bottom with each pass ranked one below the deepest pass it depends on
//! (the rows of the SVG drawing), so a pipeline reads as a column of stages rather than
//! one long line; why an implementation was chosen is each box's tooltip, not its label,
//! so boxes stay narrow. Imports no pass writes (the scene's buffers, read by half the
//! passes) are listed in each reader's box instead of drawn once with an edge to every
//! reader, which would cross the whole drawing.

use super::{kind_tag, version_nodes};
use crate::plan::Plan;
use crate::resource::ResourceKind;
use std::fmt::Write;

fn esc(s: &str) -> String {
    s.replace('\\', "\\\\")
        .replace('"', "\\\"")
        .replace('\n', "\\n")
}

/// The plan as a Graphviz DOT graph: passes, resources and their versions, edges by kind.
pub fn to_dot(plan: &Plan) -> String {
    // Imports that no pass writes: named in their readers' boxes, not drawn as nodes.
    let mut listed: Vec<bool> = plan
        .resources
        .iter()
        .map(|r| matches!(r.info.kind, ResourceKind::Imported { .. }))
        .collect();
    for s in plan.passes.iter().flat_map(|p| &p.slots) {
        if s.writes_version.is_some() {
            listed[s.resource] = false;
        }
    }
    let mut out = String::from(
        "digraph meshlight {\n  rankdir=TB;\n  newrank=true;\n  node [fontname=\"Helvetica\", fontsize=11];\n  edge [fontname=\"Helvetica\", fontsize=9];\n",
    );
    for (i, p) in plan.passes.iter().enumerate() {
        let culled = plan.is_culled(i);
        let order = plan
            .order
            .iter()
            .position(|&o| o == i)
            .map(|o| format!("#{o} "))
            .unwrap_or_default();
        let programs = if p.programs.is_empty() {
            String::new()
        } else {
            let names: Vec<&str> = p.programs.iter().map(|x| x.name.as_str()).collect();
            format!("\nprograms: {}", names.join(", "))
        };
        let tooltip = p
            .decision()
            .map(|r| format!(", tooltip=\"{}\"", esc(&r)))
            .unwrap_or_default();
        let mut inputs: Vec<&str> = p
            .slots
            .iter()
            .filter(|s| listed[s.resource])
            .map(|s| plan.resources[s.resource].info.name.as_str())
            .collect();
        inputs.sort_unstable();
        inputs.dedup();
        let inputs = if inputs.is_empty() {
            String::new()
        } else {
            format!("\nimports: {}", inputs.join(", "))
        };
        let encoder = match &p.recording {
            crate::plan::Recording::Encoder(why) if !culled => format!("\nencoder: {why}"),
            _ => String::new(),
        };
        let label = format!(
            "{order}{}\n{}/{}{programs}{inputs}{encoder}{}",
            p.name,
            p.stage,
            p.implementation_label(),
            if culled { "\n(culled)" } else { "" }
        );
        let style = if culled {
            ", style=\"filled,dashed\", fillcolor=\"#eeeeee\", fontcolor=\"#999999\", color=\"#999999\""
        } else {
            ", style=filled, fillcolor=\"#dde8f7\""
        };
        let _ = writeln!(
            out,
            "  p{i} [shape=box, label=\"{}\"{style}{tooltip}];",
            esc(&label)
        );
    }
    let ranks = super::pass_ranks(plan);
    for rank in 0..=ranks.iter().copied().max().unwrap_or(0) {
        let same: Vec<String> = (0..plan.passes.len())
            .filter(|&i| ranks[i] == rank)
            .map(|i| format!("p{i};"))
            .collect();
        if same.len() > 1 {
            let _ = writeln!(out, "  {{ rank=same; {} }}", same.join(" "));
        }
    }
    for (b, batch) in plan.batches.iter().enumerate() {
        let style = if batch.compute {
            "style=\"rounded,filled\"; fillcolor=\"#f3f7ee\"; color=\"#6a9a3a\""
        } else {
            "style=\"rounded,dashed\"; color=\"#999999\""
        };
        let members: Vec<String> = batch.passes.iter().map(|p| format!("p{p};")).collect();
        let _ = writeln!(
            out,
            "  subgraph cluster_batch{b} {{ label=\"{}\"; {style}; {} }}",
            esc(&batch.label(b)),
            members.join(" ")
        );
    }
    for (r, v) in version_nodes(plan) {
        if listed[r] {
            continue;
        }
        let res = &plan.resources[r];
        let style = match res.info.kind {
            ResourceKind::History { .. } | ResourceKind::HistoryPrev { .. } => {
                ", peripheries=2, color=\"#b5651d\""
            }
            ResourceKind::Imported { .. } => ", style=bold",
            ResourceKind::Exported => ", style=bold, color=\"#2e7d32\"",
            _ => "",
        };
        let label = format!("{} v{v}\n{}", res.info.name, kind_tag(&res.info.kind));
        let _ = writeln!(
            out,
            "  r{r}v{v} [shape=ellipse, label=\"{}\"{style}];",
            esc(&label)
        );
    }
    for (i, p) in plan.passes.iter().enumerate() {
        for s in p.slots.iter().filter(|s| !listed[s.resource]) {
            let label = esc(&format!("{}: {}", s.slot, s.access_name()));
            if s.reads() {
                let _ = writeln!(
                    out,
                    "  r{}v{} -> p{i} [label=\"{label}\"];",
                    s.resource, s.version
                );
            }
            if let Some(w) = s.writes_version {
                let _ = writeln!(out, "  p{i} -> r{}v{w} [label=\"{label}\"];", s.resource);
            }
        }
    }
    out.push_str("}\n");
    out
}
