//! A drawing of the plan as SVG, laid out here without a layout engine: each pass sits on
//! the row after the deepest pass it depends on, so every dependency points downwards and
//! the frame reads from top to bottom. Passes are coloured by batch; culled passes are
//! dashed. The HTML page embeds it; `meshlight graph --format svg` writes it alone.

use crate::plan::{EdgeKind, Plan, Recording};
use std::collections::BTreeMap;
use std::fmt::Write;

const BOX_W: u32 = 190;
const BOX_H: u32 = 38;
const GAP_X: u32 = 24;
const GAP_Y: u32 = 34;
const MARGIN: u32 = 16;
/// Top band for the legend: two lines.
const LEGEND_H: u32 = 40;
/// The legend's lines fit in this width.
const MIN_WIDTH: u32 = 520;
/// Fills by batch, cycled: neighbouring batches always differ.
const BATCH_FILLS: [&str; 6] = [
    "#dbe8fb", "#e3f4dc", "#fbeed8", "#efe1f7", "#d9f2f2", "#f8dede",
];

/// Where one pass is drawn.
struct Node {
    pass: usize,
    rank: u32,
    column: u32,
}

fn esc(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

fn layout(plan: &Plan) -> Vec<Node> {
    let rank = super::pass_ranks(plan);
    let drawn = plan.order.iter().chain(&plan.culled).copied();
    let mut next_column: BTreeMap<u32, u32> = BTreeMap::new();
    drawn
        .map(|pass| {
            let column = next_column.entry(rank[pass]).or_insert(0);
            *column += 1;
            Node {
                pass,
                rank: rank[pass],
                column: *column - 1,
            }
        })
        .collect()
}

/// The plan drawn as one SVG document: a box per pass (name, stage and implementation,
/// batch), an arrow per dependency (hover one for the resources it carries).
pub fn to_svg(plan: &Plan) -> String {
    let nodes = layout(plan);
    let at: BTreeMap<usize, (u32, u32)> = nodes
        .iter()
        .map(|n| {
            let x = MARGIN + n.column * (BOX_W + GAP_X);
            let y = MARGIN + LEGEND_H + n.rank * (BOX_H + GAP_Y);
            (n.pass, (x, y))
        })
        .collect();
    let columns = nodes.iter().map(|n| n.column + 1).max().unwrap_or(1);
    let rows = nodes.iter().map(|n| n.rank + 1).max().unwrap_or(1);
    let width = (2 * MARGIN + columns * (BOX_W + GAP_X) - GAP_X).max(MIN_WIDTH);
    let height = 2 * MARGIN + LEGEND_H + rows * (BOX_H + GAP_Y) - GAP_Y;
    let mut s = String::new();
    let _ = writeln!(
        s,
        "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{width}\" height=\"{height}\" viewBox=\"0 0 {width} {height}\" font-family=\"system-ui,sans-serif\" font-size=\"12\">"
    );
    s.push_str(
        "<defs><marker id=\"arrow\" viewBox=\"0 0 10 10\" refX=\"9\" refY=\"5\" markerWidth=\"7\" markerHeight=\"7\" orient=\"auto-start-reverse\"><path d=\"M0,0 L10,5 L0,10 z\" fill=\"#666\"/></marker></defs>\n",
    );
    let _ = writeln!(
        s,
        "<text x=\"{MARGIN}\" y=\"{}\" fill=\"#555\">{} passes in {} batches; fill: batch, thick border: on the encoder, dashed: culled</text>",
        MARGIN + 12,
        plan.order.len(),
        plan.batches.len()
    );
    let _ = writeln!(
        s,
        "<text x=\"{MARGIN}\" y=\"{}\" fill=\"#555\">arrows: read after write; dashed: write after read (hover: resources)</text>",
        MARGIN + 28,
    );
    // Arrows first, so boxes cover their ends; one per pair of passes.
    let mut carried: BTreeMap<(usize, usize), (Vec<String>, bool)> = BTreeMap::new();
    for e in &plan.edges {
        let entry = carried.entry((e.from, e.to)).or_default();
        entry.0.push(format!(
            "{}@{}",
            plan.resources[e.resource].info.name, e.version
        ));
        entry.1 |= e.kind == EdgeKind::ReadAfterWrite;
    }
    for ((from, to), (resources, raw)) in &carried {
        let (Some(&(x0, y0)), Some(&(x1, y1))) = (at.get(from), at.get(to)) else {
            continue;
        };
        let (x0, y0) = (x0 + BOX_W / 2, y0 + BOX_H);
        let (x1, y1) = (x1 + BOX_W / 2, y1);
        let bend = (y1.saturating_sub(y0) / 2).max(12);
        let dash = if *raw {
            ""
        } else {
            " stroke-dasharray=\"4 3\""
        };
        let _ = writeln!(
            s,
            "<path d=\"M{x0},{y0} C{x0},{} {x1},{} {x1},{y1}\" fill=\"none\" stroke=\"#888\"{dash} marker-end=\"url(#arrow)\"><title>{} → {}: {}</title></path>",
            y0 + bend,
            y1.saturating_sub(bend),
            esc(&plan.passes[*from].name),
            esc(&plan.passes[*to].name),
            esc(&resources.join(", "))
        );
    }
    for n in &nodes {
        let pass = &plan.passes[n.pass];
        let (x, y) = at[&n.pass];
        let batch = plan.batch_of(n.pass);
        let culled = batch.is_none();
        let fill = batch.map_or("#f2f2f2", |b| BATCH_FILLS[b % BATCH_FILLS.len()]);
        let encoder = matches!(pass.recording, Recording::Encoder(_)) && !culled;
        let stroke = if culled {
            " stroke=\"#aaa\" stroke-dasharray=\"5 3\""
        } else if encoder {
            " stroke=\"#333\" stroke-width=\"2.5\""
        } else {
            " stroke=\"#777\""
        };
        let text = if culled { "#999" } else { "#222" };
        let _ = writeln!(
            s,
            "<g class=\"pass{}\" data-pass=\"{}\" data-rank=\"{}\"><rect x=\"{x}\" y=\"{y}\" width=\"{BOX_W}\" height=\"{BOX_H}\" rx=\"5\" fill=\"{fill}\"{stroke}/><text x=\"{}\" y=\"{}\" fill=\"{text}\" font-weight=\"600\">{}</text><text x=\"{}\" y=\"{}\" fill=\"{text}\" font-size=\"10\">{} / {}</text><text x=\"{}\" y=\"{}\" fill=\"#777\" font-size=\"10\" text-anchor=\"end\">{}</text></g>",
            if culled { " culled" } else { "" },
            esc(&pass.name),
            n.rank,
            x + 7,
            y + 15,
            esc(&pass.name),
            x + 7,
            y + 30,
            esc(pass.stage),
            esc(&pass.implementation_label()),
            x + BOX_W - 6,
            y + 15,
            batch.map_or("culled".to_string(), |b| format!("b{b}")),
        );
    }
    s.push_str("</svg>\n");
    s
}
