//! Streaming in the GPU scene: meshes whose pages (`meshlight_stream::pages`) come and go
//! in a fixed pool at the end of the payload.
//!
//! Nothing a pass reads changes shape. Residency is written into the data the passes
//! already read, so the LOD test, the hierarchy walk and every decoder run unchanged:
//! - **The page table is the meshlet records' `data_offset`.** A page's meshlets point
//!   into the pool while it is resident; installing a page writes its bytes to its pool
//!   range and rewrites those offsets (one write: a page's meshlets are one range).
//!   While it is not, they point at word 0 and are never drawn.
//! - **Residency is the group's error.** A group whose page is not resident has error 0
//!   on the GPU: as a parent it is never perceptible (its children, which are not there,
//!   are not drawn), as a source it always hides (the meshlets it produced stand in for
//!   its children). That is exactly the cut "refined when its error shows and its page
//!   is resident", complete whenever the resident pages are closed under parents, which
//!   the streamer guarantees (`meshlight_stream::cut`). The real error goes to
//!   [`Streaming::stream_errors`], where the cull finds the groups it wants refined.
//! - **The hierarchy keeps pruning safely.** A node's smallest own error is the smallest
//!   over the meshlets below of their source group's error as the GPU has it (0 while
//!   that group's page is missing: the meshlet may have to stand in for it, so the
//!   subtree is not "too coarse"), kept up to date on every install and eviction for
//!   the leaves holding the group's result and their ancestors; with every page in, the
//!   walk prunes exactly as a resident scene's. The leaf of a group whose page is not
//!   resident has largest parent error 0, so the walk skips it: none of its meshlets
//!   can be drawn.

use meshlight_scene::MeshletAsset;
use meshlight_scene::asset::format::{NO_GROUP, SECTION_PAYLOAD};

use crate::error::SceneDataError;

/// One streamed group's page: what installing and evicting it rewrites.
#[derive(Clone, Debug, PartialEq)]
pub struct StreamedPage {
    /// The mesh the group belongs to (its index in `SceneData::meshes`).
    pub mesh: u32,
    /// The group's error as the asset has it.
    pub error: f32,
    /// Its children: scene meshlets `first_meshlet .. first_meshlet + meshlet_count`.
    pub first_meshlet: u32,
    /// Meshlets of the page.
    pub meshlet_count: u32,
    /// Payload words of the page.
    pub words: u32,
    /// Where the page lies in its asset file, in bytes from the start.
    pub file_offset: u64,
    /// Its checksum (`PageRecord::checksum`).
    pub checksum: u64,
    /// The hierarchy leaf holding the page's meshlets, and its largest parent error.
    pub leaf: u32,
    /// The leaf's `max_parent_error` while the page is resident.
    pub leaf_parent_error: f32,
    /// Where the page lies in the pool (words from the pool's start) while resident.
    pub resident_at: Option<u32>,
    /// The scene groups whose pages must be resident before this one (the groups its
    /// group's result was simplified in; see `meshlight_stream::pages`).
    pub parents: Vec<u32>,
}

/// A scene buffer streaming changes.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub enum StreamBuffer {
    /// [`crate::names::PAYLOAD`]: a page's words, in the pool.
    Payload,
    /// [`crate::names::MESHLETS`]: a page's meshlets' `data_offset`.
    Meshlets,
    /// [`crate::names::GROUPS`]: a group's error.
    Groups,
    /// [`crate::names::HIERARCHY_NODES`]: a leaf's largest parent error, and the
    /// smallest own errors above it.
    HierarchyNodes,
    /// [`crate::names::STREAM_ERRORS`]: a group's error while its page is missing.
    StreamErrors,
}

impl StreamBuffer {
    /// Every one, in order.
    pub const ALL: [StreamBuffer; 5] = [
        StreamBuffer::Payload,
        StreamBuffer::Meshlets,
        StreamBuffer::Groups,
        StreamBuffer::HierarchyNodes,
        StreamBuffer::StreamErrors,
    ];

    /// Its name (one of [`crate::names`]).
    pub fn name(self) -> &'static str {
        use crate::names;
        match self {
            StreamBuffer::Payload => names::PAYLOAD,
            StreamBuffer::Meshlets => names::MESHLETS,
            StreamBuffer::Groups => names::GROUPS,
            StreamBuffer::HierarchyNodes => names::HIERARCHY_NODES,
            StreamBuffer::StreamErrors => names::STREAM_ERRORS,
        }
    }
}

