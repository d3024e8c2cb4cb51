//! One self-contained HTML page (no scripts, no network): the frame's GPU time and image
//! when given, a drawing of the graph, the batches and the pass order with GPU time bars
//! (per batch in `frame` timing mode, per pass in `passes` mode, the mode named), and the
//! resource-lifetime chart (rows = resources, columns = passes).

use super::kind_tag;
use crate::exec::FrameStats;
use crate::plan::Plan;
use std::fmt::Write;

fn esc(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

fn bytes(b: u64) -> String {
    match b {
        b if b >= 1 << 30 => format!("{:.2} GiB", b as f64 / (1u64 << 30) as f64),
        b if b >= 1 << 20 => format!("{:.2} MiB", b as f64 / (1u64 << 20) as f64),
        b if b >= 1 << 10 => format!("{:.1} KiB", b as f64 / 1024.0),
        b => format!("{b} B"),
    }
}

/// What a report shows besides the plan.
#[derive(Clone, Copy, Debug, Default)]
pub struct Report<'a> {
    /// The last frame's timings: GPU times per batch or pass, the frame's total.
    pub last_frame: Option<&'a FrameStats>,
    /// The image the frame made, as the page links it (a path relative to the page).
    pub image: Option<&'a str>,
    /// Figures of the frame the graph does not know (e.g. a renderer's streaming), as
    /// (label, value) rows of a table under the image.
    pub facts: &'a [(String, String)],
}

/// The plan as one self-contained HTML page (graph, batches, passes, resources, pool
/// slots), with the last frame's timings when given.
pub fn to_html(plan: &Plan, title: &str, last_frame: Option<&FrameStats>) -> String {
    to_html_report(
        plan,
        title,
        &Report {
            last_frame,
            image: None,
            facts: &[],
        },
    )
}

