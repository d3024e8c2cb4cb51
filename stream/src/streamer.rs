//! The streamer: which pages to read, publish and evict each frame.
//!
//! Each frame the renderer hands over the pages the GPU wanted (read back a few frames
//! late: pages the cut would refine, resident or not, with a priority such as the
//! screen-space error) and gets back a [`FramePlan`]: pages to evict, pages to install
//! (bytes and where in the pool), and pages to start reading. Reads complete whenever
//! the reader is done ([`Streamer::complete`]), in any order.
//!
//! The rules, each kept as an invariant the tests check on every frame:
//! - **Parents first.** A page is read only once every page it needs is at least being
//!   read, and published only once they are all resident, in the order reads were
//!   issued. So the resident set is always closed under parents, which is what makes
//!   every cut complete ([`crate::cut`]). A wanted page's missing ancestors are wanted
//!   with its priority; among equals the shallower goes first.
//! - **Evict only what nothing needs.** A page is evicted only when no page that needs it
//!   is resident or being read, and it has not been wanted for
//!   [`Budget::keep_frames`] frames (the GPU's word lags by the readback's latency);
//!   least recently wanted first, and only when a read needs the room.
//! - **Budgets.** Installs and uploaded bytes per frame (a page larger than the byte
//!   budget goes alone), reads in flight, evictions per frame.
//! - **Pressure, not thrashing.** When the pages the view wants outgrow the pool, the LOD
//!   threshold's scale rises ([`crate::pressure`]) instead of evicting pages in use.
//! - **A bad page is refused.** A read that fails or returns the wrong size marks the
//!   page failed for the rest of the run: it is never published, its group keeps its
//!   coarser level, and [`Streamer::take_failures`] names it.

use std::cmp::Ordering;
use std::collections::{BTreeSet, BinaryHeap, HashMap};

use crate::pages::{PageGraph, PageId};
use crate::pool::{Allocation, PoolAllocator};
use crate::pressure::LodPressure;

/// Per-frame limits of the streamer's work.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Budget {
    /// Pages published per frame at most.
    pub installs_per_frame: u32,
    /// Bytes uploaded per frame at most; a single page larger than this is still
    /// installed, alone.
    pub upload_bytes_per_frame: u64,
    /// Reads in flight at most.
    pub loads_in_flight: u32,
    /// Pages evicted per frame at most.
    pub evictions_per_frame: u32,
    /// Frames a page must go unwanted before it may be evicted: at least the readback's
    /// latency, so a page the GPU is still asking for is never taken away.
    pub keep_frames: u64,
    /// Levels below a requested page read along with it (1: its children, the next
    /// level finer; 2: their children too; 0: none), after every page the view wants,
    /// only into free room (never evicting for them), and evictable from the frame after
    /// they arrive until the view asks for them: the view that wants a page usually
    /// wants the levels below next, and asking for each only once the one above is in
    /// costs a readback's round trip per level.
    pub prefetch_levels: u32,
}

impl Default for Budget {
    /// 1,024 installs and 32 MiB a frame, 256 reads in flight, 1,024 evictions a frame,
    /// pages kept 8 frames after their last want, children prefetched. A page here is
    /// one group's children (about 9 KB on a generated world, where Nanite's are 128
    /// KiB), so the count binds before the bytes: over that world a cold start takes 30
    /// frames with 1,024 installs a frame, 40 with 128 and 66 with 64, whose worst
    /// render-thread frame is 0.83 ms rather than 1.25 (NVIDIA H200's machine, `bench
    /// --scenario vg-stream`). Lower it where the render thread's worst frame matters
    /// more than how soon detail arrives.
    fn default() -> Self {
        Self {
            installs_per_frame: 1024,
            upload_bytes_per_frame: 32 << 20,
            loads_in_flight: 256,
            evictions_per_frame: 1024,
            keep_frames: 8,
            prefetch_levels: 1,
        }
    }
}

/// A page the GPU wanted this frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Request {
    /// The page.
    pub page: PageId,
    /// Larger goes first (e.g. the group's projected error in pixels).
    pub priority: f32,
}

/// A read to start: the reader fetches the page's bytes and hands them to
/// [`Streamer::complete`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Load {
    /// The page.
    pub page: PageId,
    /// Its size in bytes.
    pub bytes: u64,
}

