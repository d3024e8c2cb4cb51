//! A built meshlet asset: one word buffer holding header and sections, written to disk
//! as is and read back with one read and bytemuck casts.

pub mod checksum;
pub mod format;
#[cfg(feature = "build")]
mod pack;
#[cfg(feature = "build")]
pub use pack::Dropped;
pub mod scan;
pub mod summary;
pub mod triangles;
pub mod validate;

use std::io::Read;
use std::path::{Path, PathBuf};

use glam::Vec3;

use crate::compress::{
    NORMAL_BITS, Quantization, UvQuantization, bit_window, decode_color, decode_octahedral,
    get_bits, low_bits,
};
use crate::error::SceneError;
use format::*;

/// A meshlet asset, validated: every accessor below is infallible because loading
/// refused anything inconsistent.
#[derive(Clone)]
pub struct MeshletAsset {
    words: Vec<u32>,
    /// Passed every check `inspect` runs ([`MeshletAsset::load_verified`],
    /// [`MeshletAsset::verified`]), so whoever uploads it need not check it again.
    dag_verified: bool,
    /// Opened for streaming ([`MeshletAsset::open_resident`]): `words` ends with the
    /// resident part, and the pages are read from this file as needed.
    page_file: Option<PathBuf>,
}

/// Assets are equal when their bytes are: whether one was verified is not part of it.
impl PartialEq for MeshletAsset {
    fn eq(&self, other: &Self) -> bool {
        self.words == other.words
    }
}

impl std::fmt::Debug for MeshletAsset {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("MeshletAsset")
            .field("header", self.header())
            .field("bytes", &self.bytes().len())
            .finish()
    }
}

/// Where an asset's bytes go, for summaries and for choosing what to compress next.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct SizeBreakdown {
    /// The header.
    pub header: usize,
    /// The meshlet records.
    pub meshlet_records: usize,
    /// Group records plus their child lists.
    pub groups: usize,
    /// The position offsets of the vertex records.
    pub positions: usize,
    /// The normal offsets of the vertex records (their share of each record's bits).
    pub normals: usize,
    /// The UV blocks.
    pub uvs: usize,
    /// The vertex colour words.
    pub colors: usize,
    /// Local indices, including the padding of each meshlet's list to whole words.
    pub indices: usize,
    /// The culling hierarchy: nodes and cluster list.
    pub hierarchy: usize,
    /// The page records (ranges and checksums).
    pub pages: usize,
    /// LOD 0's open edges as baked.
    pub open_edges: usize,
}

impl SizeBreakdown {
    /// All the parts: the file size, which a test can hold the breakdown to.
    pub fn total(&self) -> usize {
        self.header
            + self.meshlet_records
            + self.groups
            + self.positions
            + self.normals
            + self.uvs
            + self.colors
            + self.indices
            + self.hierarchy
            + self.pages
            + self.open_edges
    }
}

/// The error for DAG invariant violations (`Ok` for none), worded the same for
/// `inspect` and for loading.
pub fn dag_error(path: &Path, problems: &[String]) -> Result<(), SceneError> {
    match problems.first() {
        None => Ok(()),
        Some(first) => Err(SceneError::AssetCorrupt {
            path: path.to_owned(),
            reason: format!(
                "{} DAG invariant violations, first: {first}",
                problems.len()
            ),
        }),
    }
}

/// Calls `each` with every vertex's local index and grid point of meshlet `m`, whose
/// vertex records start `data` (which may end early: a window past it reads zeros).
#[inline(always)]
pub(crate) fn grid_points(m: &MeshletRecord, data: &[u8], mut each: impl FnMut(usize, [u32; 3])) {
    let [bx, by, bz] = m.axis_bits();
    let masks = [bx, by, bz].map(low_bits);
    let stride = m.vertex_stride() as usize;
    let point =
        |o: [u64; 3]| [0, 1, 2].map(|k| m.grid_min[k].wrapping_add((o[k] & masks[k]) as u32));
    if bx + by + bz <= 57 {
        for v in 0..m.vertex_count() as usize {
            let w = bit_window(data, v * stride);
            each(v, point([w, w >> bx, w >> (bx + by)]));
        }
    } else {
        for v in 0..m.vertex_count() as usize {
            let at = v * stride;
            each(
                v,
                point([
                    bit_window(data, at),
                    bit_window(data, at + bx as usize),
                    bit_window(data, at + (bx + by) as usize),
                ]),
            );
        }
    }
}

