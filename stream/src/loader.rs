//! Reading pages on threads, so that the render thread never waits on the disk.
//!
//! Each read is one positional read (`pread`) of a page's bytes at its offset in its
//! asset file: no seek shared between threads, no whole file read. A read that comes
//! back short (the file was truncated or replaced while streaming), fails, or does not
//! match the page's checksum is an error naming the file and the page; the streamer
//! refuses that page and the cut keeps its coarser level.

use std::fs::File;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::mpsc::{Receiver, channel};
use std::sync::{Arc, Condvar, Mutex};
use std::thread::JoinHandle;
use std::time::Duration;

use meshlight_scene::asset::checksum::page_checksum;

use crate::pages::PageId;

/// An asset file pages are read from, opened once and shared by the reading threads.
#[derive(Debug)]
pub struct PageFile {
    file: File,
    path: PathBuf,
}

impl PageFile {
    /// Opens `path` for reading pages.
    pub fn open(path: &Path) -> std::io::Result<Arc<Self>> {
        Ok(Arc::new(Self {
            file: File::open(path)?,
            path: path.to_owned(),
        }))
    }

    /// The file's path, for messages.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Asks the OS to start reading `bytes` at `offset` into its cache now, so a read
    /// of them later waits less (`posix_fadvise` with `WILLNEED`; nothing where there
    /// is none). Advice only: a failure is ignored.
    pub fn advise(&self, offset: u64, bytes: u64) {
        #[cfg(unix)]
        {
            use std::os::fd::AsRawFd;
            // SAFETY: the descriptor is this file's, open for as long as `self`.
            unsafe {
                libc::posix_fadvise(
                    self.file.as_raw_fd(),
                    offset as libc::off_t,
                    bytes as libc::off_t,
                    libc::POSIX_FADV_WILLNEED,
                );
            }
        }
        #[cfg(not(unix))]
        let _ = (offset, bytes);
    }

    /// Drops the file's bytes from the OS cache where the OS allows it (`posix_fadvise`
    /// with `DONTNEED` after a sync), so the next reads come from the disk: for
    /// measuring cold reads. Does nothing where there is no such call.
    pub fn forget_cached(&self) -> std::io::Result<()> {
        #[cfg(unix)]
        {
            use std::os::fd::AsRawFd;
            self.file.sync_all()?;
            // SAFETY: as in `advise`.
            let code = unsafe {
                libc::posix_fadvise(self.file.as_raw_fd(), 0, 0, libc::POSIX_FADV_DONTNEED)
            };
            if code != 0 {
                return Err(std::io::Error::from_raw_os_error(code));
            }
        }
        Ok(())
    }

    /// Reads `bytes` bytes at `offset`.
    fn read(&self, offset: u64, bytes: u64) -> std::io::Result<Vec<u8>> {
        let mut data = vec![0u8; bytes as usize];
        read_exact_at(&self.file, &mut data, offset)?;
        Ok(data)
    }
}

#[cfg(unix)]
fn read_exact_at(file: &File, buf: &mut [u8], offset: u64) -> std::io::Result<()> {
    std::os::unix::fs::FileExt::read_exact_at(file, buf, offset)
}

#[cfg(windows)]
fn read_exact_at(file: &File, mut buf: &mut [u8], mut offset: u64) -> std::io::Result<()> {
    use std::os::windows::fs::FileExt;
    while !buf.is_empty() {
        match file.seek_read(buf, offset)? {
            0 => return Err(std::io::ErrorKind::UnexpectedEof.into()),
            n => {
                buf = &mut buf[n..];
                offset += n as u64;
            }
        }
    }
    Ok(())
}

/// One page to read.
#[derive(Debug, Clone)]
pub struct ReadJob {
    /// The page, as the streamer knows it.
    pub page: PageId,
    /// The file holding it.
    pub file: Arc<PageFile>,
    /// Its first byte in the file.
    pub offset: u64,
    /// Its size.
    pub bytes: u64,
    /// Its checksum ([`page_checksum`]), when the asset stores one.
    pub checksum: Option<u64>,
    /// Checks of its contents, run on the reading thread after the checksum (so a
    /// page's decoding checks cost the render thread nothing).
    pub check: Option<PageCheck>,
}

