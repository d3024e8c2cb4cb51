//! Streaming in the frame loop, for a streamed scene (`SceneData::streamed`): the first
//! cull lists the pages its cut wants (`cull_lod`'s streaming slots), the list comes back
//! through the readback ring a few frames later without a wait, the streamer
//! (`meshlight::stream::Streamer`) plans the frame's evictions, installs and reads, the
//! reads run on the loader's threads (or copy from an asset held in memory), and the
//! scene's records are rewritten so the next frame draws what is resident.
//!
//! Everything here runs before a frame is recorded, on the render thread, and never
//! waits: a page read this frame is installed by a later one.

use std::collections::BTreeMap;
use std::sync::Arc;
use std::time::{Duration, Instant};

use meshlight::cull_lod::{
    PAGE_MARKS_SLOT, PAGE_REQUEST_COUNT_SLOT, PAGE_REQUESTS_SLOT, STREAM_ERRORS_SLOT,
};
use meshlight::gpu_scene::SceneData;
use meshlight::gpu_scene::names::STREAM_ERRORS;
use meshlight::graph::file::{EntryKind, Pipeline, ResourceEntry};
use meshlight::graph::{Executor, GraphBuilder, GraphError, Imports, Result};
use meshlight::scene::MeshletAsset;
use meshlight::scene::asset::format::SECTION_PAYLOAD;
use meshlight::stream::loader::{Loader, PageCheck, PageFile, ReadJob, ReaderTimes};
use meshlight::stream::streamer::PageFailure;
use meshlight::stream::{Budget, Install, PageGraph, Request, Streamer};

/// The resource the per-group marks live in (imported: kept across frames). Named
/// unlike `cull_lod`'s slots, which bind by name: only the first cull takes them.
pub const PAGE_MARKS: &str = "stream_marks";
/// The frame's list of wanted pages.
pub const PAGE_REQUESTS: &str = "stream_requests";
/// Its two count words.
pub const PAGE_REQUEST_COUNT: &str = "stream_request_count";
/// The readback of the list.
pub const REQUESTS_READBACK: &str = "page_requests";
/// The readback of its count.
pub const REQUEST_COUNT_READBACK: &str = "page_request_count";
/// Frames the requests take to come back: as the counters.
pub const REQUESTS_LATENCY: u32 = super::frame_graph::COUNTS_LATENCY;
/// Most pages one frame lists; the rest are listed by the next frames (their marks are
/// set only when listed).
pub const MAX_REQUESTS: u64 = 16384;

/// The pool a scene streams through when none is asked for (a scene whose baked assets
/// do not fit the adapter's payload binding): a quarter of what that binding holds, so
/// the resident parts keep the rest: 511 MiB where bindings hold 2 GiB (an NVIDIA
/// H200 through wgpu), about Nanite's pool.
pub fn default_pool_bytes(limits: &meshlight::gpu_scene::data::Limits) -> u64 {
    let binding = u64::from(limits.max_payload_words) * 4;
    // In whole MiB.
    (binding / 4) & !0xf_ffff
}

/// The pool baked assets of `payload_words` stream through when no pool is asked for:
/// [`default_pool_bytes`] when they are more than the adapter's payload binding holds,
/// `None` (resident) when they fit.
pub fn pool_for_payload(
    payload_words: u64,
    limits: &meshlight::gpu_scene::data::Limits,
) -> Option<u64> {
    (payload_words > u64::from(limits.max_payload_words)).then(|| default_pool_bytes(limits))
}

/// Where a mesh's pages are read from.
#[derive(Clone, Debug)]
pub enum PageSource {
    /// The asset's file, read a page at a time on the loader's threads; each page read
    /// is checked against its checksum and then against `asset`, the file's resident
    /// part ([`MeshletAsset::open_resident`]), before it may be installed.
    File {
        /// The file the pages are read from.
        file: Arc<PageFile>,
        /// Its resident part, which the scene holds.
        asset: Arc<MeshletAsset>,
    },
    /// An asset held whole in memory (built in the process, or loaded whole): a page is
    /// a copy of its words.
    Memory(Arc<MeshletAsset>),
}