/// One meshlet decoded back to floats, for tests, tools and CPU references.
#[derive(Debug, Clone, PartialEq)]
pub struct DecodedMeshlet {
    /// Positions, dequantised from the grid.
    pub positions: Vec<Vec3>,
    /// Grid coordinates: exact, so equal positions compare equal across meshlets.
    pub grid: Vec<[u32; 3]>,
    /// Unit normals, decoded from their octahedral components.
    pub normals: Vec<Vec3>,
    /// UVs, dequantised; empty when the asset has none.
    pub uvs: Vec<[f32; 2]>,
    /// Linear RGBA vertex colours; empty when the asset has none.
    pub colors: Vec<[f32; 4]>,
    /// Corners of each triangle as local vertex indices.
    pub triangles: Vec<[u8; 3]>,
}

impl MeshletAsset {
    /// Reads and validates an asset file. Any inconsistency is an error; nothing of a
    /// bad file is ever returned.
    pub fn load(path: &Path) -> Result<Self, SceneError> {
        let (words, len) = Self::read_words(path)?;
        Self::from_words(words, len, path)
    }

    /// A file's bytes as 32-bit words, and its length in bytes; a file too short for a
    /// header is refused here, with the magic or version message where its start says so.
    fn read_words(path: &Path) -> Result<(Vec<u32>, u64), SceneError> {
        // Before it is opened: opening a pipe would wait for a writer.
        crate::input::regular_file(path)?;
        let mut file = std::fs::File::open(path).map_err(|e| SceneError::io(path, e))?;
        let len = file.metadata().map_err(|e| SceneError::io(path, e))?.len();
        let header_bytes = (AssetHeader::WORDS * 4) as u64;
        if len < header_bytes {
            // Too short for a header: still say "wrong magic" when the start is not ours.
            let mut start = vec![0u8; len as usize];
            file.read_exact(&mut start)
                .map_err(|e| SceneError::io(path, e))?;
            if start.is_empty() || !MAGIC.starts_with(&start[..start.len().min(8)]) {
                return Err(SceneError::AssetMagic {
                    path: path.to_owned(),
                });
            }
            if let Some(v) = start.get(8..12) {
                let found = u32::from_le_bytes([v[0], v[1], v[2], v[3]]);
                if found != VERSION {
                    return Err(SceneError::AssetVersion {
                        path: path.to_owned(),
                        found,
                        expected: VERSION,
                    });
                }
            }
            return Err(SceneError::AssetTruncated {
                path: path.to_owned(),
                expected: header_bytes,
                actual: len,
            });
        }
        // Read into u32 words so every section is 4-byte aligned for the casts.
        let mut words = vec![0u32; len.div_ceil(4) as usize];
        let bytes: &mut [u8] = bytemuck::cast_slice_mut(&mut words);
        file.read_exact(&mut bytes[..len as usize])
            .map_err(|e| SceneError::io(path, e))?;
        Ok((words, len))
    }

    /// Validates a word buffer holding `len` bytes of an asset file.
    pub fn from_words(words: Vec<u32>, len: u64, path: &Path) -> Result<Self, SceneError> {
        Self::from_words_checked(words, len, path, false)
    }

    /// [`MeshletAsset::from_words`], and with `dag` the DAG invariants too. The checksum
    /// runs on one core while the structure (then the DAG) is checked on the other: the
    /// checks never trust the checksum, only the structure, so they may run before it
    /// is known, and the errors still come in the order a reader expects (checksum,
    /// then structure, then DAG).
    fn from_words_checked(
        words: Vec<u32>,
        len: u64,
        path: &Path,
        dag: bool,
    ) -> Result<Self, SceneError> {
        Self::from_prefix_checked(words, len, path, dag, None)
    }

