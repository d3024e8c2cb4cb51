//! The progress bars of `meshlight bake`: one style for a single mesh's levels and for a
//! directory's meshes, drawn on standard error (indicatif hides them off a terminal, so
//! piped output and the tests see none). The library reports progress through
//! callbacks; drawing it is the command's business.

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use meshlight::scene::bake::BakeProgress;

/// Meshes with fewer triangles build before a bar would help, so theirs is not drawn.
pub const LEVEL_BAR_MIN_TRIANGLES: u64 = 200_000;

/// A progress bar of `len` steps in the style of every bake: a spinner, `what` (an
/// indicatif template naming the work and where the bar goes), then the time taken.
pub fn progress_bar(len: u64, what: &str) -> ProgressBar {
    let template = format!("{{spinner}} {what} ({{elapsed}})");
    let style = ProgressStyle::with_template(&template)
        .unwrap_or_else(|e| panic!("progress template `{template}`: {e}"));
    ProgressBar::new(len).with_style(style.progress_chars("=> "))
}

/// The bar of one mesh's bake, created when the mesh is loaded (its triangle count is
/// the bar's length) and moved on by each level toward no triangles left.
#[derive(Default)]
pub struct LevelBar {
    bar: Option<(ProgressBar, u64)>,
}

impl LevelBar {
    /// Shows `step` of the bake.
    pub fn update(&mut self, step: BakeProgress) {
        match step {
            BakeProgress::Loaded { triangles } => {
                let bar = progress_bar(triangles, "building LOD DAG [{bar:30}] {msg}");
                if triangles < LEVEL_BAR_MIN_TRIANGLES {
                    bar.set_draw_target(ProgressDrawTarget::hidden());
                }
                self.bar = Some((bar, triangles));
            }
            BakeProgress::Level(p) => {
                let Some((bar, triangles)) = &self.bar else {
                    return;
                };
                // Triangles left shrink by about half per level; show progress toward zero.
                bar.set_position(triangles.saturating_sub(p.active_triangles as u64));
                bar.set_message(format!(
                    "level {}: {} clusters, {} triangles left",
                    p.level, p.active_clusters, p.active_triangles
                ));
            }
        }
    }

    /// Removes the bar, so that what is printed next starts on a clean line.
    pub fn finish(&mut self) {
        if let Some((bar, _)) = self.bar.take() {
            bar.finish_and_clear();
        }
    }
}
