//! A drawing of the plan as SVG, laid out here without a layout engine: each pass sits on
//! the row after the deepest pass it depends on, so every dependency points downwards and
//! the frame reads from top to bottom. Boxes are as wide as their text; an edge between
//! neighbouring rows crosses only the gap between them, one that skips rows runs down a
//! lane between the columns, so no edge crosses a box. Passes are coloured by batch,
//! skipped ones grey, culled ones dashed. The HTML page embeds it; `meshlight graph
//! --format svg` writes it alone.

use crate::plan::{EdgeKind, Plan, Recording};
use std::collections::BTreeMap;
use std::fmt::Write;

const BOX_H: u32 = 38;
/// The narrowest box; wider ones are as wide as their text.
const MIN_BOX_W: u32 = 120;
/// Space between the columns when no edge runs down between them.
const GAP_X: u32 = 24;
const GAP_Y: u32 = 34;
const MARGIN: u32 = 16;
/// Room between the vertical lanes of the edges that run down beside the boxes.
const LANE_STEP: u32 = 6;
/// Top band for the legend: two lines.
const LEGEND_H: u32 = 40;
/// The legend's lines fit in this width.
const MIN_WIDTH: u32 = 560;
/// Fills by batch, cycled: neighbouring batches always differ.
const BATCH_FILLS: [&str; 6] = [
    "#dbe8fb", "#e3f4dc", "#fbeed8", "#efe1f7", "#d9f2f2", "#f8dede",
];
/// A pass the adapter's class skips: in its batch, recording nothing.
const SKIPPED_FILL: &str = "#eeeeee";

/// Where one pass is drawn.
struct Node {
    pass: usize,
    rank: u32,
    column: u32,
    width: u32,
}