    /// [`MeshletAsset::from_words_checked`] of the first `words` of a file of `len` bytes:
    /// the whole file, or with `page_file` (an asset opened for streaming) its resident
    /// part, whose pages are then checked as they are read ([`MeshletAsset::check_page`]).
    fn from_prefix_checked(
        words: Vec<u32>,
        len: u64,
        path: &Path,
        dag: bool,
        page_file: Option<PathBuf>,
    ) -> Result<Self, SceneError> {
        let p = || path.to_owned();
        let corrupt = |reason: String| SceneError::AssetCorrupt { path: p(), reason };
        let header_words = AssetHeader::WORDS;
        // Magic and version first: an older format's header may be shorter than this
        // one's, and its file must still get the re-bake message.
        if len >= 12 && words.len() >= 3 {
            let magic: &[u8] = bytemuck::cast_slice(&words[..2]);
            if magic != MAGIC {
                return Err(SceneError::AssetMagic { path: p() });
            }
            if words[2] != VERSION {
                return Err(SceneError::AssetVersion {
                    path: p(),
                    found: words[2],
                    expected: VERSION,
                });
            }
        }
        if (words.len() as u64) < header_words as u64 || len < (header_words * 4) as u64 {
            return Err(SceneError::AssetTruncated {
                path: p(),
                expected: (header_words * 4) as u64,
                actual: len,
            });
        }
        let header: AssetHeader =
            *bytemuck::from_bytes(bytemuck::cast_slice(&words[..header_words]));
        if header.magic != MAGIC {
            return Err(SceneError::AssetMagic { path: p() });
        }
        if header.version != VERSION {
            return Err(SceneError::AssetVersion {
                path: p(),
                found: header.version,
                expected: VERSION,
            });
        }
        let size = header.file_size[0] as u64 | ((header.file_size[1] as u64) << 32);
        if len < size {
            return Err(SceneError::AssetTruncated {
                path: p(),
                expected: size,
                actual: len,
            });
        }
        if len != size || !size.is_multiple_of(4) {
            return Err(corrupt(format!("{len} bytes where the header says {size}")));
        }
        let stored = header.checksum[0] as u64 | ((header.checksum[1] as u64) << 32);
        let total_words = size / 4;
        let asset = Self {
            words,
            dag_verified: false,
            page_file,
        };
        // The resident part's end comes from the header, not yet trusted: clamped, a
        // wrong one gives a checksum that does not match rather than a panic.
        let resident_end = (header.sections[SECTION_PAYLOAD].offset as usize)
            .saturating_add(header.resident_words as usize)
            .clamp(header_words, asset.words.len());
        let (found, checked) = rayon::join(
            || {
                checksum::file_checksum(
                    &asset.words[..header_words],
                    &asset.words[header_words..resident_end],
                )
            },
            || {
                validate::validate_prefix(&asset.words, total_words).map_err(|e| {
                    SceneError::AssetField {
                        path: p(),
                        field: e.field,
                        problem: e.problem,
                    }
                })?;
                if dag {
                    asset.verify_dag(path)?;
                }
                Ok(())
            },
        );
        if found != stored {
            return Err(SceneError::AssetChecksum {
                path: p(),
                expected: stored,
                found,
            });
        }
        checked?;
        // The pages after the structure: their ranges are trusted only once validated.
        // An asset opened for streaming has read none of them yet.
        if asset.page_file.is_none() {
            asset.check_pages(path)?;
        }
        Ok(Self {
            dag_verified: dag,
            ..asset
        })
    }

    /// Checks every page's bytes against its checksum.
    fn check_pages(&self, path: &Path) -> Result<(), SceneError> {
        let payload = self.payload();
        for (page, record) in self.pages().iter().enumerate() {
            let found = checksum::page_checksum(bytemuck::cast_slice(&payload[record.range()]));
            if found != record.checksum() {
                return Err(SceneError::AssetPageChecksum {
                    path: path.to_owned(),
                    page: page as u32,
                    expected: record.checksum(),
                    found,
                });
            }
        }
        Ok(())
    }

    /// Loads an asset and runs every check `meshlight inspect` runs: what
    /// [`MeshletAsset::load`] checks (magic, version, size, checksum, structure and the
    /// cross-checks of [`validate`]) and the DAG invariants of [`crate::verify::verify`]
    /// (parent links, error monotonicity, spheres, triangle records, cracks). The
    /// renderer loads through this, so nothing `inspect` rejects reaches the GPU, and
    /// it is refused with the same message.
    pub fn load_verified(path: &Path) -> Result<Self, SceneError> {
        let (words, len) = Self::read_words(path)?;
        Self::from_words_checked(words, len, path, true)
    }