/// A check of a page's bytes: `Err` says why the page is refused.
pub type CheckFn = dyn Fn(&[u8]) -> Result<(), String> + Send + Sync;

/// Checks of a page's bytes, shared by the reading threads.
#[derive(Clone)]
pub struct PageCheck(pub Arc<CheckFn>);

impl PageCheck {
    /// A check from a closure.
    pub fn new(check: impl Fn(&[u8]) -> Result<(), String> + Send + Sync + 'static) -> Self {
        Self(Arc::new(check))
    }
}

impl std::fmt::Debug for PageCheck {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("PageCheck")
    }
}

/// A finished read: the page's bytes, or what went wrong.
pub type ReadResult = (PageId, Result<Vec<u8>, String>);

/// Reads waiting for a thread, and whether the loader is closing.
#[derive(Debug, Default)]
struct Queue {
    jobs: std::collections::VecDeque<ReadJob>,
    closed: bool,
    /// Threads reading (each takes its share of what is queued).
    threads: usize,
    /// Whether a thread advises the OS of its share's reads before making them.
    read_ahead: bool,
}

/// Threads reading pages.
#[derive(Debug)]
pub struct Loader {
    /// The waiting reads, and the signal that wakes the threads for them.
    queue: Arc<(Mutex<Queue>, Condvar)>,
    done: Receiver<ReadResult>,
    threads: Vec<JoinHandle<()>>,
    /// Nanoseconds the threads spent on each step ([`ReaderTimes`]), all of them
    /// together.
    busy: Arc<[AtomicU64; 3]>,
}

/// Time the reading threads have spent, all of them together, by step.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct ReaderTimes {
    /// Reading the pages' bytes (with the read-ahead advice).
    pub read: Duration,
    /// Their checksums.
    pub checksum: Duration,
    /// The checks of their contents ([`ReadJob::check`]).
    pub check: Duration,
}

impl ReaderTimes {
    /// The steps together.
    pub fn total(&self) -> Duration {
        self.read + self.checksum + self.check
    }
}

impl std::ops::Sub for ReaderTimes {
    type Output = ReaderTimes;
    fn sub(self, before: ReaderTimes) -> ReaderTimes {
        ReaderTimes {
            read: self.read.saturating_sub(before.read),
            checksum: self.checksum.saturating_sub(before.checksum),
            check: self.check.saturating_sub(before.check),
        }
    }
}

impl Loader {
    /// `threads` reading threads (at least one), without read-ahead.
    pub fn new(threads: usize) -> std::io::Result<Self> {
        Self::with_read_ahead(threads, false)
    }

    /// `threads` reading threads (at least one). Each takes an even share of the reads
    /// queued when it wakes; with `read_ahead`, it first advises the OS of all of them
    /// ([`PageFile::advise`]), so the disk sees a share's reads at once rather than one
    /// at a time per thread.
    pub fn with_read_ahead(threads: usize, read_ahead: bool) -> std::io::Result<Self> {
        let (finished, done) = channel();
        let threads = threads.max(1);
        let queue = Arc::new((
            Mutex::new(Queue {
                threads,
                read_ahead,
                ..Queue::default()
            }),
            Condvar::new(),
        ));
        let busy = Arc::new([AtomicU64::new(0), AtomicU64::new(0), AtomicU64::new(0)]);
        let threads = (0..threads)
            .map(|i| {
                let queue = Arc::clone(&queue);
                let finished = finished.clone();
                let busy = Arc::clone(&busy);
                std::thread::Builder::new()
                    .name(format!("meshlight-page-reader-{i}"))
                    .spawn(move || {
                        // The lock is held only to take a share, not while reading it.
                        while let Some((share, read_ahead)) = next_share(&queue) {
                            if read_ahead {
                                let start = std::time::Instant::now();
                                for job in &share {
                                    job.file.advise(job.offset, job.bytes);
                                }
                                let spent = start.elapsed().as_nanos() as u64;
                                busy[0].fetch_add(spent, Ordering::Relaxed);
                            }
                            for job in share {
                                let result = read(&job, &busy);
                                if finished.send((job.page, result)).is_err() {
                                    return;
                                }
                            }
                        }
                    })
            })
            .collect::<std::io::Result<Vec<_>>>()?;
        Ok(Self {
            queue,
            done,
            threads,
            busy,
        })
    }

