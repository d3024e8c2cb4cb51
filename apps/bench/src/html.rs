//! `meshlight bench --html`: the rows of a run (or of a saved JSON file) as one
//! self-contained page of charts drawn here in SVG, no scripts and no network:
//! - a size sweep (the cases of a metric begin with a count: 1,000 lights, 2^20
//!   elements, 8 copies) is a log-log line, one line per metric;
//! - a frame profiled per pass (`GPU <pass> (timing mode passes)`) is a stacked bar per
//!   case, a colour per pass;
//! - every other timed metric with several cases is a bar per case.
//!
//! The table of every row follows the charts, so nothing a chart leaves out is lost.

use crate::Row;
use std::collections::BTreeMap;
use std::fmt::Write;

const PASS_SUFFIX: &str = " (timing mode passes)";
const COLOURS: [&str; 16] = [
    "#4a78c2", "#e07b39", "#5aa469", "#c94f6d", "#8a6bbe", "#3aa6b9", "#b89b2e", "#7a7a7a",
    "#d46fb0", "#2f5f8a", "#9c5b2e", "#7fbf3f", "#e2b73c", "#5e3c99", "#1b9e77", "#a6a6d8",
];

fn esc(s: &str) -> String {
    s.replace('&', "&amp;")
        .replace('<', "&lt;")
        .replace('>', "&gt;")
        .replace('"', "&quot;")
}

/// Units a chart compares: times and rates. Counters go to the table only.
fn charted(unit: &str) -> bool {
    matches!(unit, "ms" | "µs" | "us" | "s" | "GB/s" | "Gelem/s" | "MB/s")
}

/// The count a case begins with (`1000 lights`, `2^20`, `32768 copies, …`), if any.
pub fn leading_size(case: &str) -> Option<f64> {
    let head = case.split([' ', ',']).next()?;
    if let Some((base, exp)) = head.split_once('^') {
        return Some(base.parse::<f64>().ok()?.powf(exp.parse().ok()?));
    }
    head.replace('_', "")
        .parse::<f64>()
        .ok()
        .filter(|v| *v > 0.0)
}

/// The whole page for `rows`, titled `title`.
pub fn page(title: &str, rows: &[Row]) -> String {
    let mut h = String::new();
    let _ = write!(
        h,
        "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\"><title>{t}</title>\n<style>\n\
body{{font:14px/1.4 system-ui,sans-serif;margin:2em;color:#222}}\n\
table{{border-collapse:collapse;margin:1em 0}}td,th{{padding:3px 8px;border:1px solid #ddd;text-align:left}}\n\
td.n{{text-align:right;font-variant-numeric:tabular-nums}}h3{{margin-bottom:0}}\n\
</style></head><body>\n<h1>{t}</h1>\n",
        t = esc(title)
    );
    let devices: Vec<&str> = unique(rows.iter().map(|r| r.device.as_str()));
    let _ = writeln!(
        h,
        "<p>{} rows from {}.</p>",
        rows.len(),
        esc(&devices.join(", "))
    );
    for scenario in unique(rows.iter().map(|r| r.scenario.as_str())) {
        let of: Vec<&Row> = rows.iter().filter(|r| r.scenario == scenario).collect();
        let _ = writeln!(h, "<h2>{}</h2>", esc(scenario));
        charts(&mut h, &of);
        table(&mut h, &of);
    }
    h.push_str("</body></html>\n");
    h
}

/// Distinct values in first-seen order.
fn unique<'a>(items: impl Iterator<Item = &'a str>) -> Vec<&'a str> {
    let mut seen = Vec::new();
    for i in items {
        if !seen.contains(&i) {
            seen.push(i);
        }
    }
    seen
}