    /// Opens an asset for streaming: reads only its resident part (the header, every
    /// record, the culling hierarchy and the roots' payload: [`Self::resident_bytes`])
    /// and checks it as [`MeshletAsset::load_verified`] checks a whole file, except for
    /// what needs the pages' bytes: each page is checked when it is read
    /// ([`MeshletAsset::check_page`], after its checksum), and the crack check, which
    /// compares neighbouring pages, is left to `bake` and `inspect`. The asset's
    /// [`Self::payload`] is the roots' alone; its pages are read from
    /// [`Self::page_file`].
    pub fn open_resident(path: &Path) -> Result<Self, SceneError> {
        crate::input::regular_file(path)?;
        let mut file = std::fs::File::open(path).map_err(|e| SceneError::io(path, e))?;
        let len = file.metadata().map_err(|e| SceneError::io(path, e))?.len();
        let header_words = AssetHeader::WORDS;
        if len < (header_words * 4) as u64 {
            // Too short for a header: the whole-file load names what is wrong.
            return Self::load(path);
        }
        let mut header = vec![0u32; header_words];
        file.read_exact(bytemuck::cast_slice_mut(&mut header))
            .map_err(|e| SceneError::io(path, e))?;
        let h: &AssetHeader = bytemuck::from_bytes(bytemuck::cast_slice(&header));
        // Untrusted until checked: clamped to the file, a wrong end gives a checksum or
        // structure error rather than a huge read.
        let end = (h.sections[SECTION_PAYLOAD].offset as u64 + h.resident_words as u64)
            .clamp(header_words as u64, len.div_ceil(4));
        let mut words = header;
        words.resize(end as usize, 0);
        let bytes: &mut [u8] = bytemuck::cast_slice_mut(&mut words);
        let read = (end * 4).min(len) as usize;
        file.read_exact(&mut bytes[header_words * 4..read])
            .map_err(|e| SceneError::io(path, e))?;
        Self::from_prefix_checked(words, len, path, true, Some(path.to_owned()))
    }

    /// Where an asset opened with [`MeshletAsset::open_resident`] reads its pages from;
    /// `None` for one held whole.
    pub fn page_file(&self) -> Option<&Path> {
        self.page_file.as_deref()
    }

    /// How many meshlets, from the first, have their data in [`Self::payload`]: all of
    /// them, or the roots of an asset opened for streaming (stored first).
    pub fn held_meshlets(&self) -> usize {
        match self.page_file {
            None => self.meshlets().len(),
            Some(_) => (self.header().root_count as usize).min(self.meshlets().len()),
        }
    }

    /// Checks page `group`'s `words` as read from [`Self::page_file`] (after its
    /// checksum): what loading a whole file checks of the page's meshlets' data, and
    /// what `inspect` checks of each meshlet alone. An error names the page's first
    /// problem.
    pub fn check_page(&self, group: usize, words: &[u32]) -> Result<(), validate::Invalid> {
        let (Some(page), Some(g)) = (self.pages().get(group), self.groups().get(group)) else {
            return Err(validate::Invalid {
                field: "page".into(),
                problem: format!("{group} is past the asset's {} pages", self.pages().len()),
            });
        };
        // Validated at open: a page's meshlets are one range.
        let first = self.group_children(g)[0] as usize;
        validate::check_page_data(
            self.header(),
            self.meshlets(),
            page,
            first..first + g.child_count as usize,
            words,
        )
    }

    /// This asset after every check of [`MeshletAsset::check_all`], marked so that
    /// [`MeshletAsset::is_verified`] says so; `path` names it in errors.
    pub fn verified(mut self, path: &Path) -> Result<Self, SceneError> {
        self.check_all(path)?;
        self.dag_verified = true;
        Ok(self)
    }

    /// Whether it passed every check `inspect` runs (loaded with
    /// [`MeshletAsset::load_verified`] or returned by [`MeshletAsset::verified`]).
    pub fn is_verified(&self) -> bool {
        self.dag_verified
    }

