//! A mesh's pages and the pages each needs first.
//!
//! A DAG group is drawn *refined* when its result is too coarse for the view: its
//! children (the meshlets simplified in it) are drawn in place of the meshlets it
//! produced. So the unit a pool holds is a group's children, one page per group: while
//! the page is resident the group may be refined, and while it is not the cut keeps the
//! group's own result. The meshlets no group simplified (the roots) are the resident
//! part, always held, so every instance always has something to draw.
//!
//! Refining group `g` replaces the meshlets `g` produced, and each of those was
//! simplified in some group `p` (its parent group). Unless `p` is refined too, the
//! meshlet `g` produced is still drawn beside `g`'s children and covers the same surface
//! twice. So page `g` *needs* the pages of those groups `p`, its parents, resident
//! first. Errors and LOD spheres grow up the DAG, so a parent is perceptible wherever
//! its child is, and a resident set closed under parents always gives a complete cut
//! ([`crate::cut`]).

use std::fmt;

use meshlight_scene::MeshletAsset;
use meshlight_scene::asset::format::{NO_GROUP, PayloadLayout};

/// A page, as an index into a [`PageGraph`]: within one mesh, its group's index.
pub type PageId = u32;

/// The DAG links of one mesh's meshlets, which the cut and the pages are derived from.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct MeshDag {
    /// Per meshlet, the group that produced it ([`NO_GROUP`] at LOD 0).
    pub source: Vec<u32>,
    /// Per meshlet, the group it was simplified in ([`NO_GROUP`] for a root).
    pub parent: Vec<u32>,
    /// Per meshlet, the bytes of its payload (vertices, triangles, UVs, colours).
    pub payload_bytes: Vec<u32>,
    /// Groups of the mesh: every link above is below it or [`NO_GROUP`].
    pub group_count: u32,
}

impl MeshDag {
    /// The links of a loaded asset's meshlets.
    pub fn of_asset(asset: &MeshletAsset) -> Self {
        let flags = asset.header().flags;
        let meshlets = asset.meshlets();
        Self {
            source: meshlets.iter().map(|m| m.source_group).collect(),
            parent: meshlets.iter().map(|m| m.parent_group).collect(),
            payload_bytes: meshlets
                .iter()
                .map(|m| PayloadLayout::of(m, flags).end * 4)
                .collect(),
            group_count: asset.groups().len() as u32,
        }
    }

    /// Meshlets of the mesh.
    pub fn meshlet_count(&self) -> usize {
        self.parent.len()
    }

    /// Per group, the meshlets it produced (its *result*), in meshlet order.
    pub fn results(&self) -> Vec<Vec<u32>> {
        let mut results = vec![Vec::new(); self.group_count as usize];
        for (m, &g) in self.source.iter().enumerate() {
            if g != NO_GROUP {
                results[g as usize].push(m as u32);
            }
        }
        results
    }

    /// The mesh's pages: one per group, holding the group's children, needing the
    /// groups its result was simplified in.
    pub fn pages(&self) -> PageGraph {
        let mut bytes = vec![0u64; self.group_count as usize];
        for (m, &g) in self.parent.iter().enumerate() {
            if g != NO_GROUP {
                bytes[g as usize] += u64::from(self.payload_bytes[m]);
            }
        }
        let parents = self
            .results()
            .iter()
            .map(|result| {
                let mut parents: Vec<PageId> = result
                    .iter()
                    .map(|&m| self.parent[m as usize])
                    .filter(|&p| p != NO_GROUP)
                    .collect();
                parents.sort_unstable();
                parents.dedup();
                parents
            })
            .collect();
        // A verified asset's links point down the levels, so this cannot fail; a
        // hand-made DAG that loops is the caller's to build with `PageGraph::new`.
        PageGraph::new(bytes, parents).expect("a meshlet DAG's groups form no cycle")
    }
}

/// What is wrong with a page graph given to [`PageGraph::new`].
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum PageGraphError {
    /// A page names a parent past the last page.
    #[error("page {page} needs page {parent}, but there are only {pages} pages")]
    ParentOutOfRange {
        /// The page.
        page: PageId,
        /// The parent it names.
        parent: PageId,
        /// Pages in the graph.
        pages: usize,
    },
    /// The pages' needs loop, so none of the loop could ever be loaded first.
    #[error("pages {0:?} need each other in a loop: a page may only need coarser pages")]
    Cycle(Vec<PageId>),
    /// The byte and parent lists differ in length.
    #[error("{bytes} page sizes for {parents} parent lists: give one of each per page")]
    Lengths {
        /// Sizes given.
        bytes: usize,
        /// Parent lists given.
        parents: usize,
    },
}

