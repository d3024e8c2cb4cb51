//! A run of the viewer with no display: the same frames as in a window (graph, blit,
//! overlay) drawn into a texture, timed, with the process's memory and the graph's pool
//! sampled along the way. `meshlight view --offscreen` prints it; it is how the overlay's
//! cost and the viewer's memory over many frames are measured on a GPU server.

use crate::options::ViewerOptions;
use crate::viewer::{Viewer, ViewerError, resident_kib};
use std::fmt::Write as _;
use std::time::Instant;

/// Memory at one frame of the run.
#[derive(Clone, Copy, Debug)]
pub struct MemorySample {
    /// Frames run so far.
    pub frame: u64,
    /// The process's resident memory in KiB.
    pub resident_kib: u64,
    /// Of it, what the C allocator has handed out and not had back, in KiB (where it can
    /// be asked): Rust's, wgpu's and the driver's `malloc`s. Memory a driver maps for
    /// itself is resident but not counted here.
    pub heap_kib: Option<u64>,
    /// Of that, what Rust code holds (meshlight, wgpu, egui), in KiB, where the binary
    /// counts its allocations with [`CountingAllocator`]; the rest of the heap is the C
    /// libraries' (the Vulkan driver's).
    pub rust_heap_kib: Option<u64>,
    /// Bytes of GPU buffers and textures the graph's pool holds.
    pub pool_bytes: u64,
    /// GPU allocations the executor made in the sampled frame (0 once the pool has
    /// what the frame needs).
    pub allocations: u64,
}

/// What an off-screen run measured.
#[derive(Clone, Debug)]
pub struct OffscreenReport {
    /// The adapter it ran on.
    pub adapter: String,
    /// Frames measured (after the warm-up).
    pub frames: u64,
    /// Frames run before measuring: pipelines built, lists grown, caches filled.
    pub warmup: u64,
    /// Wall-clock time per frame over the measured frames, the GPU drained at the end:
    /// the frame rate a window without vsync would get.
    pub wall_ms: f64,
    /// Mean CPU time of a frame on the viewer's side.
    pub cpu_ms: f64,
    /// Mean part of it spent on the overlay.
    pub overlay_ms: f64,
    /// Mean part of it spent in the graph's frame.
    pub graph_ms: f64,
    /// Mean GPU time of the graph's frame (its timestamp pair; the blit and the overlay
    /// run after it, outside the pair), where the adapter has timestamps.
    pub gpu_ms: Option<f64>,
    /// Memory at the end of the warm-up, then every `sample_every` frames.
    pub memory: Vec<MemorySample>,
}

impl OffscreenReport {
    /// Growth of resident memory from the first sample to the last, in KiB per frame.
    pub fn resident_growth_kib_per_frame(&self) -> f64 {
        match (self.memory.first(), self.memory.last()) {
            (Some(a), Some(b)) if b.frame > a.frame => {
                (b.resident_kib as f64 - a.resident_kib as f64) / (b.frame - a.frame) as f64
            }
            _ => 0.0,
        }
    }

    /// The report as lines of `name value`, one figure a line.
    pub fn text(&self) -> String {
        let mut s = String::new();
        let _ = writeln!(s, "adapter {}", self.adapter);
        let _ = writeln!(s, "frames {} (after {} warm-up)", self.frames, self.warmup);
        let _ = writeln!(s, "wall_ms_per_frame {:.4}", self.wall_ms);
        let _ = writeln!(s, "cpu_ms {:.4}", self.cpu_ms);
        let _ = writeln!(s, "overlay_ms {:.4}", self.overlay_ms);
        let _ = writeln!(s, "graph_ms {:.4}", self.graph_ms);
        match self.gpu_ms {
            Some(g) => {
                let _ = writeln!(s, "gpu_ms {g:.4}");
            }
            None => {
                let _ = writeln!(s, "gpu_ms none (no timestamps)");
            }
        }
        for m in &self.memory {
            let kib = |k: Option<u64>| k.map_or("unknown".to_string(), |k| k.to_string());
            let _ = writeln!(
                s,
                "memory frame {} resident_kib {} heap_kib {} rust_heap_kib {} pool_bytes {} allocations {}",
                m.frame,
                m.resident_kib,
                kib(m.heap_kib),
                kib(m.rust_heap_kib),
                m.pool_bytes,
                m.allocations
            );
        }
        let _ = writeln!(
            s,
            "resident_growth_kib_per_frame {:.3}",
            self.resident_growth_kib_per_frame()
        );
        s
    }
}