/// [`to_html`] with everything a [`Report`] adds: the image above the graph.
pub fn to_html_report(plan: &Plan, title: &str, report: &Report) -> String {
    let last_frame = report.last_frame;
    let mut h = String::new();
    let _ = write!(
        h,
        "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"><title>{t}</title>\n<style>\n\
body{{font:14px/1.4 system-ui,sans-serif;margin:2em;color:#222}}\n\
table{{border-collapse:collapse;margin:1em 0}}td,th{{padding:3px 8px;border:1px solid #ddd;text-align:left}}\n\
.bar{{background:#4a78c2;height:12px}}.life{{background:#7bb274}}.slot{{color:#666;font-size:12px}}\n\
.culled{{color:#999;text-decoration:line-through}}th.v{{writing-mode:vertical-rl;font-weight:normal}}\n\
</style></head><body>\n<h1>{t}</h1>\n",
        t = esc(title)
    );
    let _ = writeln!(
        h,
        "<p>{} passes run, {} culled; transient memory {} with slot reuse, {} without.</p>",
        plan.order.len(),
        plan.culled.len(),
        bytes(plan.bytes_with_reuse),
        bytes(plan.bytes_without_reuse)
    );

    if let Some(frame) = last_frame {
        let gpu = frame
            .gpu_frame_us
            .map(|us| {
                format!(
                    "<b>{:.3} ms</b> on the GPU ({})",
                    us / 1000.0,
                    esc(frame.timing.name())
                )
            })
            .unwrap_or_else(|| "no GPU time (timing off or not back yet)".into());
        let _ = writeln!(
            h,
            "<p class=\"total\">Frame {}: {gpu}, {:.3} ms of CPU recording and submission.</p>",
            frame.frame,
            frame.cpu_frame_us / 1000.0
        );
    }
    if let Some(image) = report.image {
        let _ = writeln!(
            h,
            "<p><img src=\"{}\" alt=\"the frame's image\" style=\"max-width:100%\"></p>",
            esc(image)
        );
    }
    if !report.facts.is_empty() {
        h.push_str("<table>\n");
        for (label, value) in report.facts {
            let _ = writeln!(h, "<tr><th>{}</th><td>{}</td></tr>", esc(label), esc(value));
        }
        h.push_str("</table>\n");
    }
    h.push_str("<h2>Graph</h2>\n");
    // Inline SVG in HTML needs no namespace, and the page names no address.
    h.push_str(&super::to_svg(plan).replacen(" xmlns=\"http://www.w3.org/2000/svg\"", "", 1));
    batches(&mut h, plan, last_frame);
    h.push_str("<h2>Pass order</h2>\n<table><tr><th>#</th><th>batch</th><th>pass</th><th>stage / implementation</th><th>GPU µs</th><th></th><th>CPU record µs</th><th>programs (kind, entries, defs)</th></tr>\n");
    let max_gpu = last_frame
        .map(|f| f.passes.iter().filter_map(|p| p.gpu_us).fold(0.0, f64::max))
        .unwrap_or(0.0);
    for (o, &p) in plan.order.iter().enumerate() {
        let pass = &plan.passes[p];
        let timing = last_frame.and_then(|f| f.passes.iter().find(|t| t.name == pass.name));
        let gpu = timing.and_then(|t| t.gpu_us);
        let width = match gpu {
            Some(g) if max_gpu > 0.0 => (g / max_gpu * 300.0).round() as u32,
            _ => 0,
        };
        let _ = writeln!(
            h,
            "<tr><td>{o}</td><td>{}</td><td>{}</td><td>{} / {}{}</td><td>{}</td><td><div class=\"bar\" style=\"width:{width}px\"></div></td><td>{}</td><td>{}</td></tr>",
            plan.batch_of(p).map(|b| b.to_string()).unwrap_or_default(),
            esc(&pass.name),
            esc(pass.stage),
            esc(&pass.implementation_label()),
            pass.decision()
                .map(|r| format!("<br><small>{}</small>", esc(&r)))
                .unwrap_or_default(),
            gpu.map(|g| format!("{g:.1}")).unwrap_or_else(|| "–".into()),
            timing
                .map(|t| format!("{:.1}", t.cpu_record_us))
                .unwrap_or_else(|| "–".into()),
            pass.programs
                .iter()
                .map(|p| esc(&format!(
                    "{}: {} {}::{} [{}]",
                    p.name,
                    p.kind,
                    p.shader,
                    p.entries.join("+"),
                    p.defs
                        .iter()
                        .map(|(n, v)| format!("{n}={v}"))
                        .collect::<Vec<_>>()
                        .join(" ")
                )))
                .collect::<Vec<_>>()
                .join("<br>"),
        );
    }
    for &p in &plan.culled {
        let _ = writeln!(
            h,
            "<tr class=\"culled\"><td></td><td></td><td>{}</td><td colspan=\"6\">culled: nothing it writes is used</td></tr>",
            esc(&plan.passes[p].name)
        );
    }
    h.push_str("</table>\n<h2>Resource lifetimes</h2>\n<table><tr><th>resource</th><th>kind</th><th>size</th><th>slot</th>");
    for &p in &plan.order {
        let _ = write!(h, "<th class=\"v\">{}</th>", esc(&plan.passes[p].name));
    }
    h.push_str("</tr>\n");
    for res in &plan.resources {
        let _ = write!(
            h,
            "<tr><td>{}</td><td class=\"slot\">{}</td><td>{}</td><td>{}</td>",
            esc(&res.info.name),
            kind_tag(&res.info.kind),
            bytes(res.info.desc.bytes()),
            res.pool_slot
                .map(|s| s.to_string())
                .unwrap_or_else(|| "–".into())
        );
        for (o, &p) in plan.order.iter().enumerate() {
            let used = plan.passes[p]
                .slots
                .iter()
                .any(|s| plan.resources[s.resource].info.name == res.info.name)
                || plan.passes[p]
                    .scratch
                    .iter()
                    .any(|&s| plan.resources[s].info.name == res.info.name);
            let alive = res.lifetime.is_some_and(|l| l.first <= o && o <= l.last);
            let class = if alive { " class=\"life\"" } else { "" };
            let _ = write!(h, "<td{class}>{}</td>", if used { "●" } else { "" });
        }
        h.push_str("</tr>\n");
    }
    h.push_str("</table>\n</body></html>\n");
    h
}

/// The batches: what shares a compute pass, what needs the encoder and why, and each
/// batch's GPU time when the frame was timed per batch.
fn batches(h: &mut String, plan: &Plan, last_frame: Option<&FrameStats>) {
    let mode = last_frame.map_or("no frame run", |f| f.timing.name());
    let _ = writeln!(
        h,
        "<h2>Batches</h2>\n<p>{} batches, {} of them shared compute passes; GPU times from timing mode <b>{}</b>{}.</p>",
        plan.batches.len(),
        plan.batches.iter().filter(|b| b.compute).count(),
        esc(mode),
        last_frame
            .and_then(|f| f.gpu_frame_us)
            .map(|us| format!(", frame {us:.1} µs on the GPU"))
            .unwrap_or_default()
    );
    h.push_str("<table><tr><th>batch</th><th>passes</th><th>GPU µs</th><th></th></tr>\n");
    let times: Vec<Option<f64>> = plan
        .batches
        .iter()
        .enumerate()
        .map(|(b, _)| {
            last_frame
                .and_then(|f| f.batches.get(b))
                .and_then(|s| s.gpu_us)
        })
        .collect();
    let max = times.iter().flatten().fold(0.0, |a: f64, &b| a.max(b));
    for (b, batch) in plan.batches.iter().enumerate() {
        let passes = batch
            .passes
            .iter()
            .map(|&p| {
                let pass = &plan.passes[p];
                match &pass.recording {
                    crate::plan::Recording::Encoder(why) => {
                        format!("{} <small>(encoder: {})</small>", esc(&pass.name), esc(why))
                    }
                    crate::plan::Recording::Compute => esc(&pass.name),
                }
            })
            .collect::<Vec<_>>()
            .join(", ");
        let width = match times[b] {
            Some(t) if max > 0.0 => (t / max * 300.0).round() as u32,
            _ => 0,
        };
        let _ = writeln!(
            h,
            "<tr><td>{}</td><td>{passes}</td><td>{}</td><td><div class=\"bar\" style=\"width:{width}px\"></div></td></tr>",
            esc(&batch.label(b)),
            times[b]
                .map(|t| format!("{t:.1}"))
                .unwrap_or_else(|| "–".into()),
        );
    }
    h.push_str("</table>\n");
}