fn charts(h: &mut String, rows: &[&Row]) {
    // Per-pass profiles: one stacked bar per case.
    // A value that is not finite (written as `null`) is listed in the table only.
    let profiled: Vec<&Row> = rows
        .iter()
        .copied()
        .filter(|r| per_pass(r) && r.value.is_finite())
        .collect();
    if !profiled.is_empty() {
        let _ = writeln!(h, "<h3>GPU time per pass (ms, passes timing)</h3>");
        h.push_str(&stacked(&profiled));
    }
    for metric in unique(rows.iter().map(|r| r.metric.as_str())) {
        if rows.iter().any(|r| r.metric == metric && per_pass(r)) {
            continue;
        }
        let of: Vec<&Row> = rows
            .iter()
            .copied()
            .filter(|r| r.metric == metric && charted(&r.unit) && r.value.is_finite())
            .collect();
        if of.len() < 2 {
            continue;
        }
        let unit = &of[0].unit;
        let _ = writeln!(h, "<h3>{} ({})</h3>", esc(metric), esc(unit));
        let sizes: Option<Vec<f64>> = of.iter().map(|r| leading_size(&r.case)).collect();
        match sizes {
            Some(sizes) if unique_count(&sizes) >= 3 => h.push_str(&sweep(&of, &sizes)),
            _ => h.push_str(&bars(&of)),
        }
    }
}

fn unique_count(v: &[f64]) -> usize {
    let mut v = v.to_vec();
    v.sort_by(f64::total_cmp);
    v.dedup();
    v.len()
}

/// How long `value`'s bar is on a scale where `max` fills `full`; nothing when every
/// value is zero, rather than a division by it.
fn bar_length(value: f64, max: f64, full: f64) -> f64 {
    if max > 0.0 { value / max * full } else { 0.0 }
}

/// A bar per row, labelled with its case and value.
pub fn bars(rows: &[&Row]) -> String {
    let max = rows.iter().map(|r| r.value).fold(0.0, f64::max);
    let (label_w, bar_w, row_h) = (330.0, 360.0, 20.0);
    let height = rows.len() as f64 * row_h + 10.0;
    let mut s = format!(
        "<svg width=\"{}\" height=\"{height}\" font-size=\"11\" font-family=\"system-ui,sans-serif\">\n",
        label_w + bar_w + 90.0
    );
    for (i, r) in rows.iter().enumerate() {
        let y = 5.0 + i as f64 * row_h;
        let w = bar_length(r.value, max, bar_w);
        let _ = writeln!(
            s,
            "<text x=\"{}\" y=\"{}\" text-anchor=\"end\">{}</text><rect x=\"{label_w}\" y=\"{y}\" width=\"{w:.1}\" height=\"{}\" fill=\"{}\"/><text x=\"{:.1}\" y=\"{}\">{}</text>",
            label_w - 6.0,
            y + 12.0,
            esc(&shorten(&r.case, 52)),
            row_h - 5.0,
            COLOURS[0],
            label_w + w + 4.0,
            y + 12.0,
            format_value(r.value)
        );
    }
    s.push_str("</svg>\n");
    s
}

/// What a case is besides its size: its words without numbers (`1000 lights, raster`
/// and `8 lights, raster` are one line; `… compute` another).
fn variant(case: &str) -> String {
    case.split_whitespace()
        .skip(1)
        .filter(|w| !w.chars().any(|c| c.is_ascii_digit()))
        .collect::<Vec<_>>()
        .join(" ")
}

