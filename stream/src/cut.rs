//! The LOD cut over resident pages, and the check that a drawn cut has no hole.
//!
//! Without streaming, a meshlet is drawn when its own error hides and its parent's
//! shows. Expressed per group: a group is *refined* (its children drawn in place of its
//! result) when its error shows, and a meshlet is drawn when the group it was simplified
//! in is refined (or it is a root) and the group that produced it is not (or it is at
//! LOD 0). Streaming adds one condition, the same for every group: a group is refined
//! only while its page is resident. Where the view wants detail the pool lacks, the cut
//! keeps the finest resident ancestor's level.
//!
//! A cut is *complete* when every path from a LOD-0 meshlet up to a root (through the
//! group each meshlet was simplified in, then any meshlet that group produced) meets
//! exactly one drawn meshlet: none is a hole, two is surface drawn twice.
//! [`check`] verifies that of any drawn set, so the GPU's cut can be read back and
//! checked on the CPU.

use meshlight_scene::asset::format::NO_GROUP;

use crate::pages::MeshDag;

/// Which meshlets the cut draws: group `g` is refined when `perceptible[g]` (its error
/// shows from this view) and `resident(g)`. The cut is complete when the resident pages
/// are closed under parents ([`crate::pages`]), as the streamer keeps them, and the
/// perceptible groups too, as errors growing up the DAG make them.
pub fn select(dag: &MeshDag, perceptible: &[bool], resident: impl Fn(u32) -> bool) -> Vec<bool> {
    let refined: Vec<bool> = (0..dag.group_count)
        .map(|g| perceptible[g as usize] && resident(g))
        .collect();
    let is_refined = |g: u32| g != NO_GROUP && refined[g as usize];
    (0..dag.meshlet_count())
        .map(|m| {
            let (source, parent) = (dag.source[m], dag.parent[m]);
            (parent == NO_GROUP || is_refined(parent)) && !is_refined(source)
        })
        .collect()
}

/// Why a drawn set is not a complete cut.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum Hole {
    /// A meshlet is drawn whose page (its parent group's) is not resident: the GPU
    /// would read a pool slot that holds something else.
    #[error("meshlet {meshlet} is drawn, but its page (group {group}) is not resident")]
    NotResident {
        /// The meshlet.
        meshlet: u32,
        /// Its parent group, whose page holds it.
        group: u32,
    },
    /// Some path from a LOD-0 meshlet to a root meets no drawn meshlet, or more than
    /// one.
    #[error(
        "the paths up from LOD-0 meshlet {meshlet} meet between {fewest} and {most} drawn \
         meshlets; a complete cut draws exactly one on each"
    )]
    Path {
        /// The LOD-0 meshlet.
        meshlet: u32,
        /// Fewest drawn meshlets on one of its paths.
        fewest: u32,
        /// Most drawn meshlets on one of its paths.
        most: u32,
    },
    /// The drawn set does not have one entry per meshlet.
    #[error("{got} drawn flags for a mesh of {meshlets} meshlets")]
    Length {
        /// Flags given.
        got: usize,
        /// Meshlets of the mesh.
        meshlets: usize,
    },
}

