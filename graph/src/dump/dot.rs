//! Graphviz DOT: passes as boxes, resource versions as ellipses, edges labelled with the
//! access; culled passes greyed, history resources double-ringed, imports bold; each of
//! the plan's batches a cluster around its passes (compute batches shaded).

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
    let mut out = String::from(
        "digraph meshlight {\n  rankdir=LR;\n  node [fontname=\"Helvetica\", fontsize=11];\n  edge [fontname=\"Helvetica\", fontsize=9];\n",
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
        let why = p
            .choice_reason()
            .map(|r| format!("\nchosen: {r}"))
            .unwrap_or_default();
        let encoder = match &p.recording {
            crate::plan::Recording::Encoder(why) if !culled => format!("\nencoder: {why}"),
            _ => String::new(),
        };
        let label = format!(
            "{order}{}\n{}/{}{why}{programs}{encoder}{}",
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
        let _ = writeln!(out, "  p{i} [shape=box, label=\"{}\"{style}];", esc(&label));
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
        for s in &p.slots {
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