fn esc(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

/// How wide a line of `text` is drawn at `size` px, with room to spare: proportional
/// sans-serif glyphs average about half an em, bold ones a little more, and no font is
/// embedded, so this errs wide (0.62 em a character).
fn text_width(text: &str, size: u32) -> u32 {
    (text.chars().count() as u32 * size * 62).div_ceil(100)
}

/// A pass's three labels: its name, its stage and implementation, its batch.
fn labels(plan: &Plan, pass: usize) -> (String, String, String) {
    let p = &plan.passes[pass];
    let batch = plan
        .batch_of(pass)
        .map_or("culled".to_string(), |b| format!("b{b}"));
    (
        p.name.clone(),
        format!("{} / {}", p.stage, p.implementation_label()),
        batch,
    )
}

fn layout(plan: &Plan) -> Vec<Node> {
    let rank = super::pass_ranks(plan);
    let drawn = plan.order.iter().chain(&plan.culled).copied();
    let mut next_column: BTreeMap<u32, u32> = BTreeMap::new();
    drawn
        .map(|pass| {
            let column = next_column.entry(rank[pass]).or_insert(0);
            *column += 1;
            let (name, label, batch) = labels(plan, pass);
            // The name and the batch share the top line; the label has the second.
            let width = (text_width(&name, 12) + text_width(&batch, 10) + 22)
                .max(text_width(&label, 10) + 14)
                .max(MIN_BOX_W);
            Node {
                pass,
                rank: rank[pass],
                column: *column - 1,
                width,
            }
        })
        .collect()
}

/// An edge that skips a row runs down a lane between two columns (or beside the outer
/// ones), where no box stands: channel `k` lies left of column `k`, channel `columns`
/// right of the last. Between neighbouring rows an edge crosses only the gap.
struct Lane {
    channel: usize,
    /// Its place among the lanes of its channel.
    index: u32,
}

fn channel_for(from_column: u32, to_column: u32) -> usize {
    if from_column == to_column {
        from_column as usize + 1
    } else {
        // A boundary between the two columns, the middle one.
        (from_column + to_column + 1).div_ceil(2) as usize
    }
}

/// The plan drawn as one SVG document: a box per pass (name, stage and implementation,
/// batch), an arrow per dependency (hover one for the resources it carries).
pub fn to_svg(plan: &Plan) -> String {
    let nodes = layout(plan);
    let columns = nodes.iter().map(|n| n.column + 1).max().unwrap_or(1) as usize;
    let rows = nodes.iter().map(|n| n.rank + 1).max().unwrap_or(1);
    let node_of: BTreeMap<usize, &Node> = nodes.iter().map(|n| (n.pass, n)).collect();

    // One arrow per pair of passes, with the resources it carries.
    let mut carried: BTreeMap<(usize, usize), (Vec<String>, bool)> = BTreeMap::new();
    for e in &plan.edges {
        if !(node_of.contains_key(&e.from) && node_of.contains_key(&e.to)) {
            continue;
        }
        let entry = carried.entry((e.from, e.to)).or_default();
        entry.0.push(format!(
            "{}@{}",
            plan.resources[e.resource].info.name, e.version
        ));
        entry.1 |= e.kind == EdgeKind::ReadAfterWrite;
    }
    // Lanes for the edges that skip rows, then the channels wide enough to hold them.
    let mut lanes: BTreeMap<(usize, usize), Lane> = BTreeMap::new();
    let mut per_channel = vec![0u32; columns + 1];
    for &(from, to) in carried.keys() {
        let (a, b) = (node_of[&from], node_of[&to]);
        if b.rank > a.rank + 1 {
            let channel = channel_for(a.column, b.column);
            lanes.insert(
                (from, to),
                Lane {
                    channel,
                    index: per_channel[channel],
                },
            );
            per_channel[channel] += 1;
        }
    }
    let channel_w: Vec<u32> = per_channel
        .iter()
        .enumerate()
        .map(|(k, &n)| {
            let lanes = if n == 0 { 0 } else { (n + 1) * LANE_STEP };
            let between = if k == 0 || k == columns { 0 } else { GAP_X };
            lanes.max(between)
        })
        .collect();
    let mut column_w = vec![MIN_BOX_W; columns];
    for n in &nodes {
        column_w[n.column as usize] = column_w[n.column as usize].max(n.width);
    }
    let mut column_x = Vec::with_capacity(columns + 1);
    let mut x = MARGIN;
    for c in 0..columns {
        x += channel_w[c];
        column_x.push(x);
        x += column_w[c];
    }
    // Where the channel right of the last column starts.
    column_x.push(x);
    let lane_x = |lane: &Lane| {
        let right = if lane.channel < columns {
            column_x[lane.channel]
        } else {
            column_x[columns] + channel_w[columns]
        };
        right - channel_w[lane.channel] + (lane.index + 1) * LANE_STEP
    };
    let row_y = |rank: u32| MARGIN + LEGEND_H + rank * (BOX_H + GAP_Y);
    let box_at = |n: &Node| {
        let c = n.column as usize;
        (column_x[c] + (column_w[c] - n.width) / 2, row_y(n.rank))
    };

    let width = (column_x[columns] + channel_w[columns] + MARGIN).max(MIN_WIDTH);
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
        "<text x=\"{MARGIN}\" y=\"{}\" fill=\"#555\">{} passes in {} batches; fill: batch, thick border: on the encoder, grey: skipped, dashed: culled</text>",
        MARGIN + 12,
        plan.order.len(),
        plan.batches.len()
    );
    let _ = writeln!(
        s,
        "<text x=\"{MARGIN}\" y=\"{}\" fill=\"#555\">arrows: read after write; dashed: write after read (hover: resources)</text>",
        MARGIN + 28,
    );
    // Arrows first, so boxes cover their ends.
    for ((from, to), (resources, raw)) in &carried {
        let (a, b) = (node_of[from], node_of[to]);
        let ((ax, ay), (bx, by)) = (box_at(a), box_at(b));
        let (x0, y0) = (ax + a.width / 2, ay + BOX_H);
        let (x1, y1) = (bx + b.width / 2, by);
        let d = match lanes.get(&(*from, *to)) {
            // Down into the gap below its row, across to the lane, down the lane to the
            // gap above the target's row, across, and down into the box. Lanes of one
            // channel cross their gaps at different heights.
            Some(lane) => {
                let step = (lane.index % 5) * 3;
                let below = y0 + GAP_Y / 2 - 6 + step;
                let above = y1 - GAP_Y / 2 - 6 + step;
                format!("M{x0},{y0} V{below} H{} V{above} H{x1} V{y1}", lane_x(lane))
            }
            // Neighbouring rows: a curve that stays inside the gap between them.
            None => {
                let bend = (y1.saturating_sub(y0) / 2).max(12);
                format!(
                    "M{x0},{y0} C{x0},{} {x1},{} {x1},{y1}",
                    y0 + bend,
                    y1.saturating_sub(bend)
                )
            }
        };
        let dash = if *raw {
            ""
        } else {
            " stroke-dasharray=\"4 3\""
        };
        let _ = writeln!(
            s,
            "<path d=\"{d}\" fill=\"none\" stroke=\"#888\"{dash} marker-end=\"url(#arrow)\"><title>{} → {}: {}</title></path>",
            esc(&plan.passes[*from].name),
            esc(&plan.passes[*to].name),
            esc(&resources.join(", "))
        );
    }
    for n in &nodes {
        let pass = &plan.passes[n.pass];
        let (x, y) = box_at(n);
        let w = n.width;
        let (name, label, batch_label) = labels(plan, n.pass);
        let batch = plan.batch_of(n.pass);
        let culled = batch.is_none();
        let skipped = pass.skipped.is_some() && !culled;
        let fill = match batch {
            None => "#f2f2f2",
            Some(_) if skipped => SKIPPED_FILL,
            Some(b) => BATCH_FILLS[b % BATCH_FILLS.len()],
        };
        let encoder = matches!(pass.recording, Recording::Encoder(_)) && !culled && !skipped;
        let stroke = if culled {
            " stroke=\"#aaa\" stroke-dasharray=\"5 3\""
        } else if encoder {
            " stroke=\"#333\" stroke-width=\"2.5\""
        } else if skipped {
            " stroke=\"#aaa\""
        } else {
            " stroke=\"#777\""
        };
        let text = if culled || skipped { "#999" } else { "#222" };
        let class = if culled {
            " culled"
        } else if skipped {
            " skipped"
        } else {
            ""
        };
        let _ = writeln!(
            s,
            "<g class=\"pass{class}\" data-pass=\"{}\" data-rank=\"{}\"><rect x=\"{x}\" y=\"{y}\" width=\"{w}\" height=\"{BOX_H}\" rx=\"5\" fill=\"{fill}\"{stroke}/><text x=\"{}\" y=\"{}\" fill=\"{text}\" font-weight=\"600\">{}</text><text x=\"{}\" y=\"{}\" fill=\"{text}\" font-size=\"10\">{}</text><text x=\"{}\" y=\"{}\" fill=\"#777\" font-size=\"10\" text-anchor=\"end\">{}</text></g>",
            esc(&name),
            n.rank,
            x + 7,
            y + 15,
            esc(&name),
            x + 7,
            y + 30,
            esc(&label),
            x + w - 6,
            y + 15,
            batch_label,
        );
    }
    s.push_str("</svg>\n");
    s
}
