//! Assets damaged on purpose, sound in structure but not as a DAG: what the checks of
//! `inspect`, `bake`, the cache and the renderer must refuse. For the tests of every
//! tool that loads assets, so each damages them the same way. Compiled for this
//! crate's own tests and behind the `test-utils` feature, which other crates enable in
//! their dev-dependencies: an application has no use for broken assets.

use crate::{Built, MeshletAsset};

/// `built` with one group's error set below its children's (a group with a child above
/// LOD 0, whose error is positive), written with a valid checksum: only the DAG checks
/// see it. `None` when the DAG has no such group (a mesh too small for two levels).
pub fn error_below_child(built: &Built) -> Option<MeshletAsset> {
    let mut dag = built.dag.clone();
    let g = dag.groups.iter().position(|g| {
        g.children
            .iter()
            .any(|&c| dag.clusters[c as usize].level > 0)
    })?;
    dag.groups[g].lod.error = 0.0;
    Some(MeshletAsset::from_dag(
        &built.mesh,
        &dag,
        16,
        Default::default(),
    ))
}
