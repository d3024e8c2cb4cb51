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
use std::sync::mpsc::{Receiver, Sender, channel};
use std::sync::{Arc, Mutex};
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

/// Threads reading pages.
#[derive(Debug)]
pub struct Loader {
    jobs: Option<Sender<ReadJob>>,
    done: Receiver<ReadResult>,
    threads: Vec<JoinHandle<()>>,
    /// Nanoseconds the threads spent reading and checking, all of them together.
    busy: Arc<AtomicU64>,
}

impl Loader {
    /// `threads` reading threads (at least one).
    pub fn new(threads: usize) -> std::io::Result<Self> {
        let (jobs, queue) = channel::<ReadJob>();
        let (finished, done) = channel();
        let queue = Arc::new(Mutex::new(queue));
        let busy = Arc::new(AtomicU64::new(0));
        let threads = (0..threads.max(1))
            .map(|i| {
                let queue = Arc::clone(&queue);
                let finished = finished.clone();
                let busy = Arc::clone(&busy);
                std::thread::Builder::new()
                    .name(format!("meshlight-page-reader-{i}"))
                    .spawn(move || {
                        loop {
                            // The lock is held only to take a job, not while reading it.
                            let job = match queue.lock() {
                                Ok(queue) => queue.recv(),
                                Err(_) => return,
                            };
                            let Ok(job) = job else { return };
                            let start = std::time::Instant::now();
                            let result = read(&job);
                            let spent = start.elapsed().as_nanos() as u64;
                            busy.fetch_add(spent, Ordering::Relaxed);
                            if finished.send((job.page, result)).is_err() {
                                return;
                            }
                        }
                    })
            })
            .collect::<std::io::Result<Vec<_>>>()?;
        Ok(Self {
            jobs: Some(jobs),
            done,
            threads,
            busy,
        })
    }

    /// Time the threads have spent reading and checking pages so far, all of them
    /// together: the streamer's work off the render thread.
    pub fn busy(&self) -> std::time::Duration {
        std::time::Duration::from_nanos(self.busy.load(Ordering::Relaxed))
    }

    /// Queues a read.
    pub fn submit(&self, job: ReadJob) {
        if let Some(jobs) = &self.jobs {
            // Fails only when every thread has stopped, which only dropping does.
            let _ = jobs.send(job);
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
        self.jobs = None;
        for thread in self.threads.drain(..) {
            let _ = thread.join();
        }
    }
}

/// One read, with its checks.
fn read(job: &ReadJob) -> Result<Vec<u8>, String> {
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
    })?;
    if let Some(expected) = job.checksum
        && page_checksum(&data) != expected
    {
        return Err(format!(
            "{path}: page {} fails its checksum: the file is damaged or changed while \
             streaming; bake it again",
            job.page
        ));
    }
    if let Some(check) = &job.check {
        (check.0)(&data)?;
    }
    Ok(data)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pages_are_read_at_their_offsets_and_damage_is_named() {
        let dir = std::env::temp_dir().join(format!("meshlight-loader-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join("pages.bin");
        let bytes: Vec<u8> = (0..10_000u32).map(|i| (i * 7) as u8).collect();
        std::fs::write(&path, &bytes).unwrap();
        let file = PageFile::open(&path).unwrap();
        let loader = Loader::new(3).unwrap();
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
        drop(loader);
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