/// A range of a scene buffer that changed, to be written to the GPU.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct StreamWrite {
    /// The buffer.
    pub buffer: StreamBuffer,
    /// First element changed.
    pub first: usize,
    /// Elements changed.
    pub count: usize,
}

/// The streaming state of a [`crate::SceneData`].
#[derive(Clone, Debug, Default)]
pub struct Streaming {
    /// Per scene group, its page.
    pub pages: Vec<StreamedPage>,
    /// Per scene group: its real error while its page is not resident, 0 while it is.
    /// The cull asks for a group's page when this error shows.
    pub stream_errors: Vec<f32>,
    /// Per scene meshlet of a page: its first payload word within the page.
    pub page_offsets: Vec<u32>,
    /// The pool: payload words `pool_base .. pool_base + pool_words`.
    pub pool_base: u32,
    /// Words of the pool.
    pub pool_words: u32,
    /// Changes not yet written to the GPU.
    pub(crate) writes: Vec<StreamWrite>,
    /// Per scene hierarchy node, its parent ([`NO_NODE`] for a root).
    node_parents: Vec<u32>,
    /// Per scene group, the hierarchy leaves holding the meshlets it produced: their
    /// smallest own error follows the group's residency.
    result_leaves: Vec<Vec<u32>>,
}

/// No parent node: a hierarchy's root.
const NO_NODE: u32 = u32::MAX;

impl Streaming {
    /// A page's group, checked.
    fn page(&self, group: u32) -> Result<&StreamedPage, SceneDataError> {
        self.pages
            .get(group as usize)
            .ok_or_else(|| SceneDataError::Streaming {
                reason: format!(
                    "page {group} does not exist: the scene streams {} pages",
                    self.pages.len()
                ),
            })
    }
}

impl crate::SceneData {
    /// Whether the scene streams its meshes' pages (see [`crate::SceneData::streamed`]).
    pub fn streaming(&self) -> Option<&Streaming> {
        self.streaming.as_ref()
    }

    /// Adds `asset` in streamed form: its records, hierarchy and roots' payload, every
    /// page absent. Called by `add_mesh` on a streamed scene.
    pub(crate) fn add_streamed_parts(&mut self, asset: &MeshletAsset, mesh: u32) {
        // `add_mesh` has appended the whole asset: find where its parts begin.
        let header = *asset.header();
        let payload_base = (self.payload.len() - asset.payload().len()) as u32;
        let first_meshlet = self.meshes[mesh as usize].first_meshlet;
        let group_base = (self.groups.len() - asset.groups().len()) as u32;
        let node_base = self.hierarchy_roots[mesh as usize];
        let streaming = self.streaming.get_or_insert_with(Streaming::default);
        let pages = asset.pages();
        let payload_offset = u64::from(header.sections[SECTION_PAYLOAD].offset) * 4;
        // The leaf of each group: the leaf whose meshlets it simplified.
        let mut leaves = vec![(0u32, 0.0f32); pages.len()];
        for (i, node) in asset.nodes().iter().enumerate() {
            if let Some(&m) = asset.node_meshlets(node).first()
                && node.is_leaf()
            {
                let g = asset.meshlets()[m as usize].parent_group;
                if g != NO_GROUP {
                    leaves[g as usize] = (node_base + i as u32, node.max_parent_error);
                }
            }
        }
        // Each group's parents: the groups its result went into.
        let mut parents = vec![Vec::new(); pages.len()];
        for m in asset.meshlets() {
            if m.source_group != NO_GROUP && m.parent_group != NO_GROUP {
                parents[m.source_group as usize].push(group_base + m.parent_group);
            }
        }
        for list in &mut parents {
            list.sort_unstable();
            list.dedup();
        }
        for (g, (page, group)) in pages.iter().zip(asset.groups()).enumerate() {
            let children = asset.group_children(group);
            streaming.pages.push(StreamedPage {
                mesh,
                error: group.error,
                first_meshlet: first_meshlet + children[0],
                meshlet_count: group.child_count,
                words: page.words,
                file_offset: payload_offset + u64::from(page.first_word) * 4,
                checksum: page.checksum(),
                leaf: leaves[g].0,
                leaf_parent_error: leaves[g].1,
                resident_at: None,
                parents: std::mem::take(&mut parents[g]),
            });
            streaming.stream_errors.push(group.error);
            streaming.result_leaves.push(Vec::new());
        }
        for m in asset.meshlets() {
            let offset = match pages.get(m.parent_group as usize) {
                Some(page) => m.data_offset - page.first_word,
                None => 0,
            };
            streaming.page_offsets.push(offset);
        }
        // Absent: the pages' meshlets point at word 0, their groups have error 0, the
        // leaves that hold them prune, and no subtree is too coarse.
        let meshlets = &mut self.meshlets[first_meshlet as usize..];
        for m in meshlets.iter_mut() {
            if m.parent_group != NO_GROUP {
                m.data_offset = 0;
            }
        }
        for g in &mut self.groups[group_base as usize..] {
            g.error = 0.0;
        }
        let nodes = &mut self.hierarchy_nodes[node_base as usize..];
        streaming
            .node_parents
            .resize(node_base as usize + nodes.len(), NO_NODE);
        for (i, node) in nodes.iter_mut().enumerate() {
            // Every source group's page is missing: every own error is 0 on the GPU.
            node.min_error = 0.0;
            for child in node.children() {
                // `first_child` is rebased onto the shared nodes already.
                streaming.node_parents[child] = node_base + i as u32;
            }
            if node.is_leaf() {
                let leaf = node_base + i as u32;
                for &m in &self.hierarchy_clusters[node.clusters()] {
                    let source = self.meshlets[m as usize].source_group;
                    if source != NO_GROUP {
                        streaming.result_leaves[source as usize].push(leaf);
                    }
                }
            }
        }
        for leaves in &mut streaming.result_leaves[group_base as usize..] {
            leaves.sort_unstable();
            leaves.dedup();
        }
        for &(leaf, _) in &leaves {
            self.hierarchy_nodes[leaf as usize].max_parent_error = 0.0;
        }
        self.payload
            .truncate(payload_base as usize + header.resident_words as usize);
    }