/// Runs `warmup` frames, then `frames` measured ones, off-screen; memory is sampled
/// every `sample_every` frames.
pub fn run_offscreen(
    options: ViewerOptions,
    warmup: u64,
    frames: u64,
    sample_every: u64,
) -> Result<(Viewer, OffscreenReport), ViewerError> {
    let mut viewer = Viewer::offscreen(options)?;
    viewer.run_frames(warmup)?;
    viewer.renderer.executor.finish()?;
    let sample = |v: &Viewer| {
        let stats = v.last_stats.as_ref();
        MemorySample {
            frame: v.frames,
            resident_kib: resident_kib().unwrap_or(0),
            heap_kib: heap_kib(),
            rust_heap_kib: rust_heap_kib(),
            pool_bytes: stats.map_or(0, |s| s.pool_bytes_held),
            allocations: stats.map_or(0, |s| u64::from(s.allocations)),
        }
    };
    let mut memory = vec![sample(&viewer)];
    let (mut cpu, mut overlay, mut graph, mut gpu, mut gpu_n) = (0.0, 0.0, 0.0, 0.0, 0u64);
    let start = Instant::now();
    for i in 1..=frames {
        viewer.frame()?;
        if let Some(t) = viewer.times.back() {
            cpu += f64::from(t.cpu_ms);
            overlay += f64::from(t.overlay_ms);
            graph += f64::from(t.graph_ms);
            if let Some(g) = t.gpu_ms {
                gpu += f64::from(g);
                gpu_n += 1;
            }
        }
        if sample_every > 0 && i % sample_every == 0 {
            memory.push(sample(&viewer));
        }
    }
    viewer.renderer.executor.finish()?;
    let wall = start.elapsed().as_secs_f64() * 1000.0;
    let n = frames.max(1) as f64;
    let report = OffscreenReport {
        adapter: viewer.renderer.adapter.to_string(),
        frames,
        warmup,
        wall_ms: wall / n,
        cpu_ms: cpu / n,
        overlay_ms: overlay / n,
        graph_ms: graph / n,
        gpu_ms: (gpu_n > 0).then(|| gpu / gpu_n as f64),
        memory,
    };
    Ok((viewer, report))
}

/// Bytes in use from glibc's allocator (its arenas and its mmapped blocks), in KiB.
#[cfg(all(target_os = "linux", target_env = "gnu"))]
pub fn heap_kib() -> Option<u64> {
    // SAFETY: mallinfo only reads the allocator's statistics. Its fields are C ints, so
    // each wraps past 2 GiB; that is read as unsigned, which holds up to 4 GiB.
    #[allow(deprecated)]
    let info = unsafe { libc::mallinfo() };
    Some((u64::from(info.uordblks as u32) + u64::from(info.hblkhd as u32)) / 1024)
}

#[cfg(not(all(target_os = "linux", target_env = "gnu")))]
pub fn heap_kib() -> Option<u64> {
    None
}

/// The system allocator, counting the bytes Rust code holds, so that a run can tell its
/// own heap from the C libraries' (`meshlight` installs it as the global allocator).
pub struct CountingAllocator;

static RUST_HEAP_BYTES: std::sync::atomic::AtomicI64 = std::sync::atomic::AtomicI64::new(0);

// SAFETY: every call is passed to the system allocator unchanged; the counter only
// records the sizes.
unsafe impl std::alloc::GlobalAlloc for CountingAllocator {
    unsafe fn alloc(&self, layout: std::alloc::Layout) -> *mut u8 {
        // SAFETY: the caller's contract is the system allocator's.
        let p = unsafe { std::alloc::System.alloc(layout) };
        if !p.is_null() {
            count(layout.size() as i64);
        }
        p
    }

    unsafe fn alloc_zeroed(&self, layout: std::alloc::Layout) -> *mut u8 {
        // SAFETY: as above.
        let p = unsafe { std::alloc::System.alloc_zeroed(layout) };
        if !p.is_null() {
            count(layout.size() as i64);
        }
        p
    }

    unsafe fn dealloc(&self, ptr: *mut u8, layout: std::alloc::Layout) {
        // SAFETY: as above.
        unsafe { std::alloc::System.dealloc(ptr, layout) };
        count(-(layout.size() as i64));
    }

    unsafe fn realloc(&self, ptr: *mut u8, layout: std::alloc::Layout, new: usize) -> *mut u8 {
        // SAFETY: as above.
        let p = unsafe { std::alloc::System.realloc(ptr, layout, new) };
        if !p.is_null() {
            count(new as i64 - layout.size() as i64);
        }
        p
    }
}

fn count(bytes: i64) {
    RUST_HEAP_BYTES.fetch_add(bytes, std::sync::atomic::Ordering::Relaxed);
}

/// The bytes Rust code holds, in KiB; `None` where [`CountingAllocator`] is not the
/// global allocator (nothing was ever counted).
pub fn rust_heap_kib() -> Option<u64> {
    let bytes = RUST_HEAP_BYTES.load(std::sync::atomic::Ordering::Relaxed);
    (bytes > 0).then_some(bytes as u64 / 1024)
}
