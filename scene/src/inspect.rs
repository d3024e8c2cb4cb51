//! What `meshlight inspect` finds out about an asset file, as a value: its summary, the
//! DAG invariants it breaks and the quality findings of a DAG that holds them. The
//! command formats and prints it; a renderer or an editor can show the same findings
//! without running the command.

use std::path::{Path, PathBuf};

use crate::asset::summary::AssetSummary;
use crate::asset::{MeshletAsset, dag_error};
use crate::error::SceneError;
use crate::verify::{quality, verify};

/// An asset inspected: what it holds and what is wrong with it.
#[derive(Debug, Clone, PartialEq)]
pub struct InspectReport {
    /// The file inspected, for the messages about it.
    pub path: PathBuf,
    /// Header and DAG statistics.
    pub summary: AssetSummary,
    /// Violated DAG invariants (the asset would draw wrongly); empty when all hold.
    pub problems: Vec<String>,
    /// What is poor about a DAG whose invariants hold (too deep, too many roots, levels
    /// that do not halve), each with what to try. Not looked for when `problems` is not
    /// empty: the figures of a broken DAG say nothing about its quality.
    pub warnings: Vec<String>,
}

impl InspectReport {
    /// Inspects an asset already loaded from `path`.
    pub fn of(path: &Path, asset: &MeshletAsset) -> Self {
        let problems = verify(asset);
        let warnings = if problems.is_empty() {
            quality(asset).warnings
        } else {
            Vec::new()
        };
        Self {
            path: path.to_path_buf(),
            summary: AssetSummary::of(asset),
            problems,
            warnings,
        }
    }

    /// `Ok` when every DAG invariant holds, else the error loading the asset for drawing
    /// gives ([`MeshletAsset::load_verified`]), worded the same. Quality warnings never
    /// make it fail.
    pub fn verdict(&self) -> Result<(), SceneError> {
        dag_error(&self.path, &self.problems)
    }
}

/// Loads the asset at `path` (which checks magic, version, size, checksum and
/// structure) and inspects it. Only a file that does not load is an error; a loaded
/// asset whose DAG is broken gives a report whose [`InspectReport::verdict`] fails, so
/// that the figures can be shown beside the violations.
pub fn inspect(path: &Path) -> Result<InspectReport, SceneError> {
    let asset = MeshletAsset::load(path)?;
    Ok(InspectReport::of(path, &asset))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::asset::format::{AssetHeader, MAGIC, VERSION};

    /// A file that is not an asset of this version is refused with the error that says
    /// what to do, before anything is reported (and without the builder: these run
    /// under `--no-default-features` too).
    #[test]
    fn what_is_not_a_current_asset_is_refused_before_a_report() {
        let dir = std::env::temp_dir().join(format!("meshlight-inspect-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let header_bytes = AssetHeader::WORDS * 4;

        let mesh = dir.join("mesh.obj");
        std::fs::write(&mesh, "v 0 0 0\n".repeat(header_bytes)).unwrap();
        let err = inspect(&mesh).unwrap_err();
        assert!(matches!(err, SceneError::AssetMagic { .. }), "{err:?}");
        assert!(err.to_string().contains("meshlight bake"), "{err}");

        let mut old = vec![0u8; header_bytes];
        old[..8].copy_from_slice(&MAGIC);
        old[8..12].copy_from_slice(&(VERSION - 1).to_le_bytes());
        let old_path = dir.join("old.mlasset");
        std::fs::write(&old_path, &old).unwrap();
        let err = inspect(&old_path).unwrap_err();
        assert!(
            matches!(err, SceneError::AssetVersion { found, expected, .. }
                if found == VERSION - 1 && expected == VERSION),
            "{err:?}"
        );

        let err = inspect(&dir.join("missing.mlasset")).unwrap_err();
        assert!(err.to_string().contains("missing.mlasset"), "{err}");
        let _ = std::fs::remove_dir_all(&dir);
    }
}
