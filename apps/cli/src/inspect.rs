//! `meshlight inspect ASSET`: the header and DAG statistics of an asset, then whether
//! its invariants hold (each violation, and the command fails) or how good the DAG is
//! (quality warnings, which do not fail it).

use crate::dag_table::dag_table;
use meshlight::scene::SceneError;
use meshlight::scene::inspect::{InspectReport, inspect};
use std::fmt::Write as _;
use std::path::Path;

/// Inspects `file` and prints the report. A file that does not load fails with nothing
/// printed; a broken DAG fails after its figures and violations are printed.
pub fn run(file: &Path) -> Result<(), SceneError> {
    let report = inspect(file)?;
    print!("{}", text(&report));
    report.verdict()
}

/// The text `meshlight inspect` prints.
pub fn text(report: &InspectReport) -> String {
    let summary = &report.summary;
    let h = &summary.header;
    let mut s = String::new();
    let _ = writeln!(
        s,
        "{}: meshlet asset version {}",
        report.path.display(),
        h.version
    );
    let _ = writeln!(
        s,
        "  {} bytes, checksum {:#018x}, {} meshlets, {} groups, UVs: {}, material slots: {}",
        summary.bytes,
        summary.checksum(),
        h.meshlet_count,
        h.group_count,
        if h.has_uvs() { "yes" } else { "no" },
        h.material_count
    );
    let _ = writeln!(
        s,
        "  bounds {:?} .. {:?}; position grid {} bits, step {:.3e} (max error {:.3e})",
        h.bounds_min, h.bounds_max, h.quant_bits, h.quant_step, summary.max_position_error
    );
    let _ = writeln!(
        s,
        "  source: {} triangles, of which {} degenerate and {} duplicate were dropped; LOD 0 \
         uses {} vertices and is open along {} edges",
        h.input_triangles,
        h.dropped_degenerate,
        h.dropped_duplicate,
        h.lod0_vertices,
        summary.open_edges
    );
    s += &dag_table(summary);
    if report.problems.is_empty() {
        let _ = writeln!(s, "  invariants: all hold");
        for w in &report.warnings {
            let _ = writeln!(s, "  warning: {w}");
        }
        if report.warnings.is_empty() {
            let _ = writeln!(s, "  quality: levels halve, {} root(s)", h.root_count);
        }
    } else {
        for p in &report.problems {
            let _ = writeln!(s, "  violated: {p}");
        }
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;
    use meshlight::scene::{build_asset, procedural_mesh};

    #[test]
    fn a_sound_asset_shows_its_figures_then_that_its_invariants_hold() {
        let built = build_asset(&procedural_mesh(8), &Default::default(), &mut |_| {}).unwrap();
        let report = InspectReport::of(Path::new("knot.mlasset"), &built.asset);
        let text = text(&report);
        let lines: Vec<&str> = text.lines().collect();
        assert_eq!(
            lines[0],
            format!(
                "knot.mlasset: meshlet asset version {}",
                meshlight::scene::asset::format::VERSION
            ),
            "{text}"
        );
        assert!(lines[1].ends_with("material slots: 1"), "{text}");
        assert!(
            lines[1].contains(&format!(
                "{} bytes, checksum {:#018x}",
                built.asset.bytes().len(),
                report.summary.checksum()
            )),
            "{text}"
        );
        assert!(text.contains("  invariants: all hold\n"), "{text}");
        assert!(
            text.ends_with(&format!(
                "  quality: levels halve, {} root(s)\n",
                built.asset.header().root_count
            )),
            "{text}"
        );
        assert!(!text.contains("violated"), "{text}");
    }

    #[test]
    fn violations_and_warnings_each_get_a_line() {
        let built = build_asset(&procedural_mesh(8), &Default::default(), &mut |_| {}).unwrap();
        let mut report = InspectReport::of(Path::new("knot.mlasset"), &built.asset);
        report.warnings = vec!["too deep".into(), "too many roots".into()];
        let warned = text(&report);
        assert!(
            warned.ends_with(
                "  invariants: all hold\n  warning: too deep\n  warning: too many roots\n"
            ),
            "{warned}"
        );
        report.problems = vec!["group 2: error 0 below child".into()];
        let broken = text(&report);
        assert!(
            broken.ends_with("  violated: group 2: error 0 below child\n"),
            "{broken}"
        );
        assert!(!broken.contains("invariants: all hold"), "{broken}");
    }
}