/// Checks that `drawn` (one flag per meshlet) is a complete cut drawing only resident
/// pages. Runs in time linear in the DAG's links: per group, the fewest and most drawn
/// meshlets on the paths above it, coarsest first.
pub fn check(dag: &MeshDag, drawn: &[bool], resident: impl Fn(u32) -> bool) -> Result<(), Hole> {
    if drawn.len() != dag.meshlet_count() {
        return Err(Hole::Length {
            got: drawn.len(),
            meshlets: dag.meshlet_count(),
        });
    }
    for (m, &d) in drawn.iter().enumerate() {
        let group = dag.parent[m];
        if d && group != NO_GROUP && !resident(group) {
            return Err(Hole::NotResident {
                meshlet: m as u32,
                group,
            });
        }
    }
    // above[g]: (fewest, most) drawn meshlets on a path from one of g's results up.
    let results = dag.results();
    let pages = dag.pages();
    let mut order: Vec<u32> = (0..dag.group_count).collect();
    // Coarsest first: every group after the groups its result went into.
    order.sort_by_key(|&g| pages.depth(g));
    let mut above = vec![(0u32, 0u32); dag.group_count as usize];
    let from = |m: usize, above: &[(u32, u32)]| {
        let own = u32::from(drawn[m]);
        match dag.parent[m] {
            NO_GROUP => (own, own),
            g => (own + above[g as usize].0, own + above[g as usize].1),
        }
    };
    for &g in &order {
        let span = results[g as usize]
            .iter()
            .map(|&m| from(m as usize, &above))
            .fold(None, |acc: Option<(u32, u32)>, (lo, hi)| {
                Some(acc.map_or((lo, hi), |(a, b)| (a.min(lo), b.max(hi))))
            });
        // A group that produced nothing ends its paths (the builder never makes one).
        above[g as usize] = span.unwrap_or((0, 0));
    }
    for m in 0..dag.meshlet_count() {
        if dag.source[m] != NO_GROUP {
            continue;
        }
        let (fewest, most) = from(m, &above);
        if (fewest, most) != (1, 1) {
            return Err(Hole::Path {
                meshlet: m as u32,
                fewest,
                most,
            });
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::pages::diamond;

    #[test]
    fn a_missing_page_keeps_its_groups_result_and_the_cut_stays_complete() {
        let dag = diamond();
        let all = |_| true;
        // Everything perceptible and resident: LOD 0.
        let drawn = select(&dag, &[true; 3], all);
        assert_eq!(drawn, [true, true, true, true, false, false, false]);
        check(&dag, &drawn, all).unwrap();
        // Group 1's page missing: its result (meshlet 5) stands in for its children.
        let without_1 = |g| g != 1;
        let drawn = select(&dag, &[true; 3], without_1);
        assert_eq!(drawn, [true, true, false, false, false, true, false]);
        check(&dag, &drawn, without_1).unwrap();
        // Nothing resident: the root alone.
        let none = |_| false;
        let drawn = select(&dag, &[true; 3], none);
        assert_eq!(drawn, [false, false, false, false, false, false, true]);
        check(&dag, &drawn, none).unwrap();
        // Only the finer pages: not closed under parents, so the root is drawn over LOD
        // 0. The streamer never lets this happen; the checker sees it.
        let not_closed = |g| g != 2;
        let drawn = select(&dag, &[true; 3], not_closed);
        assert_eq!(drawn, [true, true, true, true, false, false, true]);
        assert!(matches!(
            check(&dag, &drawn, not_closed),
            Err(Hole::Path { most: 2, .. })
        ));
    }

    #[test]
    fn holes_double_draws_and_unheld_pages_are_named() {
        let dag = diamond();
        let all = |_| true;
        // Meshlet 1 left out: LOD-0 meshlet 1's only path meets nothing.
        let hole = [true, false, true, true, false, false, false];
        assert_eq!(
            check(&dag, &hole, all),
            Err(Hole::Path {
                meshlet: 1,
                fewest: 0,
                most: 0
            })
        );
        // LOD 0 and the root together.
        let twice = [true, true, true, true, false, false, true];
        assert!(matches!(
            check(&dag, &twice, all),
            Err(Hole::Path { most: 2, .. })
        ));
        // Meshlet 4 with 0 and 1: paths through group 2 from meshlet 0 meet 4 and 0.
        let mixed = [true, true, false, false, true, true, false];
        assert!(matches!(
            check(&dag, &mixed, all),
            Err(Hole::Path { meshlet: 0, .. })
        ));
        // A complete cut whose page is not resident.
        let lod0 = [true, true, true, true, false, false, false];
        assert_eq!(
            check(&dag, &lod0, |g| g != 0),
            Err(Hole::NotResident {
                meshlet: 0,
                group: 0
            })
        );
        assert!(matches!(
            check(&dag, &[true], all),
            Err(Hole::Length { got: 1, .. })
        ));
    }
}