    /// Every check of [`MeshletAsset::load_verified`] on an asset already in memory
    /// (built, or read from a cache): the structural checks and the DAG invariants.
    /// `path` names it in errors.
    pub fn check_all(&self, path: &Path) -> Result<(), SceneError> {
        self.validate().map_err(|e| SceneError::AssetField {
            path: path.to_owned(),
            field: e.field,
            problem: e.problem,
        })?;
        self.verify_dag(path)
    }

    /// The DAG invariants, as an error naming the first violation and how many there
    /// are: what `inspect` and [`MeshletAsset::load_verified`] report.
    pub fn verify_dag(&self, path: &Path) -> Result<(), SceneError> {
        dag_error(path, &crate::verify::verify(self))
    }

    /// The structural checks [`MeshletAsset::load`] applies, for an asset built in
    /// memory: `bake` runs them before writing, so it never writes what `load` refuses.
    pub fn validate(&self) -> Result<(), validate::Invalid> {
        validate::validate(&self.words)
    }

    /// Writes the file image to `path` as it is: the words are already the file, with
    /// header and checksum, so saving is one write.
    pub fn save(&self, path: &Path) -> Result<(), SceneError> {
        if let Some(file) = &self.page_file {
            return Err(SceneError::Write {
                path: PathBuf::from(path),
                source: std::io::Error::other(format!(
                    "the asset was opened for streaming and holds its resident part only; \
                     copy {} instead",
                    file.display()
                )),
            });
        }
        std::fs::write(path, self.bytes()).map_err(|source| SceneError::Write {
            path: PathBuf::from(path),
            source,
        })
    }

    /// The file image.
    pub fn bytes(&self) -> &[u8] {
        bytemuck::cast_slice(&self.words)
    }

    /// The header, in place (no copy): counts, bounds, grids and where the sections lie.
    pub fn header(&self) -> &AssetHeader {
        bytemuck::from_bytes(bytemuck::cast_slice(&self.words[..AssetHeader::WORDS]))
    }

    /// A section; the payload of an asset opened for streaming ends with the roots'.
    fn section(&self, i: usize) -> &[u32] {
        let s = self.header().sections[i];
        &self.words[s.offset as usize..((s.offset + s.words) as usize).min(self.words.len())]
    }

    /// The meshlet records, in place, as the GPU receives them.
    pub fn meshlets(&self) -> &[MeshletRecord] {
        bytemuck::cast_slice(self.section(SECTION_MESHLETS))
    }

    /// The group records, in place: where meshlets take their own and parent LOD spheres
    /// and errors.
    pub fn groups(&self) -> &[GroupRecord] {
        bytemuck::cast_slice(self.section(SECTION_GROUPS))
    }

    /// Every group's children (meshlet ids), one list after another.
    pub fn children(&self) -> &[u32] {
        self.section(SECTION_CHILDREN)
    }

    /// The meshlets simplified in `group`.
    pub fn group_children(&self, group: &GroupRecord) -> &[u32] {
        &self.children()
            [group.first_child as usize..(group.first_child + group.child_count) as usize]
    }

    /// Packed vertex and index words, addressed by [`MeshletRecord::data_offset`]; of an
    /// asset opened for streaming ([`Self::open_resident`]), the roots' alone, and its
    /// other meshlets are not decoded from it.
    pub fn payload(&self) -> &[u32] {
        self.section(SECTION_PAYLOAD)
    }

    /// One page per group: where its children's payload lies, and its checksum.
    pub fn pages(&self) -> &[PageRecord] {
        bytemuck::cast_slice(self.section(SECTION_PAGES))
    }

    /// LOD 0's open edges as the bake recorded them (none for a closed mesh); see
    /// [`crate::open_edges`]. Empty if the section does not hold whole records, which
    /// validation refuses.
    pub fn open_edges(&self) -> &[OpenEdgeRecord] {
        bytemuck::try_cast_slice(self.section(SECTION_OPEN_EDGES)).unwrap_or_default()
    }

    /// Bytes of the resident part: every section before the payload and the roots'
    /// payload, the prefix of the file a streamed scene reads whole.
    pub fn resident_bytes(&self) -> u64 {
        (self.header().sections[SECTION_PAYLOAD].offset as u64
            + self.header().resident_words as u64)
            * 4
    }