/// A page to publish: upload `data` at `allocation.offset` of the pool, then mark the
/// page resident in the page table.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Install {
    /// The page.
    pub page: PageId,
    /// Where in the pool.
    pub allocation: Allocation,
    /// The page's bytes, as read.
    pub data: Vec<u8>,
}

/// What one frame changes. Apply the evictions before the installs: an install may
/// reuse an evicted page's bytes.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct FramePlan {
    /// Pages to mark not resident.
    pub evict: Vec<PageId>,
    /// Pages to upload and mark resident, parents before children.
    pub install: Vec<Install>,
    /// Reads to start.
    pub load: Vec<Load>,
    /// The frame's figures.
    pub stats: FrameStats,
}

/// One frame of the streamer, in figures.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct FrameStats {
    /// Wanted pages (and their ancestors) not resident.
    pub requested: u32,
    /// Reads started.
    pub loads_started: u32,
    /// Pages published.
    pub installed: u32,
    /// Pages evicted.
    pub evicted: u32,
    /// Bytes of the pages published.
    pub bytes_uploaded: u64,
    /// Pool bytes reserved (resident pages and reads in flight).
    pub pool_used: u64,
    /// Pool bytes.
    pub pool_bytes: u64,
    /// Pages resident.
    pub resident_pages: u32,
    /// Reads in flight or read and waiting for their parents.
    pub in_flight: u32,
    /// Bytes of every page the view wants (and their ancestors), resident or not.
    pub wanted_bytes: u64,
    /// The LOD threshold's scale from pool pressure.
    pub lod_scale: f32,
    /// Pages refused so far.
    pub failed_pages: u32,
}

/// Where a page is.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum PageState {
    /// Not on the GPU, not being read.
    Absent,
    /// Being read; room in the pool is reserved.
    Loading,
    /// Read, waiting for its parents or the frame's budget to be published.
    Loaded,
    /// On the GPU: its group may be refined.
    Resident,
    /// Refused (a read failed or returned the wrong bytes); never published.
    Failed,
}

/// A page refused, and why.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct PageFailure {
    /// The page.
    pub page: PageId,
    /// What was wrong with it.
    pub reason: String,
}

/// What is wrong with a streamer's setup.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum StreamError {
    /// A page cannot fit in the pool even when it is empty.
    #[error(
        "the page pool of {pool} bytes cannot hold page {page} of {page_bytes} bytes: \
         give the pool at least {page_bytes} bytes"
    )]
    PoolTooSmall {
        /// The pool's bytes.
        pool: u64,
        /// The largest page.
        page: PageId,
        /// Its bytes.
        page_bytes: u64,
    },
}

/// A queued read, ordered by priority, then shallower first, then page id.
#[derive(Debug, Clone, Copy)]
struct Queued {
    priority: f32,
    depth: u32,
    page: PageId,
}

impl PartialEq for Queued {
    fn eq(&self, other: &Self) -> bool {
        self.cmp(other) == Ordering::Equal
    }
}
impl Eq for Queued {}
impl PartialOrd for Queued {
    fn partial_cmp(&self, other: &Self) -> Option<Ordering> {
        Some(self.cmp(other))
    }
}
impl Ord for Queued {
    fn cmp(&self, other: &Self) -> Ordering {
        self.priority
            .total_cmp(&other.priority)
            .then(other.depth.cmp(&self.depth))
            .then(other.page.cmp(&self.page))
    }
}

/// Not queued, in [`Streamer::queued`].
const NOT_QUEUED: f32 = f32::NEG_INFINITY;

/// Not an eviction candidate, in [`Streamer::evictable_key`].
const NOT_EVICTABLE: u64 = u64::MAX;