impl PageSource {
    /// Where `asset`'s pages come from: the file it was opened from for streaming
    /// ([`MeshletAsset::open_resident`]), or the asset itself when it is held whole.
    pub fn of(
        asset: &Arc<MeshletAsset>,
    ) -> std::result::Result<Self, meshlight::scene::SceneError> {
        Ok(match asset.page_file() {
            Some(path) => PageSource::File {
                file: PageFile::open(path).map_err(|source| meshlight::scene::SceneError::Io {
                    path: path.to_owned(),
                    source,
                })?,
                asset: Arc::clone(asset),
            },
            None => PageSource::Memory(Arc::clone(asset)),
        })
    }

    /// The asset (whole, or its resident part).
    pub fn asset(&self) -> &Arc<MeshletAsset> {
        match self {
            PageSource::File { asset, .. } | PageSource::Memory(asset) => asset,
        }
    }
}

/// The check of page `group` of `asset` read from `file`, after its checksum: the checks
/// [`MeshletAsset::open_resident`] leaves to each page.
fn page_check(file: &Arc<PageFile>, asset: &Arc<MeshletAsset>, group: u32) -> PageCheck {
    let (file, asset) = (Arc::clone(file), Arc::clone(asset));
    PageCheck::new(move |bytes| {
        asset
            .check_page(group as usize, &words_of(bytes))
            .map_err(|e| {
                format!(
                    "{}: page {group} is corrupt: {} {}; bake it again",
                    file.path().display(),
                    e.field,
                    e.problem
                )
            })
    })
}

/// A page's bytes as words: in place when they lie aligned (as a read's buffer does),
/// copied when not.
fn words_of(bytes: &[u8]) -> std::borrow::Cow<'_, [u32]> {
    match bytemuck::try_cast_slice(bytes) {
        Ok(words) => std::borrow::Cow::Borrowed(words),
        Err(_) => std::borrow::Cow::Owned(bytemuck::pod_collect_to_vec(bytes)),
    }
}

/// The resources a streamed frame adds to its pipeline, bound to the first culling pass
/// (`cull_lod` without `mode = "second"`): the scene's `stream_errors`, the page marks,
/// the request list and its count.
pub fn apply(p: &mut Pipeline, data: &SceneData) -> Result<()> {
    if data.streaming().is_none() {
        return Ok(());
    }
    let cull = meshlight::cull_lod::STAGE;
    if !p
        .passes_of(cull)
        .any(|e| !super::frame_graph::is_second_pass(e))
    {
        return Err(GraphError::PipelineFile {
            file: p.file().to_string(),
            message: format!(
                "the scene streams, but the pipeline has no first `{cull}` pass to ask for pages; add one"
            ),
        });
    }
    let groups = data.groups.len().max(1) as u64;
    let usage = ["STORAGE", "COPY_DST", "COPY_SRC"];
    for entry in [
        ResourceEntry::buffer(STREAM_ERRORS, EntryKind::Imported, "f32", Some(4), groups)
            .with_usage(&usage),
        ResourceEntry::buffer(PAGE_MARKS, EntryKind::Imported, "u32", Some(4), groups)
            .with_usage(&usage),
        ResourceEntry::buffer(
            PAGE_REQUESTS,
            EntryKind::Transient,
            "PageRequest",
            Some(8),
            groups.min(MAX_REQUESTS),
        ),
        ResourceEntry::buffer(PAGE_REQUEST_COUNT, EntryKind::Transient, "u32", None, 2),
    ] {
        if p.resource(&entry.name).is_none() {
            p.add_resource(entry)?;
        }
    }
    let mut threshold = None;
    // Every first cull asks for the pages of its cut: the camera's starts the frame's
    // list, the shadow views' add theirs after it (a caster's shadow reaches the detail
    // its cascade wants, and the pages it draws from are kept in use).
    for pass in p.passes_of_mut(cull) {
        if !super::frame_graph::is_second_pass(pass) {
            for (slot, resource) in [
                (STREAM_ERRORS_SLOT, STREAM_ERRORS),
                (PAGE_MARKS_SLOT, PAGE_MARKS),
                (PAGE_REQUESTS_SLOT, PAGE_REQUESTS),
                (PAGE_REQUEST_COUNT_SLOT, PAGE_REQUEST_COUNT),
            ] {
                pass.bind(slot, resource);
            }
            if super::shadows::is_shadow(pass) {
                pass.set_param("append_requests", true);
            } else {
                threshold = threshold.or(pass.param("lod_threshold_px").cloned());
            }
        }
    }
    // The `residency` view measures missing detail against the cull's threshold.
    for pass in p.passes_of_mut(meshlight::resolve::STAGE) {
        pass.bind(meshlight::resolve::STREAM_ERRORS, STREAM_ERRORS);
        if let Some(t) = &threshold {
            pass.set_param("lod_threshold_px", t.clone());
        }
    }
    Ok(())
}

