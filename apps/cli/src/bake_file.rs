//! `meshlight bake FILE -o ASSET`: one mesh baked with a progress bar, then a summary of
//! what was built (the input after cleaning, the crack repairs, the DAG table, the
//! times) and any quality warnings.

use crate::dag_table::dag_table;
use crate::progress::LevelBar;
use meshlight::scene::SceneError;
use meshlight::scene::bake::{BakeOptions, BakeReport, bake};
use std::fmt::Write as _;

/// Bakes one mesh as `options` say, drawing the progress, and prints the summary.
pub fn run(options: &BakeOptions) -> Result<(), SceneError> {
    let mut bar = LevelBar::default();
    let report = bake(options, &mut |step| bar.update(step));
    bar.finish();
    print!("{}", summary(&report?));
    Ok(())
}

/// The text `meshlight bake` prints for one mesh, warnings last.
pub fn summary(report: &BakeReport) -> String {
    let mut s = String::new();
    let _ = writeln!(
        s,
        "baked {} -> {}",
        report.input.display(),
        report.output.display()
    );
    let c = &report.clean;
    let _ = writeln!(
        s,
        "  input: {} triangles, {} vertices; {} degenerate and {} duplicate triangles dropped, \
         {} vertices welded to a neighbour{}",
        report.mesh_triangles,
        report.mesh_vertices,
        c.dropped_degenerate,
        c.dropped_duplicate,
        c.welded_vertices,
        if report.snapped_to_grid {
            "; snapped to the position grid"
        } else {
            ""
        }
    );
    let _ = writeln!(
        s,
        "  crack repairs: {} groups kept unsimplified (fallback), {} simplified again with \
         their border triangles locked",
        report.fallbacks.unsimplified, report.fallbacks.relocked
    );
    s += &dag_table(&report.summary);
    let seconds = report.total_time.as_secs_f64();
    let _ = writeln!(
        s,
        "  build time: {:.3} s ({:.3} s DAG, {:.3} s loading before), {:.0} input triangles/s",
        seconds,
        report.dag_time.as_secs_f64(),
        report.load_time.as_secs_f64(),
        report.summary.header.lod0_triangles as f64 / seconds
    );
    for w in &report.warnings {
        let _ = writeln!(s, "  warning: {w}");
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;
    use meshlight::scene::bake::BakeReport;
    use meshlight::scene::{build_asset, procedural_mesh};
    use std::path::Path;
    use std::time::Duration;

    #[test]
    fn the_summary_reports_the_input_the_repairs_the_levels_and_the_times() {
        let built = build_asset(&procedural_mesh(8), &Default::default(), &mut |_| {}).unwrap();
        let mut report = BakeReport::new(
            Path::new("knot.obj"),
            Path::new("knot.mlasset"),
            &built,
            Duration::from_millis(250),
        );
        report.fallbacks.unsimplified = 7;
        report.fallbacks.relocked = 5;
        report.warnings = vec!["too deep".into()];
        let text = summary(&report);
        let lines: Vec<&str> = text.lines().collect();
        assert_eq!(lines[0], "baked knot.obj -> knot.mlasset", "{text}");
        assert!(
            lines[1].contains(&format!(
                "input: {} triangles, {} vertices",
                report.mesh_triangles, report.mesh_vertices
            )),
            "{text}"
        );
        assert!(
            lines[2].contains("7 groups kept unsimplified (fallback), 5 simplified again"),
            "{text}"
        );
        for needle in [
            "level  meshlets  triangles",
            "levels:",
            "root:",
            "meshlet fill",
            "bytes per LOD-0 triangle",
            "0.250 s loading before",
            "input triangles/s",
        ] {
            assert!(text.contains(needle), "missing {needle:?} in\n{text}");
        }
        assert_eq!(lines.last(), Some(&"  warning: too deep"), "{text}");
    }
}