/// The streaming policy over one [`PageGraph`] and one pool.
#[derive(Debug)]
pub struct Streamer {
    graph: PageGraph,
    budget: Budget,
    pressure: LodPressure,
    pool: PoolAllocator,
    state: Vec<PageState>,
    allocation: Vec<Option<Allocation>>,
    /// Bytes read, waiting to be published.
    data: HashMap<PageId, Vec<u8>>,
    /// Last frame each page was wanted.
    last_wanted: Vec<u64>,
    /// Dependents being read, read or resident: while any, the page stays.
    holders: Vec<u32>,
    /// This frame, a wanted page found no room: every resident page is needed.
    out_of_room: bool,
    /// Resident pages without holders, by (last wanted, page): eviction candidates.
    evictable: BTreeSet<(u64, PageId)>,
    /// Each page's key in `evictable` ([`NOT_EVICTABLE`] when it is not there), which
    /// may be older than its last want (see [`Streamer::touch`]).
    evictable_key: Vec<u64>,
    queue: BinaryHeap<Queued>,
    /// The priority a page is queued at ([`NOT_QUEUED`] when it is not).
    queued: Vec<f32>,
    /// Reads in the order they were issued, for publishing in that order.
    issued: Vec<PageId>,
    /// The frame a page was last visited in while taking the frame's wants.
    visited: Vec<u64>,
    failures: Vec<PageFailure>,
    failed_pages: u32,
    resident_pages: u32,
    frame: u64,
    /// Pages queued only as prefetches (not wanted themselves): read only into free
    /// room, never at the cost of an eviction.
    prefetched: Vec<bool>,
    /// Installs and bytes published in the current frame, against its budgets.
    installed_this_frame: u32,
    uploaded_this_frame: u64,
}

impl Streamer {
    /// A streamer for `graph`'s pages over a pool of `pool_bytes`, nothing resident.
    pub fn new(graph: PageGraph, pool_bytes: u64, budget: Budget) -> Result<Self, StreamError> {
        let pool = PoolAllocator::new(pool_bytes);
        if let Some(page) = (0..graph.len() as PageId).max_by_key(|&p| graph.bytes(p))
            && PoolAllocator::reserved(graph.bytes(page)) > pool.capacity()
        {
            return Err(StreamError::PoolTooSmall {
                pool: pool_bytes,
                page,
                page_bytes: graph.bytes(page),
            });
        }
        let n = graph.len();
        Ok(Self {
            graph,
            budget,
            pressure: LodPressure::default(),
            pool,
            state: vec![PageState::Absent; n],
            allocation: vec![None; n],
            data: HashMap::new(),
            last_wanted: vec![0; n],
            holders: vec![0; n],
            out_of_room: false,
            evictable: BTreeSet::new(),
            evictable_key: vec![NOT_EVICTABLE; n],
            queue: BinaryHeap::new(),
            queued: vec![NOT_QUEUED; n],
            issued: Vec::new(),
            visited: vec![u64::MAX; n],
            failures: Vec::new(),
            failed_pages: 0,
            resident_pages: 0,
            frame: 0,
            installed_this_frame: 0,
            uploaded_this_frame: 0,
            prefetched: vec![false; n],
        })
    }

    /// Replaces the pressure's band and step.
    pub fn with_pressure(mut self, pressure: LodPressure) -> Self {
        self.pressure = pressure;
        self
    }

    /// The pages streamed.
    pub fn graph(&self) -> &PageGraph {
        &self.graph
    }

    /// The budgets.
    pub fn budget(&self) -> &Budget {
        &self.budget
    }

    /// Where page `page` is.
    pub fn state(&self, page: PageId) -> PageState {
        self.state[page as usize]
    }

    /// Whether page `page` is resident: its group may be refined.
    pub fn is_resident(&self, page: PageId) -> bool {
        self.state(page) == PageState::Resident
    }

    /// Where a page in the pool lies (reserved once its read starts).
    pub fn allocation(&self, page: PageId) -> Option<Allocation> {
        self.allocation[page as usize]
    }

    /// The LOD threshold's scale from pool pressure (1 without).
    pub fn lod_scale(&self) -> f32 {
        self.pressure.scale()
    }

    /// Pool bytes reserved (resident pages and reads).
    pub fn pool_used(&self) -> u64 {
        self.pool.used()
    }

    /// Pool bytes.
    pub fn pool_bytes(&self) -> u64 {
        self.pool.capacity()
    }

    /// The pages refused since the last call, for the renderer's warnings.
    pub fn take_failures(&mut self) -> Vec<PageFailure> {
        std::mem::take(&mut self.failures)
    }

    /// Publishes, within what is left of this frame's budgets, the pages whose reads
    /// finished since [`Self::frame`] planned it (a reader that completes at once, such
    /// as one copying from memory, installs in the same frame). Apply these after the
    /// frame plan's.
    pub fn publish_ready(&mut self) -> Vec<Install> {
        let mut plan = FramePlan::default();
        self.publish(&mut plan);
        plan.install
    }

