//! Mermaid flowchart of the same graph as the DOT dump, each batch a subgraph.

use super::{kind_tag, version_nodes};
use crate::plan::Plan;
use std::fmt::Write;

fn esc(s: &str) -> String {
    s.replace('"', "#quot;")
        .replace('<', "#lt;")
        .replace('>', "#gt;")
}

/// The plan as a Mermaid flowchart, for Markdown that renders it.
pub fn to_mermaid(plan: &Plan) -> String {
    let mut out = String::from("flowchart LR\n");
    for (i, p) in plan.passes.iter().enumerate() {
        let culled = if plan.is_culled(i) { " (culled)" } else { "" };
        let _ = writeln!(
            out,
            "  p{i}[\"{}<br/>{}/{}{culled}\"]",
            esc(&p.name),
            esc(p.stage),
            esc(&p.implementation_label())
        );
    }
    for (b, batch) in plan.batches.iter().enumerate() {
        let _ = writeln!(out, "  subgraph batch{b} [\"{}\"]", esc(&batch.label(b)));
        for p in &batch.passes {
            let _ = writeln!(out, "    p{p}");
        }
        out.push_str("  end\n");
    }
    for (r, v) in version_nodes(plan) {
        let res = &plan.resources[r];
        let _ = writeln!(
            out,
            "  r{r}v{v}([\"{} v{v}<br/>{}\"])",
            esc(&res.info.name),
            kind_tag(&res.info.kind)
        );
    }
    for (i, p) in plan.passes.iter().enumerate() {
        for s in &p.slots {
            let label = esc(&format!("{}: {}", s.slot, s.access_name()));
            if s.reads() {
                let _ = writeln!(out, "  r{}v{} -->|\"{label}\"| p{i}", s.resource, s.version);
            }
            if let Some(w) = s.writes_version {
                let _ = writeln!(out, "  p{i} -->|\"{label}\"| r{}v{w}", s.resource);
            }
        }
    }
    out.push_str("  classDef culled fill:#eee,stroke:#999,color:#999,stroke-dasharray: 4 3\n");
    for &c in &plan.culled {
        let _ = writeln!(out, "  class p{c} culled");
    }
    out
}