/// The readbacks of the request list and its count, in a streamed frame.
pub fn add_readbacks(g: &mut GraphBuilder) -> Result<()> {
    if g.resource(PAGE_REQUESTS).is_none() {
        return Ok(());
    }
    g.readback_named(
        REQUEST_COUNT_READBACK,
        PAGE_REQUEST_COUNT,
        Some(0..8),
        REQUESTS_LATENCY,
    )?;
    g.readback_named(REQUESTS_READBACK, PAGE_REQUESTS, None, REQUESTS_LATENCY)
}

/// One frame of streaming, in figures (the newest frame's, and totals since the start).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct StreamStats {
    /// The streamer's figures for the frame (pool, pages, uploads, LOD scale).
    pub frame: meshlight::stream::streamer::FrameStats,
    /// Pages the GPU listed in the requests that came back this frame.
    pub listed: u32,
    /// Pages the GPU could not list (its list was full): listed by a later frame.
    pub unlisted: u32,
    /// Time the render thread spent on streaming for this frame: [`StreamPhases`]
    /// together.
    pub cpu: Duration,
    /// Where that time went.
    pub phases: StreamPhases,
    /// Time the reader threads spent reading and checking pages since the frame before
    /// (all threads together).
    pub readers: Duration,
    /// That time by step.
    pub reader_steps: ReaderTimes,
    /// Pages read so far.
    pub loaded_total: u64,
    /// Pages evicted so far.
    pub evicted_total: u64,
    /// Pages refused so far (a read failed or did not match its checksum).
    pub failed_total: u64,
}

impl StreamStats {
    /// The figures as (label, value) rows, for the viewer's overlay and the HTML pages.
    pub fn rows(&self) -> Vec<(String, String)> {
        let f = &self.frame;
        let mib = |b: u64| b as f64 / (1u64 << 20) as f64;
        let ms = |d: Duration| d.as_secs_f64() * 1e3;
        [
            (
                "pool",
                format!("{:.1} of {:.1} MiB", mib(f.pool_used), mib(f.pool_bytes)),
            ),
            ("pages resident", f.resident_pages.to_string()),
            (
                "this frame: wanted, missing, read, installed, evicted",
                format!(
                    "{}, {}, {}, {}, {}",
                    self.listed, f.requested, f.loads_started, f.installed, f.evicted
                ),
            ),
            (
                "uploaded this frame",
                format!("{:.1} KiB", f.bytes_uploaded as f64 / 1024.0),
            ),
            (
                "streamer CPU: render thread, readers",
                format!("{:.3} ms, {:.3} ms", ms(self.cpu), ms(self.readers)),
            ),
            (
                "render thread: lists, plan, scene, upload",
                format!(
                    "{:.3}, {:.3}, {:.3}, {:.3} ms",
                    ms(self.phases.requests),
                    ms(self.phases.plan),
                    ms(self.phases.scene),
                    ms(self.phases.upload)
                ),
            ),
            (
                "LOD scale from pool pressure",
                format!("{:.2}", f.lod_scale),
            ),
            (
                "pages read, evicted, refused so far",
                format!(
                    "{}, {}, {}",
                    self.loaded_total, self.evicted_total, self.failed_total
                ),
            ),
        ]
        .into_iter()
        .map(|(label, value)| (label.to_string(), value))
        .collect()
    }
}