/// Pages, their sizes, and which need which: of one mesh, or of a scene's meshes
/// appended one after another ([`PageGraph::append`]).
#[derive(Clone, PartialEq, Eq, Default)]
pub struct PageGraph {
    bytes: Vec<u64>,
    /// `parents[parent_start[p]..parent_start[p + 1]]` are page `p`'s parents.
    parent_start: Vec<u32>,
    parents: Vec<PageId>,
    dependent_start: Vec<u32>,
    dependents: Vec<PageId>,
    /// Longest chain of parents above each page: 0 for a page that needs none. Loads of
    /// equal priority go shallowest first, so parents are read before children.
    depth: Vec<u32>,
}

impl fmt::Debug for PageGraph {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.debug_struct("PageGraph")
            .field("pages", &self.len())
            .field("bytes", &self.total_bytes())
            .finish()
    }
}

/// Compressed rows: `starts[i]..starts[i + 1]` of the flattened lists are row `i`'s.
fn rows(lists: &[Vec<PageId>]) -> (Vec<u32>, Vec<PageId>) {
    let mut starts = Vec::with_capacity(lists.len() + 1);
    let mut flat = Vec::new();
    starts.push(0);
    for list in lists {
        flat.extend_from_slice(list);
        starts.push(flat.len() as u32);
    }
    (starts, flat)
}

impl PageGraph {
    /// Pages of `bytes[p]` bytes, page `p` needing `parents[p]`. Refused when a parent
    /// is out of range or the needs loop.
    pub fn new(bytes: Vec<u64>, parents: Vec<Vec<PageId>>) -> Result<Self, PageGraphError> {
        if bytes.len() != parents.len() {
            return Err(PageGraphError::Lengths {
                bytes: bytes.len(),
                parents: parents.len(),
            });
        }
        let pages = bytes.len();
        let mut dependents = vec![Vec::new(); pages];
        for (page, list) in parents.iter().enumerate() {
            for &parent in list {
                if parent as usize >= pages {
                    return Err(PageGraphError::ParentOutOfRange {
                        page: page as PageId,
                        parent,
                        pages,
                    });
                }
                dependents[parent as usize].push(page as PageId);
            }
        }
        // Depths in topological order (Kahn): a page is placed once its parents are.
        let mut waiting: Vec<usize> = parents.iter().map(Vec::len).collect();
        let mut depth = vec![0u32; pages];
        let mut ready: Vec<usize> = (0..pages).filter(|&p| waiting[p] == 0).collect();
        let mut placed = 0;
        while let Some(p) = ready.pop() {
            placed += 1;
            for &d in &dependents[p] {
                let d = d as usize;
                depth[d] = depth[d].max(depth[p] + 1);
                waiting[d] -= 1;
                if waiting[d] == 0 {
                    ready.push(d);
                }
            }
        }
        if placed != pages {
            let looped = (0..pages)
                .filter(|&p| waiting[p] > 0)
                .map(|p| p as PageId)
                .collect();
            return Err(PageGraphError::Cycle(looped));
        }
        let (parent_start, parents) = rows(&parents);
        let (dependent_start, dependents) = rows(&dependents);
        Ok(Self {
            bytes,
            parent_start,
            parents,
            dependent_start,
            dependents,
            depth,
        })
    }

    /// Appends `other`'s pages after this graph's, and returns the id its page 0 now has:
    /// a scene's meshes share one graph, each at its own base.
    pub fn append(&mut self, other: &PageGraph) -> PageId {
        let base = self.len() as PageId;
        if self.parent_start.is_empty() {
            self.parent_start.push(0);
            self.dependent_start.push(0);
        }
        let (parents_before, dependents_before) =
            (self.parents.len() as u32, self.dependents.len() as u32);
        self.bytes.extend_from_slice(&other.bytes);
        self.parents.extend(other.parents.iter().map(|&p| p + base));
        self.dependents
            .extend(other.dependents.iter().map(|&p| p + base));
        self.parent_start.extend(
            other
                .parent_start
                .iter()
                .skip(1)
                .map(|&s| s + parents_before),
        );
        self.dependent_start.extend(
            other
                .dependent_start
                .iter()
                .skip(1)
                .map(|&s| s + dependents_before),
        );
        self.depth.extend_from_slice(&other.depth);
        base
    }