    /// The culling hierarchy's nodes, root first (see [`crate::hierarchy`]).
    pub fn nodes(&self) -> &[NodeRecord] {
        bytemuck::cast_slice(self.section(SECTION_NODES))
    }

    /// The meshlet ids the hierarchy's leaves take, each meshlet once, in depth-first
    /// order ([`NodeRecord::first_cluster`] indexes it).
    pub fn node_clusters(&self) -> &[u32] {
        self.section(SECTION_NODE_CLUSTERS)
    }

    /// The meshlets below `node`.
    pub fn node_meshlets(&self, node: &NodeRecord) -> &[u32] {
        &self.node_clusters()[node.clusters()]
    }

    /// A meshlet's own LOD sphere and error: its source group's, or its bounds and zero
    /// at LOD 0.
    pub fn lod(&self, m: &MeshletRecord) -> ([f32; 4], f32) {
        match self.groups().get(m.source_group as usize) {
            Some(g) => (g.lod_sphere, g.error),
            None => (m.bounds, 0.0),
        }
    }

    /// A meshlet's parent LOD sphere and error: its parent group's, or an infinite
    /// error (`f32::MAX`, which shaders handle) for roots.
    pub fn parent_lod(&self, m: &MeshletRecord) -> ([f32; 4], f32) {
        match self.groups().get(m.parent_group as usize) {
            Some(g) => (g.lod_sphere, g.error),
            None => ([0.0; 4], f32::MAX),
        }
    }

    /// The position grid of the header, to decode positions or bound their error.
    pub fn quantization(&self) -> Quantization {
        let h = self.header();
        Quantization {
            origin: Vec3::from(h.quant_origin),
            step: h.quant_step,
            bits: h.quant_bits,
        }
    }

    /// Bytes per part of the file; the parts add up to the file size.
    pub fn size_breakdown(&self) -> SizeBreakdown {
        let flags = self.header().flags;
        let mut b = SizeBreakdown {
            header: AssetHeader::WORDS * 4,
            meshlet_records: self.section(SECTION_MESHLETS).len() * 4,
            groups: (self.section(SECTION_GROUPS).len() + self.children().len()) * 4,
            hierarchy: (self.section(SECTION_NODES).len() + self.node_clusters().len()) * 4,
            pages: self.section(SECTION_PAGES).len() * 4,
            open_edges: self.section(SECTION_OPEN_EDGES).len() * 4,
            ..Default::default()
        };
        for m in self.meshlets() {
            let l = PayloadLayout::of(m, flags);
            // Vertex records interleave positions and normals: split their words by bits.
            let vertex_bytes = (l.triangles - l.vertices) as usize * 4;
            let [nx, ny] = m.normal_bits();
            let normal_share = (nx + ny) as usize;
            let normals = vertex_bytes * normal_share / m.vertex_stride().max(1) as usize;
            b.positions += vertex_bytes - normals;
            b.normals += normals;
            b.indices += (l.uvs - l.triangles) as usize * 4;
            b.uvs += (l.colors - l.uvs) as usize * 4;
            b.colors += (l.end - l.colors) as usize * 4;
        }
        b
    }

    /// A meshlet's triangle records (see [`triangles`]).
    pub fn triangle_block(&self, m: &MeshletRecord) -> &[u32] {
        let layout = PayloadLayout::of(m, self.header().flags);
        &self.payload()
            [(m.data_offset + layout.triangles) as usize..(m.data_offset + layout.uvs) as usize]
    }

    /// One meshlet's grid points and triangles only: what the DAG checks compare, without
    /// decoding normals and UVs.
    pub fn decode_topology(&self, index: usize) -> (Vec<[u32; 3]>, Vec<[u8; 3]>) {
        (self.decode_grid(index), self.decode_triangles(index))
    }

    /// One meshlet's grid points, in local vertex order.
    pub fn decode_grid(&self, index: usize) -> Vec<[u32; 3]> {
        let m = &self.meshlets()[index];
        let mut grid = Vec::with_capacity(m.vertex_count() as usize);
        self.for_each_grid_point(m, |_, p| grid.push(p));
        grid
    }