/// Where the render thread's streaming time of one frame went.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct StreamPhases {
    /// Taking the request lists that came back and the reads that finished.
    pub requests: Duration,
    /// The streamer's plan (wants, queue, evictions, publishing).
    pub plan: Duration,
    /// Evictions and installs applied to the scene's records, and reads handed out.
    pub scene: Duration,
    /// The changed records and pages written to the GPU's buffers.
    pub upload: Duration,
}

impl StreamPhases {
    /// The phases with their names, for reports.
    pub fn named(&self) -> [(&'static str, Duration); 4] {
        [
            ("requests", self.requests),
            ("plan", self.plan),
            ("scene", self.scene),
            ("upload", self.upload),
        ]
    }

    /// All of them.
    pub fn total(&self) -> Duration {
        self.requests + self.plan + self.scene + self.upload
    }
}

/// One frame's request readbacks: (count words, list).
type RequestReadbacks = (Option<Vec<u8>>, Option<Vec<u8>>);

/// The streaming side of a renderer.
pub struct Streaming {
    streamer: Streamer,
    loader: Loader,
    sources: Vec<PageSource>,
    /// Per mesh, its first page (its groups are its pages, in order).
    first_page: Vec<u32>,
    marks: wgpu::Buffer,
    /// Request readbacks by frame, until both halves are in.
    back: BTreeMap<u64, RequestReadbacks>,
    stats: StreamStats,
    failures: Vec<PageFailure>,
    /// A frame has run since streaming started, so its readbacks exist.
    ran: bool,
    /// The readers' busy time at the frame before.
    readers_before: ReaderTimes,
}

impl Streaming {
    /// Streaming for `data` (a streamed scene with its pool reserved), reading mesh `i`'s
    /// pages from `sources[i]` with `threads` reader threads, within `budget`.
    pub fn new(
        gpu: &meshlight::graph::GpuContext,
        data: &SceneData,
        sources: Vec<PageSource>,
        budget: Budget,
        threads: usize,
    ) -> Result<Self> {
        let setting = |message: String| GraphError::Setting {
            setting: "streaming".into(),
            message,
        };
        let s = data
            .streaming()
            .ok_or_else(|| setting("the scene does not stream".into()))?;
        if sources.len() != data.meshes.len() {
            return Err(setting(format!(
                "{} page sources for {} meshes: give one per mesh, in the order they were added",
                sources.len(),
                data.meshes.len()
            )));
        }
        let graph = PageGraph::new(
            s.pages.iter().map(|p| u64::from(p.words) * 4).collect(),
            s.pages.iter().map(|p| p.parents.clone()).collect(),
        )
        .map_err(|e| setting(e.to_string()))?;
        let streamer = Streamer::new(graph, u64::from(s.pool_words) * 4, budget)
            .map_err(|e| setting(format!("{e} (`--pool-mb`)")))?;
        // Read-ahead: from a cold page cache, 8 threads read a world's pages 1.2–1.4×
        // as fast with it (three runs on the NVIDIA H200 machine, `bench --scenario
        // vg-stream`).
        let loader = Loader::with_read_ahead(threads, true)
            .map_err(|e| setting(format!("the page reader threads could not start: {e}")))?;
        let marks = gpu.buffer_with_data(
            PAGE_MARKS,
            &vec![0u8; data.groups.len().max(1) * 4],
            wgpu::BufferUsages::STORAGE
                | wgpu::BufferUsages::COPY_DST
                | wgpu::BufferUsages::COPY_SRC,
        );
        let first_page = (0..data.meshes.len() as u32)
            .map(|mesh| s.pages.partition_point(|p| p.mesh < mesh) as u32)
            .collect();
        Ok(Self {
            streamer,
            loader,
            sources,
            first_page,
            marks,
            back: BTreeMap::new(),
            stats: StreamStats::default(),
            failures: Vec::new(),
            ran: false,
            readers_before: ReaderTimes::default(),
        })
    }