    /// Makes room for a pool of `bytes` (rounded down to words) at the end of the
    /// payload, where installed pages go. Once per scene, after its meshes.
    pub fn reserve_pool(&mut self, bytes: u64) -> Result<(), SceneDataError> {
        let words = bytes / 4;
        let base = self.payload.len() as u64;
        crate::data::check_limit(
            "payload words",
            base + words,
            self.limits().max_payload_words as u64,
            "give a smaller pool (--pool-mb), or use a device with a larger storage binding",
        )?;
        let Some(streaming) = self.streaming.as_mut() else {
            return Err(SceneDataError::Streaming {
                reason: "the scene does not stream: make it with SceneData::streamed".into(),
            });
        };
        if streaming.pool_words != 0 {
            return Err(SceneDataError::Streaming {
                reason: "the pool is already reserved".into(),
            });
        }
        streaming.pool_base = base as u32;
        streaming.pool_words = words as u32;
        self.payload.resize((base + words) as usize, 0);
        self.geometry_version += 1;
        Ok(())
    }

    /// Installs page `group` at word `at` of the pool with its `words`: its bytes into the
    /// pool, its meshlets pointed at them, its group and leaf made live.
    pub fn install_page(
        &mut self,
        group: u32,
        at: u32,
        words: &[u32],
    ) -> Result<(), SceneDataError> {
        let Some(streaming) = self.streaming.as_mut() else {
            return Err(SceneDataError::Streaming {
                reason: "the scene does not stream".into(),
            });
        };
        let page = streaming.page(group)?;
        let span = PageSpan::of(page);
        if words.len() != page.words as usize {
            return Err(SceneDataError::Streaming {
                reason: format!(
                    "page {group} has {} words, {} were given",
                    page.words,
                    words.len()
                ),
            });
        }
        if u64::from(at) + u64::from(page.words) > u64::from(streaming.pool_words) {
            return Err(SceneDataError::Streaming {
                reason: format!(
                    "page {group} ({} words) at pool word {at} runs past the pool's {} words",
                    page.words, streaming.pool_words
                ),
            });
        }
        let start = (streaming.pool_base + at) as usize;
        self.payload[start..start + words.len()].copy_from_slice(words);
        let first = span.first_meshlet as usize;
        let count = span.meshlet_count as usize;
        for (m, record) in self.meshlets[first..first + count].iter_mut().enumerate() {
            record.data_offset = start as u32 + streaming.page_offsets[first + m];
        }
        self.groups[group as usize].error = span.error;
        self.hierarchy_nodes[span.leaf as usize].max_parent_error = span.leaf_parent_error;
        streaming.stream_errors[group as usize] = 0.0;
        streaming.pages[group as usize].resident_at = Some(at);
        streaming
            .writes
            .extend(page_writes(&span, group, Some((start, words.len()))));
        self.refresh_min_errors(group);
        Ok(())
    }