    /// Time the threads have spent reading and checking pages so far, all of them
    /// together: the streamer's work off the render thread.
    pub fn busy(&self) -> ReaderTimes {
        let step = |i: usize| Duration::from_nanos(self.busy[i].load(Ordering::Relaxed));
        ReaderTimes {
            read: step(0),
            checksum: step(1),
            check: step(2),
        }
    }

    /// Queues a read.
    pub fn submit(&self, job: ReadJob) {
        self.submit_all([job]);
    }

    /// Queues reads, waking the threads once for all of them (a frame hands over tens
    /// of reads, and a wake per read is a system call each on the render thread).
    pub fn submit_all(&self, jobs: impl IntoIterator<Item = ReadJob>) {
        let (queue, wake) = &*self.queue;
        let mut queue = queue
            .lock()
            .unwrap_or_else(|poisoned| poisoned.into_inner());
        let before = queue.jobs.len();
        queue.jobs.extend(jobs);
        let added = queue.jobs.len() - before;
        drop(queue);
        match added {
            0 => {}
            1 => wake.notify_one(),
            _ => wake.notify_all(),
        }
    }

    /// The reads finished since the last call, without waiting.
    pub fn finished(&self) -> Vec<ReadResult> {
        self.done.try_iter().collect()
    }

    /// Waits up to `timeout` for the next finished read (for tools and tests that want a
    /// read done now).
    pub fn wait(&self, timeout: Duration) -> Option<ReadResult> {
        self.done.recv_timeout(timeout).ok()
    }
}

impl Drop for Loader {
    fn drop(&mut self) {
        let (queue, wake) = &*self.queue;
        queue
            .lock()
            .unwrap_or_else(|poisoned| poisoned.into_inner())
            .closed = true;
        wake.notify_all();
        for thread in self.threads.drain(..) {
            let _ = thread.join();
        }
    }
}

/// The next reads for a reading thread, in the order they were queued, waiting for
/// some: an even share of those queued (so a frame's reads spread over the threads),
/// and whether to advise the OS of them first. `None` once the loader closes (reads
/// still queued then are dropped).
fn next_share(queue: &(Mutex<Queue>, Condvar)) -> Option<(Vec<ReadJob>, bool)> {
    let (queue, wake) = queue;
    let mut queue = queue.lock().ok()?;
    loop {
        if queue.closed {
            return None;
        }
        if !queue.jobs.is_empty() {
            let share = queue.jobs.len().div_ceil(queue.threads);
            let jobs = queue.jobs.drain(..share).collect();
            return Some((jobs, queue.read_ahead));
        }
        queue = wake.wait(queue).ok()?;
    }
}