    /// The frame's imports with the page marks added.
    pub fn imports(&self, imports: Imports) -> Imports {
        imports.buffer(PAGE_MARKS, &self.marks)
    }

    /// The LOD threshold's scale from pool pressure (the view's `lod_scale` is divided
    /// by it).
    pub fn lod_scale(&self) -> f32 {
        self.streamer.lod_scale()
    }

    /// The newest figures.
    pub fn stats(&self) -> StreamStats {
        self.stats
    }

    /// The streamer, for tools and tests that inspect residency.
    pub fn streamer(&self) -> &Streamer {
        &self.streamer
    }

    /// The pages refused since the last call (each was also logged as a warning).
    pub fn take_failures(&mut self) -> Vec<PageFailure> {
        std::mem::take(&mut self.failures)
    }

    /// Before frame `frame` is recorded: takes the requests that came back and the reads
    /// that finished, and applies the streamer's plan to the scene.
    pub fn before_frame(
        &mut self,
        executor: &mut Executor,
        data: &mut SceneData,
        frame: u64,
    ) -> Result<()> {
        let start = Instant::now();
        let (wanted, listed, unlisted) = match self.ran {
            true => self.take_requests(executor)?,
            false => (None, 0, 0),
        };
        self.ran = true;
        for (page, result) in self.loader.finished() {
            self.streamer.complete(page, result);
        }
        let planned = Instant::now();
        let plan = self.streamer.frame(frame, wanted.as_deref());
        let applied = Instant::now();
        let scene_error = |e: meshlight::gpu_scene::SceneDataError| GraphError::Setting {
            setting: "streaming".into(),
            message: e.to_string(),
        };
        for &page in &plan.evict {
            data.evict_page(page).map_err(scene_error)?;
        }
        let install = |data: &mut SceneData, installs: &[Install]| -> Result<()> {
            for i in installs {
                data.install_page(i.page, (i.allocation.offset / 4) as u32, &words_of(&i.data))
                    .map_err(scene_error)?;
            }
            Ok(())
        };
        install(data, &plan.install)?;
        let mut reads = Vec::with_capacity(plan.load.len());
        for load in &plan.load {
            let page = &data.streaming().expect("a streamed scene").pages[load.page as usize];
            match &self.sources[page.mesh as usize] {
                PageSource::File { file, asset } => reads.push(ReadJob {
                    page: load.page,
                    file: Arc::clone(file),
                    offset: page.file_offset,
                    bytes: load.bytes,
                    checksum: Some(page.checksum),
                    check: Some(page_check(
                        file,
                        asset,
                        load.page - self.first_page[page.mesh as usize],
                    )),
                }),
                PageSource::Memory(asset) => {
                    let payload = asset.header().sections[SECTION_PAYLOAD].offset;
                    let first = (page.file_offset / 4 - u64::from(payload)) as usize;
                    let words = &asset.payload()[first..first + page.words as usize];
                    self.streamer
                        .complete(load.page, Ok(bytemuck::cast_slice(words).to_vec()));
                }
            }
        }
        self.loader.submit_all(reads);
        // Pages copied from memory just now go in this frame, not the next.
        let ready = self.streamer.publish_ready();
        install(data, &ready)?;
        for failure in self.streamer.take_failures() {
            log::warn!("page {} refused: {}", failure.page, failure.reason);
            self.stats.failed_total += 1;
            self.failures.push(failure);
        }
        self.stats.loaded_total += plan.stats.loads_started as u64;
        self.stats.evicted_total += plan.stats.evicted as u64;
        self.stats.frame = plan.stats;
        self.stats.frame.installed += ready.len() as u32;
        self.stats.frame.resident_pages += ready.len() as u32;
        self.stats.frame.bytes_uploaded += ready.iter().map(|i| i.data.len() as u64).sum::<u64>();
        self.stats.listed = listed;
        self.stats.unlisted = unlisted;
        let done = Instant::now();
        self.stats.phases = StreamPhases {
            requests: planned - start,
            plan: applied - planned,
            scene: done - applied,
            upload: Duration::ZERO,
        };
        self.stats.cpu = self.stats.phases.total();
        let busy = self.loader.busy();
        self.stats.reader_steps = busy - self.readers_before;
        self.stats.readers = self.stats.reader_steps.total();
        self.readers_before = busy;
        Ok(())
    }