    /// After group `group`'s error changed on the GPU: the smallest own error of the
    /// leaves holding its result, and of their ancestors, recomputed.
    fn refresh_min_errors(&mut self, group: u32) {
        let streaming = self.streaming.as_mut().expect("a streamed scene");
        let mut changed = Vec::new();
        for &leaf in &streaming.result_leaves[group as usize] {
            let n = self.hierarchy_nodes[leaf as usize];
            let min = self.hierarchy_clusters[n.clusters()]
                .iter()
                .map(|&m| match self.meshlets[m as usize].source_group {
                    NO_GROUP => 0.0,
                    g => self.groups[g as usize].error,
                })
                .fold(f32::INFINITY, f32::min);
            changed.push((leaf, min));
        }
        // Up from each leaf while the value changes.
        while let Some((i, min)) = changed.pop() {
            let record = &mut self.hierarchy_nodes[i as usize];
            if record.min_error == min {
                continue;
            }
            record.min_error = min;
            streaming.writes.push(StreamWrite {
                buffer: StreamBuffer::HierarchyNodes,
                first: i as usize,
                count: 1,
            });
            let parent = streaming.node_parents[i as usize];
            if parent != NO_NODE {
                let p = self.hierarchy_nodes[parent as usize];
                let min = self.hierarchy_nodes[p.children()]
                    .iter()
                    .map(|c| c.min_error)
                    .fold(f32::INFINITY, f32::min);
                changed.push((parent, min));
            }
        }
    }

    /// Evicts page `group`: its group and leaf dead again, its meshlets pointed at word 0.
    /// Its pool words are left as they are, for the next page installed there.
    pub fn evict_page(&mut self, group: u32) -> Result<(), SceneDataError> {
        let Some(streaming) = self.streaming.as_mut() else {
            return Err(SceneDataError::Streaming {
                reason: "the scene does not stream".into(),
            });
        };
        let span = PageSpan::of(streaming.page(group)?);
        let first = span.first_meshlet as usize;
        for record in &mut self.meshlets[first..first + span.meshlet_count as usize] {
            record.data_offset = 0;
        }
        self.groups[group as usize].error = 0.0;
        self.hierarchy_nodes[span.leaf as usize].max_parent_error = 0.0;
        streaming.stream_errors[group as usize] = span.error;
        streaming.pages[group as usize].resident_at = None;
        streaming.writes.extend(page_writes(&span, group, None));
        self.refresh_min_errors(group);
        Ok(())
    }

    /// The changes since the last call, for [`crate::GpuScene::upload`]: per buffer,
    /// in order, overlapping and touching ranges merged (a node changed by several
    /// installs is written once).
    pub(crate) fn take_stream_writes(&mut self) -> Vec<StreamWrite> {
        let Some(streaming) = self.streaming.as_mut() else {
            return Vec::new();
        };
        let mut writes = std::mem::take(&mut streaming.writes);
        writes.sort_by_key(|w| (w.buffer, w.first));
        let mut merged: Vec<StreamWrite> = Vec::with_capacity(writes.len());
        for w in writes {
            match merged.last_mut() {
                Some(last) if last.buffer == w.buffer && w.first <= last.first + last.count => {
                    let end = (last.first + last.count).max(w.first + w.count);
                    last.count = end - last.first;
                }
                _ => merged.push(w),
            }
        }
        merged
    }
}

/// What installing or evicting a page rewrites, copied out of its [`StreamedPage`].
struct PageSpan {
    error: f32,
    first_meshlet: u32,
    meshlet_count: u32,
    leaf: u32,
    leaf_parent_error: f32,
}

impl PageSpan {
    fn of(page: &StreamedPage) -> Self {
        Self {
            error: page.error,
            first_meshlet: page.first_meshlet,
            meshlet_count: page.meshlet_count,
            leaf: page.leaf,
            leaf_parent_error: page.leaf_parent_error,
        }
    }
}

/// What installing (with the pool words written) or evicting a page changes.
fn page_writes(
    page: &PageSpan,
    group: u32,
    pool: Option<(usize, usize)>,
) -> impl Iterator<Item = StreamWrite> + use<> {
    let write = |buffer, first, count| StreamWrite {
        buffer,
        first,
        count,
    };
    [
        pool.map(|(first, count)| write(StreamBuffer::Payload, first, count)),
        Some(write(
            StreamBuffer::Meshlets,
            page.first_meshlet as usize,
            page.meshlet_count as usize,
        )),
        Some(write(StreamBuffer::Groups, group as usize, 1)),
        Some(write(StreamBuffer::HierarchyNodes, page.leaf as usize, 1)),
        Some(write(StreamBuffer::StreamErrors, group as usize, 1)),
    ]
    .into_iter()
    .flatten()
}