    /// Calls `each` with every vertex's local index and grid point, reading positions only
    /// and a whole vertex record at a time: what the load-time checks decode every
    /// vertex of an asset with.
    #[inline(always)]
    pub fn for_each_grid_point(&self, m: &MeshletRecord, each: impl FnMut(usize, [u32; 3])) {
        // From the meshlet's data on: a record's window may reach past its block, and the
        // masks drop what it reads there.
        grid_points(
            m,
            bytemuck::cast_slice(&self.payload()[m.data_offset as usize..]),
            each,
        );
    }

    /// One meshlet's triangles as local vertex indices, clamped as the GPU clamps them.
    pub fn decode_triangles(&self, index: usize) -> Vec<[u8; 3]> {
        let m = &self.meshlets()[index];
        let mut out = Vec::with_capacity(m.triangle_count() as usize);
        self.for_each_triangle(m, |t| out.push(t));
        out
    }

    /// Calls `each` with every triangle's local corners in order, clamped as the GPU
    /// clamps them.
    pub fn for_each_triangle(&self, m: &MeshletRecord, mut each: impl FnMut([u8; 3])) {
        let (vc, tc) = (m.vertex_count(), m.triangle_count());
        let last = vc.max(1) as i64 - 1;
        triangles::for_each_stored(self.triangle_block(m), m.triangle_bits(), vc, tc, |_, c| {
            each(c.map_or([0; 3], |c| c.map(|c| c.clamp(0, last) as u8)))
        });
    }

    /// Decodes one meshlet (as the GPU would).
    pub fn decode_meshlet(&self, index: usize) -> DecodedMeshlet {
        let h = self.header();
        let m = &self.meshlets()[index];
        let layout = PayloadLayout::of(m, h.flags);
        let data = &self.payload()[m.data_offset as usize..(m.data_offset + layout.end) as usize];
        let vc = m.vertex_count() as usize;
        let bits = m.axis_bits();
        let quant = self.quantization();
        let vertex_block = &data[..layout.triangles as usize];
        let stride = m.vertex_stride() as usize;
        // Every field is in range (validated at load); `unwrap_or(0)` only keeps a
        // decoder of untrusted words from panicking.
        let field = |block: &[u32], at: usize, bits: u32| get_bits(block, at, bits).unwrap_or(0);
        let (normal_min, normal_bits) = (m.normal_min(), m.normal_bits());
        let mut grid = Vec::with_capacity(vc);
        let mut normals = Vec::with_capacity(vc);
        for v in 0..vc {
            let mut at = v * stride;
            grid.push([0, 1, 2].map(|k| {
                let d = field(vertex_block, at, bits[k]);
                at += bits[k] as usize;
                m.grid_min[k] + d
            }));
            let oct = [0, 1].map(|k| {
                let d = field(vertex_block, at, normal_bits[k]);
                at += normal_bits[k] as usize;
                normal_min[k] + d as i32
            });
            normals.push(decode_octahedral(oct, NORMAL_BITS));
        }
        let uvq = UvQuantization {
            min: h.uv_min,
            step: h.uv_step,
        };
        let uvs = if h.has_uvs() {
            let origin = [data[layout.uvs as usize], data[layout.uvs as usize + 1]];
            let uv_block = &data[layout.uv_words as usize..];
            let [bu, bv] = m.uv_bits();
            (0..m.vertex_count() as usize)
                .map(|v| {
                    let at = v * (bu + bv) as usize;
                    let offset = [
                        field(uv_block, at, bu),
                        field(uv_block, at + bu as usize, bv),
                    ];
                    uvq.decode(origin, offset)
                })
                .collect()
        } else {
            Vec::new()
        };
        let triangle_block = &data[layout.triangles as usize..];
        let (vc, tc) = (m.vertex_count(), m.triangle_count());
        let triangles = (0..tc)
            .map(|t| {
                triangles::decode(triangle_block, t, m.triangle_bits(), vc, tc).map(|i| i as u8)
            })
            .collect();
        let colors = if h.has_colors() {
            data[layout.colors as usize..layout.end as usize]
                .iter()
                .map(|&w| decode_color(w))
                .collect()
        } else {
            Vec::new()
        };
        DecodedMeshlet {
            positions: grid.iter().map(|&q| quant.dequantize(q)).collect(),
            grid,
            normals,
            uvs,
            colors,
            triangles,
        }
    }
}