/// Log-log lines of value against the case's leading count, one per variant.
pub fn sweep(rows: &[&Row], sizes: &[f64]) -> String {
    let (w, h, left, bottom, top, right) = (560.0, 260.0, 60.0, 36.0, 12.0, 16.0);
    let points: Vec<(f64, f64, &Row)> = sizes
        .iter()
        .zip(rows)
        .filter(|(x, r)| **x > 0.0 && r.value > 0.0)
        .map(|(x, r)| (x.log10(), r.value.log10(), *r))
        .collect();
    let range = |f: fn(&(f64, f64, &Row)) -> f64| {
        let lo = points.iter().map(f).fold(f64::INFINITY, f64::min).floor();
        let hi = points
            .iter()
            .map(f)
            .fold(f64::NEG_INFINITY, f64::max)
            .ceil();
        (lo, if hi > lo { hi } else { lo + 1.0 })
    };
    let ((x0, x1), (y0, y1)) = (range(|p| p.0), range(|p| p.1));
    let px = |x: f64| left + (x - x0) / (x1 - x0) * (w - left - right);
    let py = |y: f64| h - bottom - (y - y0) / (y1 - y0) * (h - bottom - top);
    let variants: Vec<String> = {
        let all: Vec<String> = points.iter().map(|p| variant(&p.2.case)).collect();
        unique(all.iter().map(String::as_str))
            .into_iter()
            .map(String::from)
            .collect()
    };
    let legend_h = 16.0 * variants.len() as f64;
    let mut s = format!(
        "<svg width=\"{w}\" height=\"{}\" font-size=\"11\" font-family=\"system-ui,sans-serif\">\n<rect x=\"{left}\" y=\"{top}\" width=\"{}\" height=\"{}\" fill=\"none\" stroke=\"#ccc\"/>\n",
        h + legend_h,
        w - left - right,
        h - bottom - top
    );
    for d in x0 as i32..=x1 as i32 {
        let x = px(d as f64);
        let _ = writeln!(
            s,
            "<line x1=\"{x:.1}\" y1=\"{top}\" x2=\"{x:.1}\" y2=\"{}\" stroke=\"#eee\"/><text x=\"{x:.1}\" y=\"{}\" text-anchor=\"middle\">1e{d}</text>",
            h - bottom,
            h - bottom + 14.0
        );
    }
    for d in y0 as i32..=y1 as i32 {
        let y = py(d as f64);
        let _ = writeln!(
            s,
            "<line x1=\"{left}\" y1=\"{y:.1}\" x2=\"{}\" y2=\"{y:.1}\" stroke=\"#eee\"/><text x=\"{}\" y=\"{:.1}\" text-anchor=\"end\">1e{d}</text>",
            w - right,
            left - 4.0,
            y + 4.0
        );
    }
    for (v, name) in variants.iter().enumerate() {
        let colour = COLOURS[v % COLOURS.len()];
        let mut line: Vec<&(f64, f64, &Row)> = points
            .iter()
            .filter(|p| variant(&p.2.case) == *name)
            .collect();
        line.sort_by(|a, b| a.0.total_cmp(&b.0));
        let path: Vec<String> = line
            .iter()
            .map(|p| format!("{:.1},{:.1}", px(p.0), py(p.1)))
            .collect();
        let _ = writeln!(
            s,
            "<polyline points=\"{}\" fill=\"none\" stroke=\"{colour}\" stroke-width=\"2\"/>",
            path.join(" ")
        );
        for p in &line {
            let _ = writeln!(
                s,
                "<circle cx=\"{:.1}\" cy=\"{:.1}\" r=\"3\" fill=\"{colour}\"><title>{}: {}</title></circle>",
                px(p.0),
                py(p.1),
                esc(&p.2.case),
                format_value(p.2.value)
            );
        }
        let y = h + 16.0 * v as f64;
        let _ = writeln!(
            s,
            "<rect x=\"{left}\" y=\"{y}\" width=\"10\" height=\"10\" fill=\"{colour}\"/><text x=\"{}\" y=\"{}\">{}</text>",
            left + 14.0,
            y + 9.0,
            esc(if name.is_empty() { "(all)" } else { name })
        );
    }
    let _ = writeln!(
        s,
        "<text x=\"{}\" y=\"{}\" text-anchor=\"middle\" fill=\"#555\">size (the case's leading count), log scale</text>",
        (left + w - right) / 2.0,
        h - 4.0
    );
    s.push_str("</svg>\n");
    s
}