/// One read, with its checks; each step's time added to `busy`.
fn read(job: &ReadJob, busy: &[AtomicU64; 3]) -> Result<Vec<u8>, String> {
    let mut clock = std::time::Instant::now();
    let mut lap = |step: usize| {
        let now = std::time::Instant::now();
        busy[step].fetch_add((now - clock).as_nanos() as u64, Ordering::Relaxed);
        clock = now;
    };
    let path = job.file.path().display();
    let data = job.file.read(job.offset, job.bytes).map_err(|e| {
        if e.kind() == std::io::ErrorKind::UnexpectedEof {
            format!(
                "{path}: page {} (bytes {}..{}) lies past the end of the file: it was \
                 truncated or replaced while streaming; bake it again",
                job.page,
                job.offset,
                job.offset + job.bytes
            )
        } else {
            format!("{path}: page {} could not be read: {e}", job.page)
        }
    });
    lap(0);
    let data = data?;
    let sum = job.checksum.map(|_| page_checksum(&data));
    lap(1);
    if let Some(expected) = job.checksum
        && sum != Some(expected)
    {
        return Err(format!(
            "{path}: page {} fails its checksum: the file is damaged or changed while \
             streaming; bake it again",
            job.page
        ));
    }
    if let Some(check) = &job.check {
        let checked = (check.0)(&data);
        lap(2);
        checked?;
    }
    Ok(data)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pages_are_read_at_their_offsets_and_damage_is_named() {
        for read_ahead in [false, true] {
            pages_are_read(read_ahead);
        }
    }

    fn pages_are_read(read_ahead: bool) {
        let dir = std::env::temp_dir().join(format!(
            "meshlight-loader-{}-{read_ahead}",
            std::process::id()
        ));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("pages.bin");
        let bytes: Vec<u8> = (0..10_000u32).map(|i| (i * 7) as u8).collect();
        std::fs::write(&path, &bytes).unwrap();
        let file = PageFile::open(&path).unwrap();
        // Cold or not, the bytes read are the file's.
        file.forget_cached().unwrap();
        let loader = Loader::with_read_ahead(3, read_ahead).unwrap();
        let job = |page, offset, len, checksum| ReadJob {
            page,
            file: Arc::clone(&file),
            offset,
            bytes: len,
            checksum,
            check: None,
        };
        let good = page_checksum(&bytes[100..612]);
        loader.submit(job(0, 100, 512, Some(good)));
        loader.submit(job(1, 4000, 6000, None));
        loader.submit(job(2, 9000, 2000, None));
        loader.submit(job(3, 100, 512, Some(good ^ 1)));
        // A check of the contents runs after the checksum, and its word is the error.
        let odd_first = PageCheck::new(|b: &[u8]| match b[0] % 2 {
            0 => Ok(()),
            _ => Err(format!("first byte {} is odd", b[0])),
        });
        for (page, offset) in [(4, 100), (5, 101)] {
            loader.submit(ReadJob {
                check: Some(odd_first.clone()),
                ..job(page, offset, 16, None)
            });
        }
        let mut results: Vec<ReadResult> = (0..6)
            .map(|_| {
                loader
                    .wait(Duration::from_secs(10))
                    .expect("a read finished")
            })
            .collect();
        results.sort_by_key(|r| r.0);
        assert_eq!(results[0].1.as_deref(), Ok(&bytes[100..612]));
        assert_eq!(results[1].1.as_deref(), Ok(&bytes[4000..]));
        let past = results[2].1.as_ref().unwrap_err();
        assert!(
            past.contains("page 2 (bytes 9000..11000) lies past the end"),
            "{past}"
        );
        assert!(past.contains("pages.bin"), "{past}");
        let damaged = results[3].1.as_ref().unwrap_err();
        assert!(damaged.contains("page 3 fails its checksum"), "{damaged}");
        assert_eq!(results[4].1.as_deref(), Ok(&bytes[100..116]));
        assert_eq!(
            results[5].1.as_ref().unwrap_err(),
            &format!("first byte {} is odd", bytes[101])
        );
        assert!(loader.finished().is_empty());
        // A frame's reads handed over at once are shared out and all come back.
        loader.submit_all((0..100u32).map(|i| job(100 + i, u64::from(i) * 97, 97, None)));
        let mut pages: Vec<u32> = (0..100)
            .map(|_| {
                let (page, data) = loader.wait(Duration::from_secs(10)).expect("a read");
                let at = (page as usize - 100) * 97;
                assert_eq!(data.as_deref(), Ok(&bytes[at..at + 97]));
                page
            })
            .collect();
        pages.sort();
        assert_eq!(pages, (100..200).collect::<Vec<u32>>());
        drop(loader);
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