    /// A read finished: `Ok` with the page's bytes, or `Err` with what went wrong. A
    /// result for a page that is not being read is ignored.
    pub fn complete(&mut self, page: PageId, result: Result<Vec<u8>, String>) {
        if self.state(page) != PageState::Loading {
            return;
        }
        let expected = self.graph.bytes(page);
        match result {
            Ok(data) if data.len() as u64 == expected => {
                self.state[page as usize] = PageState::Loaded;
                self.data.insert(page, data);
            }
            Ok(data) => self.fail(
                page,
                format!(
                    "{} bytes were read where the page has {expected}",
                    data.len()
                ),
            ),
            Err(reason) => self.fail(page, reason),
        }
    }

    /// One frame: takes the GPU's wants, and plans evictions, installs and reads.
    /// `frame` must grow from call to call. `wanted` is `None` when no word came back
    /// from the GPU for this frame (its readback is late): nothing is touched and the
    /// pressure holds, where an empty list would say the view wants nothing.
    pub fn frame(&mut self, frame: u64, wanted: Option<&[Request]>) -> FramePlan {
        self.frame = frame;
        self.installed_this_frame = 0;
        self.uploaded_this_frame = 0;
        let mut plan = FramePlan::default();
        let (requested, wanted_bytes) = self.take_wants(frame, wanted.unwrap_or_default());
        self.publish(&mut plan);
        self.start_loads(frame, &mut plan);
        let lod_scale = match wanted {
            Some(_) => self.pressure.update_with_room(
                wanted_bytes as f32 / self.pool.capacity().max(1) as f32,
                self.out_of_room,
            ),
            None => self.pressure.scale(),
        };
        plan.stats = FrameStats {
            requested,
            loads_started: plan.load.len() as u32,
            installed: plan.install.len() as u32,
            evicted: plan.evict.len() as u32,
            bytes_uploaded: plan.install.iter().map(|i| i.data.len() as u64).sum(),
            pool_used: self.pool.used(),
            pool_bytes: self.pool.capacity(),
            resident_pages: self.resident_pages,
            in_flight: self.issued.len() as u32,
            wanted_bytes,
            lod_scale,
            failed_pages: self.failed_pages,
        };
        plan
    }

    /// Marks the wanted pages and their ancestors, queues the absent ones; returns how
    /// many are absent and the bytes of all of them.
    fn take_wants(&mut self, frame: u64, wanted: &[Request]) -> (u32, u64) {
        // Highest first, so a page reached from two wants is queued at the higher. Most
        // wants are pages in use (priority 0, thousands a frame): only the rest, the
        // missing pages, need sorting.
        let (mut wanted, in_use): (Vec<Request>, Vec<Request>) =
            wanted.iter().partition(|r| r.priority > 0.0);
        wanted.sort_by(|a, b| b.priority.total_cmp(&a.priority));
        wanted.extend(in_use);
        let (mut requested, mut bytes) = (0, 0);
        let mut stack = Vec::new();
        for r in wanted {
            if r.page as usize >= self.graph.len() {
                continue;
            }
            stack.push(r.page);
            while let Some(p) = stack.pop() {
                if self.visited[p as usize] == frame {
                    continue;
                }
                self.visited[p as usize] = frame;
                match self.state(p) {
                    PageState::Failed => continue,
                    PageState::Absent => {
                        requested += 1;
                        self.enqueue(p, r.priority);
                        if p == r.page {
                            self.prefetch_below(p, r.priority, frame, 1);
                        }
                    }
                    _ => {}
                }
                // Wanted: no longer a mere prefetch.
                self.prefetched[p as usize] = false;
                bytes += self.graph.bytes(p);
                self.touch(p, frame);
                // A resident page's ancestors are resident and held by it (none can be
                // evicted under it), and the GPU lists them itself where they are in
                // use: only a page not yet in needs its ancestors wanted with it.
                if self.state(p) != PageState::Resident {
                    stack.extend_from_slice(self.graph.parents(p));
                }
            }
        }
        (requested, bytes)
    }

