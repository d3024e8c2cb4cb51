//! One false alarm kept off standard error. Where `XDG_RUNTIME_DIR` is unset (a fresh
//! container, a remote shell), enumerating Vulkan adapters makes the window-system code
//! of Mesa's drivers print `error: XDG_RUNTIME_DIR is invalid or not set in the
//! environment.`, twice, although nothing here opens a window. A library must not set
//! environment variables behind its host's back (another thread may read them), so
//! instead standard error is passed through a pipe while adapters are enumerated, and
//! every line but that one is written on. Output of other threads in that window is
//! delayed, never lost.

/// The message the drivers print; only this exact line is dropped.
const ALARM: &str = "error: XDG_RUNTIME_DIR is invalid or not set in the environment.";

/// Runs `f`, dropping the drivers' `XDG_RUNTIME_DIR` line from what it prints on
/// standard error when the variable is not a usable directory (otherwise `f` runs as
/// it is).
pub(crate) fn without_runtime_dir_alarm<T>(f: impl FnOnce() -> T) -> T {
    let usable = std::env::var_os("XDG_RUNTIME_DIR")
        .map(std::path::PathBuf::from)
        .is_some_and(|dir| dir.is_absolute() && dir.is_dir());
    if usable {
        return f();
    }
    imp::filtered(f)
}

#[cfg(unix)]
mod imp {
    use super::ALARM;
    use std::io::{Read, Write};
    use std::os::fd::{FromRawFd, OwnedFd};

    /// One filter at a time: two threads selecting adapters at once would each save and
    /// restore fd 2, and the later restore would put the first's pipe back on fd 2 for
    /// good, so its reader never saw the pipe end and selection hung.
    static ONE_AT_A_TIME: std::sync::Mutex<()> = std::sync::Mutex::new(());

    /// Standard error through a pipe while `f` runs; a reader thread keeps the pipe from
    /// filling, and what it read is written on afterwards, the alarm left out. Where a
    /// step fails (no stderr, no pipe), `f` runs unfiltered.
    pub(super) fn filtered<T>(f: impl FnOnce() -> T) -> T {
        const STDERR: i32 = 2;
        // A panic inside another filter leaves nothing to protect but fd 2, which it
        // restored (or never moved): go on.
        let _one = ONE_AT_A_TIME
            .lock()
            .unwrap_or_else(std::sync::PoisonError::into_inner);
        let mut fds = [0i32; 2];
        // SAFETY: `fds` is a valid array of two ints for pipe(2) to fill.
        if unsafe { libc::pipe(fds.as_mut_ptr()) } != 0 {
            return f();
        }
        // SAFETY: pipe(2) succeeded, so both descriptors are open and owned here alone.
        let (read, write) = unsafe { (OwnedFd::from_raw_fd(fds[0]), OwnedFd::from_raw_fd(fds[1])) };
        // SAFETY: dup(2) of the process's stderr; a failure (-1) is handled.
        let saved = unsafe { libc::dup(STDERR) };
        if saved < 0 {
            return f();
        }
        // SAFETY: `saved` was just returned by dup(2) and is owned here alone.
        let saved = unsafe { OwnedFd::from_raw_fd(saved) };
        use std::os::fd::AsRawFd;
        // SAFETY: both descriptors are open; dup2 replaces fd 2 atomically.
        if unsafe { libc::dup2(write.as_raw_fd(), STDERR) } < 0 {
            return f();
        }
        drop(write);
        let reader = std::thread::spawn(move || {
            let mut bytes = Vec::new();
            let _ = std::fs::File::from(read).read_to_end(&mut bytes);
            bytes
        });
        let result = f();
        // SAFETY: `saved` is open; putting it back on fd 2 closes the pipe's last
        // write end, so the reader sees the end of the pipe.
        unsafe { libc::dup2(saved.as_raw_fd(), STDERR) };
        let bytes = reader.join().unwrap_or_default();
        let text = String::from_utf8_lossy(&bytes);
        let kept: String = text
            .split_inclusive('\n')
            .filter(|line| line.trim_end() != ALARM)
            .collect();
        if !kept.is_empty() {
            let _ = std::io::stderr().write_all(kept.as_bytes());
        }
        result
    }
}

#[cfg(not(unix))]
mod imp {
    /// Elsewhere the drivers do not print the alarm.
    pub(super) fn filtered<T>(f: impl FnOnce() -> T) -> T {
        f()
    }
}

#[cfg(all(test, unix))]
mod tests {
    use super::*;
    use std::os::fd::AsRawFd;

    /// Writes `text` on file descriptor 2 itself, as a driver does (the test harness
    /// captures only Rust's own printing).
    fn write_fd2(text: &str) {
        // SAFETY: writes a valid buffer of its stated length to fd 2.
        unsafe { libc::write(2, text.as_ptr().cast(), text.len()) };
    }

    /// The tests move fd 2 themselves: one at a time.
    static TESTS: std::sync::Mutex<()> = std::sync::Mutex::new(());

    #[test]
    fn only_the_alarm_is_dropped_and_the_rest_reaches_stderr() {
        let _one = TESTS
            .lock()
            .unwrap_or_else(std::sync::PoisonError::into_inner);
        let file = std::env::temp_dir().join(format!("meshlight-quiet-{}", std::process::id()));
        let sink = std::fs::File::create(&file).unwrap();
        // SAFETY: fd 2 is saved and put back; `sink` is open for both calls.
        let saved = unsafe { libc::dup(2) };
        unsafe { libc::dup2(sink.as_raw_fd(), 2) };
        let value = imp::filtered(|| {
            write_fd2(&format!("{ALARM}\n"));
            write_fd2("MESA: a real warning\n");
            write_fd2(&format!("{ALARM}\n"));
            7
        });
        unsafe {
            libc::dup2(saved, 2);
            libc::close(saved);
        }
        let shown = std::fs::read_to_string(&file).unwrap();
        let _ = std::fs::remove_file(&file);
        assert_eq!(value, 7);
        assert_eq!(shown, "MESA: a real warning\n");
    }

    /// Filters on several threads at once all finish (they once hung: each saved and
    /// restored fd 2, and a late restore left another's pipe open for good).
    #[test]
    fn filters_on_many_threads_at_once_all_finish() {
        let _one = TESTS
            .lock()
            .unwrap_or_else(std::sync::PoisonError::into_inner);
        let (done, finished) = std::sync::mpsc::channel();
        for i in 0..8 {
            let done = done.clone();
            std::thread::spawn(move || {
                let v = imp::filtered(|| {
                    std::thread::sleep(std::time::Duration::from_millis(5));
                    i
                });
                let _ = done.send(v);
            });
        }
        let mut got: Vec<i32> = (0..8)
            .map(|_| {
                finished
                    .recv_timeout(std::time::Duration::from_secs(20))
                    .expect("a filter never finished")
            })
            .collect();
        got.sort();
        assert_eq!(got, (0..8).collect::<Vec<_>>());
    }
}