    /// Pages in the graph.
    pub fn len(&self) -> usize {
        self.bytes.len()
    }

    /// Whether the graph has no pages.
    pub fn is_empty(&self) -> bool {
        self.bytes.is_empty()
    }

    /// Bytes of page `page`'s payload.
    pub fn bytes(&self, page: PageId) -> u64 {
        self.bytes[page as usize]
    }

    /// Bytes of every page together.
    pub fn total_bytes(&self) -> u64 {
        self.bytes.iter().sum()
    }

    /// The pages `page` needs resident before it may be.
    pub fn parents(&self, page: PageId) -> &[PageId] {
        let p = page as usize;
        &self.parents[self.parent_start[p] as usize..self.parent_start[p + 1] as usize]
    }

    /// The pages that need `page`.
    pub fn dependents(&self, page: PageId) -> &[PageId] {
        let p = page as usize;
        &self.dependents[self.dependent_start[p] as usize..self.dependent_start[p + 1] as usize]
    }

    /// Longest chain of parents above `page` (0 when it needs none).
    pub fn depth(&self, page: PageId) -> u32 {
        self.depth[page as usize]
    }
}

/// Two LOD-0 groups (0, 1) whose results were simplified together in group 2, whose
/// result is the root: the smallest DAG with a page that needs another, for the tests.
#[cfg(test)]
pub(crate) fn diamond() -> MeshDag {
    MeshDag {
        // Meshlets 0..4 are LOD 0 (children of 0 and 1), 4 and 5 came out of groups 0
        // and 1 and went into group 2, 6 is the root group 2 produced.
        source: vec![NO_GROUP, NO_GROUP, NO_GROUP, NO_GROUP, 0, 1, 2],
        parent: vec![0, 0, 1, 1, 2, 2, NO_GROUP],
        payload_bytes: vec![10, 20, 30, 40, 50, 60, 70],
        group_count: 3,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_page_holds_its_groups_children_and_needs_the_groups_its_result_went_into() {
        let pages = diamond().pages();
        assert_eq!(pages.len(), 3);
        assert_eq!(
            (pages.bytes(0), pages.bytes(1), pages.bytes(2)),
            (30, 70, 110)
        );
        assert_eq!(pages.parents(0), &[2]);
        assert_eq!(pages.parents(1), &[2]);
        assert!(pages.parents(2).is_empty());
        assert_eq!(pages.dependents(2), &[0, 1]);
        assert_eq!((pages.depth(0), pages.depth(2)), (1, 0));
    }

    #[test]
    fn appended_graphs_keep_their_links_at_their_base() {
        let one = diamond().pages();
        let mut scene = one.clone();
        let base = scene.append(&one);
        assert_eq!(base, 3);
        assert_eq!(scene.len(), 6);
        assert_eq!(scene.parents(4), &[5]);
        assert_eq!(scene.dependents(5), &[3, 4]);
        assert_eq!(scene.bytes(5), 110);
        assert_eq!(scene.depth(3), 1);
        let mut empty = PageGraph::default();
        assert_eq!(empty.append(&one), 0);
        assert_eq!(empty, one);
    }

    #[test]
    fn loops_and_dangling_parents_are_refused_by_name() {
        let err = PageGraph::new(vec![1, 1, 1], vec![vec![1], vec![0], vec![]]).unwrap_err();
        assert_eq!(err, PageGraphError::Cycle(vec![0, 1]));
        assert!(err.to_string().contains("coarser"), "{err}");
        let err = PageGraph::new(vec![1], vec![vec![4]]).unwrap_err();
        assert_eq!(
            err.to_string(),
            "page 0 needs page 4, but there are only 1 pages"
        );
        assert!(matches!(
            PageGraph::new(vec![1], vec![]),
            Err(PageGraphError::Lengths { .. })
        ));
    }
}