/// One bar per case, a segment per pass, a legend of the passes.
pub fn stacked(rows: &[&Row]) -> String {
    let cases = unique(rows.iter().map(|r| r.case.as_str()));
    let passes = unique(rows.iter().map(|r| pass_name(&r.metric)));
    let totals: BTreeMap<&str, f64> = cases
        .iter()
        .map(|c| {
            let total = rows.iter().filter(|r| r.case == *c).map(|r| r.value).sum();
            (*c, total)
        })
        .collect();
    let max = totals.values().copied().fold(0.0, f64::max);
    let (label_w, bar_w, row_h) = (330.0, 360.0, 24.0);
    let legend_rows = passes.len().div_ceil(4);
    let height = cases.len() as f64 * row_h + legend_rows as f64 * 16.0 + 16.0;
    let mut s = format!(
        "<svg width=\"{}\" height=\"{height}\" font-size=\"11\" font-family=\"system-ui,sans-serif\">\n",
        (label_w + bar_w + 90.0f64).max(730.0)
    );
    for (i, case) in cases.iter().enumerate() {
        let y = 4.0 + i as f64 * row_h;
        let _ = writeln!(
            s,
            "<text x=\"{}\" y=\"{}\" text-anchor=\"end\">{}</text>",
            label_w - 6.0,
            y + 13.0,
            esc(&shorten(case, 52))
        );
        let mut x = label_w;
        for (p, pass) in passes.iter().enumerate() {
            let Some(r) = rows
                .iter()
                .find(|r| r.case == *case && pass_name(&r.metric) == *pass)
            else {
                continue;
            };
            let w = bar_length(r.value, max, bar_w);
            let _ = writeln!(
                s,
                "<rect x=\"{x:.1}\" y=\"{y}\" width=\"{w:.1}\" height=\"{}\" fill=\"{}\"><title>{}: {} ms</title></rect>",
                row_h - 6.0,
                COLOURS[p % COLOURS.len()],
                esc(pass),
                format_value(r.value)
            );
            x += w;
        }
        let _ = writeln!(
            s,
            "<text x=\"{:.1}\" y=\"{}\">{}</text>",
            x + 4.0,
            y + 13.0,
            format_value(totals[case])
        );
    }
    let legend_y = 8.0 + cases.len() as f64 * row_h;
    for (p, pass) in passes.iter().enumerate() {
        let (col, line) = ((p % 4) as f64, (p / 4) as f64);
        let (x, y) = (130.0 + col * 150.0, legend_y + line * 16.0);
        let _ = writeln!(
            s,
            "<rect x=\"{x}\" y=\"{y}\" width=\"10\" height=\"10\" fill=\"{}\"/><text x=\"{}\" y=\"{}\">{}</text>",
            COLOURS[p % COLOURS.len()],
            x + 14.0,
            y + 9.0,
            esc(pass)
        );
    }
    s.push_str("</svg>\n");
    s
}

/// A pass's own GPU time in a per-pass profile (not the frame's, which the bar sums).
fn per_pass(r: &Row) -> bool {
    r.unit == "ms"
        && r.metric.starts_with("GPU ")
        && r.metric.ends_with(PASS_SUFFIX)
        && !r.metric.starts_with("GPU frame")
}

fn pass_name(metric: &str) -> &str {
    metric
        .strip_prefix("GPU ")
        .and_then(|m| m.strip_suffix(PASS_SUFFIX))
        .unwrap_or(metric)
}

fn shorten(s: &str, most: usize) -> String {
    if s.chars().count() <= most {
        s.to_string()
    } else {
        format!("{}…", s.chars().take(most - 1).collect::<String>())
    }
}

fn format_value(v: f64) -> String {
    match v.abs() {
        _ if v.is_nan() => "not a number".into(),
        a if a.is_infinite() => format!("{v}"),
        a if a >= 100.0 => format!("{v:.0}"),
        a if a >= 1.0 => format!("{v:.2}"),
        _ => format!("{v:.3}"),
    }
}

fn table(h: &mut String, rows: &[&Row]) {
    h.push_str("<details><summary>every row</summary><table><tr><th>case</th><th>metric</th><th>value</th><th>unit</th><th>vs baseline</th></tr>\n");
    for r in rows {
        let _ = writeln!(
            h,
            "<tr><td>{}</td><td>{}</td><td class=\"n\">{}</td><td>{}</td><td class=\"n\">{}</td></tr>",
            esc(&r.case),
            esc(&r.metric),
            format_value(r.value),
            esc(&r.unit),
            r.vs_baseline
                .map(|b| format!("×{b:.2}"))
                .unwrap_or_default()
        );
    }
    h.push_str("</table></details>\n");
}