    /// Queues the absent pages that need `page`, `level` levels below the requested
    /// page, and (up to [`Budget::prefetch_levels`]) the levels below them, after every
    /// wanted page and each level after the one above. They are not wanted (neither
    /// counted nor touched), only kept from going stale in the queue.
    fn prefetch_below(&mut self, page: PageId, priority: f32, frame: u64, level: u32) {
        if level > self.budget.prefetch_levels {
            return;
        }
        for i in 0..self.graph.dependents(page).len() {
            let child = self.graph.dependents(page)[i];
            let c = child as usize;
            if self.state(child) == PageState::Absent && self.visited[c] != frame {
                // Below every wanted page (priorities are >= 0) and every level above,
                // the higher the requested page's the sooner.
                let below = -((level - 1) as f32) - 1.0 / (1.0 + priority.max(0.0));
                // The child's other parents first (at the same priority the coarser
                // pages go first): it cannot be read before them, and a view that wants
                // this page's children usually wants theirs too.
                for k in 0..self.graph.parents(child).len() {
                    let q = self.graph.parents(child)[k];
                    if q != page {
                        self.prefetch_page(q, below, frame);
                    }
                }
                self.prefetch_page(child, below, frame);
                self.prefetch_below(child, priority, frame, level + 1);
            }
        }
    }

    /// Queues `page` as a prefetch at `priority`, if it is absent and not wanted.
    fn prefetch_page(&mut self, page: PageId, priority: f32, frame: u64) {
        let p = page as usize;
        if self.state(page) == PageState::Absent && self.visited[p] != frame {
            self.last_wanted[p] = self.last_wanted[p].max(frame);
            self.prefetched[p] = true;
            self.enqueue(page, priority);
        }
    }

    fn enqueue(&mut self, page: PageId, priority: f32) {
        if priority > self.queued[page as usize] {
            self.queued[page as usize] = priority;
            self.queue.push(Queued {
                priority,
                depth: self.graph.depth(page),
                page,
            });
        }
    }

    /// Records that `page` was wanted in `frame`.
    /// Notes that `page` was wanted in `frame`. Its place among the eviction candidates
    /// is not moved now (thousands of pages in use are touched every frame): an entry
    /// found stale when evicting is put back at its page's newest frame then.
    fn touch(&mut self, page: PageId, frame: u64) {
        self.last_wanted[page as usize] = frame;
    }

    /// Makes `page` an eviction candidate, keyed by when it was last wanted.
    fn add_evictable(&mut self, page: PageId) {
        let p = page as usize;
        self.evictable_key[p] = self.last_wanted[p];
        self.evictable.insert((self.last_wanted[p], page));
    }

    /// Takes `page` out of the eviction candidates, if it is one.
    fn remove_evictable(&mut self, page: PageId) {
        let p = page as usize;
        if self.evictable_key[p] != NOT_EVICTABLE {
            self.evictable.remove(&(self.evictable_key[p], page));
            self.evictable_key[p] = NOT_EVICTABLE;
        }
    }

    /// Publishes read pages in issue order while their parents are resident and the
    /// budgets allow; drops those whose parent was refused.
    fn publish(&mut self, plan: &mut FramePlan) {
        let issued = std::mem::take(&mut self.issued);
        for page in issued {
            match self.state(page) {
                PageState::Loading => self.issued.push(page),
                PageState::Loaded => {
                    let parents = self.graph.parents(page);
                    if parents.iter().any(|&q| self.state(q) == PageState::Failed) {
                        self.data.remove(&page);
                        self.drop_page(page, PageState::Absent);
                        continue;
                    }
                    let size = self.graph.bytes(page);
                    let fits = self.installed_this_frame < self.budget.installs_per_frame
                        && (self.installed_this_frame == 0
                            || self.uploaded_this_frame + size
                                <= self.budget.upload_bytes_per_frame);
                    if !fits || parents.iter().any(|&q| !self.is_resident(q)) {
                        self.issued.push(page);
                        continue;
                    }
                    self.installed_this_frame += 1;
                    self.uploaded_this_frame += size;
                    // Installed counts as wanted now: never evicted in the frame it
                    // arrives. A prefetch nobody has asked for yet may go from the next
                    // frame on, so it never holds room a wanted page waits for.
                    self.last_wanted[page as usize] = match self.prefetched[page as usize] {
                        true => self.frame.saturating_sub(self.budget.keep_frames),
                        false => self.frame,
                    };
                    self.prefetched[page as usize] = false;
                    self.state[page as usize] = PageState::Resident;
                    self.resident_pages += 1;
                    if self.holders[page as usize] == 0 {
                        self.add_evictable(page);
                    }
                    plan.install.push(Install {
                        page,
                        allocation: self.allocation[page as usize].expect("a read page has room"),
                        data: self.data.remove(&page).expect("a read page has bytes"),
                    });
                }
                // Refused while being read.
                _ => {}
            }
        }
    }