    /// Counts `spent`, the time the frame's scene upload took (the pages and records
    /// changed by [`Self::before_frame`]), as the render thread's streaming time.
    pub fn add_upload_time(&mut self, spent: Duration) {
        self.stats.phases.upload += spent;
        self.stats.cpu = self.stats.phases.total();
    }

    /// The pages the GPU listed in every frame whose requests are back, merged (a page
    /// at its highest priority; `None` when no frame's came back), with how many it
    /// listed and could not.
    fn take_requests(
        &mut self,
        executor: &mut Executor,
    ) -> Result<(Option<Vec<Request>>, u32, u32)> {
        while let Some(r) = executor.take_readback(REQUEST_COUNT_READBACK)? {
            self.back.entry(r.frame).or_default().0 = Some(r.bytes);
        }
        while let Some(r) = executor.take_readback(REQUESTS_READBACK)? {
            self.back.entry(r.frame).or_default().1 = Some(r.bytes);
        }
        let mut merged: Vec<(u32, f32)> = Vec::new();
        let (mut listed, mut unlisted, mut heard) = (0, 0, false);
        let complete: Vec<u64> = (self.back.iter())
            .filter(|(_, (count, list))| count.is_some() && list.is_some())
            .map(|(&frame, _)| frame)
            .collect();
        for frame in complete {
            let (Some(count), Some(list)) = self.back.remove(&frame).expect("listed above") else {
                continue;
            };
            heard = true;
            let words: Vec<u32> = bytemuck::pod_collect_to_vec(&count);
            let entries: Vec<[u32; 2]> = bytemuck::pod_collect_to_vec(&list);
            let written = (words[0] as usize).min(entries.len());
            listed += written as u32;
            unlisted += words[1].saturating_sub(words[0]);
            merged.extend(
                (entries[..written].iter()).map(|&[page, bits]| (page, f32::from_bits(bits))),
            );
        }
        // A frame's readbacks that never pair up (a resize between them) are dropped.
        while self.back.len() > 8 {
            self.back.pop_first();
        }
        // A page listed by several frames (when more than one came back) stays listed
        // twice: the streamer takes each page once, at its highest priority.
        let wanted = heard.then(|| {
            merged
                .into_iter()
                .map(|(page, priority)| Request { page, priority })
                .collect()
        });
        Ok((wanted, listed, unlisted))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use meshlight::gpu_scene::data::Limits;

    #[test]
    fn assets_stream_by_default_only_when_the_binding_cannot_hold_them() {
        let h200 = Limits::for_binding_size((1 << 31) - 1);
        assert_eq!(default_pool_bytes(&h200), 511 << 20);
        let held = u64::from(h200.max_payload_words);
        assert_eq!(pool_for_payload(held, &h200), None);
        assert_eq!(pool_for_payload(held + 1, &h200), Some(511 << 20));
        let small = Limits::for_binding_size(64 << 20);
        assert_eq!(pool_for_payload(held, &small), Some(15 << 20));
    }
}