#[cfg(test)]
mod tests {
    use super::*;

    fn row(scenario: &str, case: &str, metric: &str, value: f64, unit: &str) -> Row {
        Row {
            scenario: scenario.into(),
            case: case.into(),
            metric: metric.into(),
            value,
            unit: unit.into(),
            vs_baseline: None,
            device: "test".into(),
        }
    }

    #[test]
    fn sizes_are_read_from_the_case_s_first_word() {
        assert_eq!(leading_size("1000 lights, compute"), Some(1000.0));
        assert_eq!(leading_size("2^20"), Some(1048576.0));
        assert_eq!(leading_size("32768 copies, 1 source tris"), Some(32768.0));
        assert_eq!(leading_size("15³ stanford-bunny"), None);
        assert_eq!(leading_size("scan_fan 2^20"), None);
    }

    #[test]
    fn each_kind_of_row_gets_its_chart_and_every_row_its_line_in_the_table() {
        let mut rows = Vec::new();
        for (case, scale) in [("frame a", 1.0), ("frame b", 2.0)] {
            for pass in ["fill", "cull", "resolve"] {
                let metric = format!("GPU {pass}{PASS_SUFFIX}");
                rows.push(row("profile", case, &metric, 0.1 * scale, "ms"));
            }
            let total = format!("GPU frame, sum of the per-pass profile{PASS_SUFFIX}");
            rows.push(row("profile", case, &total, 0.3 * scale, "ms"));
        }
        for n in [1000.0f64, 10000.0, 100000.0] {
            for (variant, k) in [("compute", 1.0), ("raster", 3.0)] {
                let case = format!("{n} lights, {variant}");
                rows.push(row(
                    "sweep",
                    &case,
                    "GPU clustering",
                    k * n.sqrt() / 100.0,
                    "ms",
                ));
            }
        }
        rows.push(row("bars", "one", "CPU build", 2.0, "ms"));
        rows.push(row("bars", "two", "CPU build", 3.0, "ms"));
        rows.push(row("bars", "two", "clusters", 7.0, ""));
        let page = page("t", &rows);
        // One stacked bar per case, a segment per pass, the frame's sum not a segment.
        assert_eq!(page.matches("<title>fill: ").count(), 2);
        assert!(!page.contains("<title>frame, sum"));
        // The sweep: a line per variant, a point per size.
        assert_eq!(page.matches("<polyline").count(), 2);
        assert_eq!(page.matches("<circle").count(), 6);
        assert!(page.contains(">lights, compute<") && page.contains(">lights, raster<"));
        // The bars and the table: counters are not charted but listed.
        assert!(page.contains("<h3>CPU build (ms)</h3>"));
        assert!(!page.contains("<h3>clusters"));
        assert_eq!(page.matches("<tr><td>").count(), rows.len());
        assert!(!page.contains("http") && !page.contains("<script"));
    }

    /// A value that is not finite is listed, never drawn: no `NaN` or `inf` in the SVG.
    #[test]
    fn a_value_that_is_not_finite_goes_to_the_table_only() {
        let pass = format!("GPU fill{PASS_SUFFIX}");
        let rows = [
            row("bars", "one", "CPU build", 2.0, "ms"),
            row("bars", "two", "CPU build", 3.0, "ms"),
            row("bars", "three", "CPU build", f64::NAN, "ms"),
            row("bars", "four", "PSNR", f64::INFINITY, "dB"),
            row("profile", "a", &pass, 0.1, "ms"),
            row("profile", "b", &pass, f64::NAN, "ms"),
        ];
        let page = page("t", &rows);
        assert_eq!(page.matches("<tr><td>").count(), rows.len());
        assert!(page.contains(">not a number<") && page.contains(">inf<"));
        // The charts: the page without its tables (one per scenario).
        let svg: String = page
            .split("<details>")
            .map(|part| part.split("</details>").last().unwrap())
            .collect();
        assert!(!svg.contains("NaN") && !svg.contains("inf"), "{svg}");
        assert_eq!(svg.matches("<title>fill: ").count(), 1);
    }
}