    /// Starts reads in priority order while reads may be in flight and room can be
    /// made.
    fn start_loads(&mut self, frame: u64, plan: &mut FramePlan) {
        self.out_of_room = false;
        while self.issued.len() < self.budget.loads_in_flight as usize {
            let Some(next) = self.queue.pop() else { break };
            let page = next.page;
            let p = page as usize;
            if self.queued[p] != next.priority {
                continue; // queued again at a higher priority
            }
            self.queued[p] = NOT_QUEUED;
            if self.state[p] != PageState::Absent
                || self.last_wanted[p] + self.budget.keep_frames < frame
            {
                continue; // read already, or no longer wanted
            }
            let parents = self.graph.parents(page);
            if parents
                .iter()
                .any(|&q| matches!(self.state(q), PageState::Absent | PageState::Failed))
            {
                continue; // a parent could not be read first: wanted again next frame
            }
            let size = self.graph.bytes(page);
            // Held before room is made, so that making room never evicts a parent.
            for i in 0..self.graph.parents(page).len() {
                let q = self.graph.parents(page)[i];
                self.hold(q);
            }
            let allocation = loop {
                if let Some(a) = self.pool.allocate(size) {
                    break Some(a);
                }
                if self.prefetched[p] || !self.evict_one(frame, plan) {
                    break None;
                }
            };
            let Some(allocation) = allocation else {
                for i in 0..self.graph.parents(page).len() {
                    let q = self.graph.parents(page)[i];
                    self.release_hold(q);
                }
                if self.prefetched[p] {
                    continue; // no free room for a prefetch: dropped
                }
                // Full of pages in use: wait (pressure coarsens the cut meanwhile),
                // unless only this frame's eviction budget ran out.
                self.out_of_room |= plan.evict.len() < self.budget.evictions_per_frame as usize;
                self.enqueue(page, next.priority);
                break;
            };
            self.allocation[p] = Some(allocation);
            self.state[p] = PageState::Loading;
            self.issued.push(page);
            plan.load.push(Load { page, bytes: size });
        }
    }

    /// Evicts the least recently wanted page nothing needs, if one has gone unwanted
    /// long enough and the frame may evict more.
    fn evict_one(&mut self, frame: u64, plan: &mut FramePlan) -> bool {
        if plan.evict.len() >= self.budget.evictions_per_frame as usize {
            return false;
        }
        let page = loop {
            let Some(&(last, page)) = self.evictable.first() else {
                return false;
            };
            if last != self.last_wanted[page as usize] {
                // Wanted since it became a candidate: back in at its newest frame.
                self.remove_evictable(page);
                self.add_evictable(page);
                continue;
            }
            if last + self.budget.keep_frames >= frame {
                return false;
            }
            break page;
        };
        self.remove_evictable(page);
        self.resident_pages -= 1;
        self.drop_page(page, PageState::Absent);
        plan.evict.push(page);
        true
    }

    /// Takes a page out of the pool (evicted, refused, or dropped after its parent was
    /// refused): its room is freed and its parents lose a holder.
    fn drop_page(&mut self, page: PageId, to: PageState) {
        self.state[page as usize] = to;
        if let Some(a) = self.allocation[page as usize].take() {
            self.pool.release(a);
        }
        for i in 0..self.graph.parents(page).len() {
            let q = self.graph.parents(page)[i];
            self.release_hold(q);
        }
    }

    fn hold(&mut self, page: PageId) {
        let p = page as usize;
        if self.holders[p] == 0 {
            self.remove_evictable(page);
        }
        self.holders[p] += 1;
    }

    fn release_hold(&mut self, page: PageId) {
        let p = page as usize;
        self.holders[p] -= 1;
        if self.holders[p] == 0 && self.state[p] == PageState::Resident {
            self.add_evictable(page);
        }
    }

    fn fail(&mut self, page: PageId, reason: String) {
        self.failed_pages += 1;
        self.failures.push(PageFailure { page, reason });
        self.drop_page(page, PageState::Failed);
    }
}
