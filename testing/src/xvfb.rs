//! An X server of a test's own (Xvfb on a free display, started through
//! `scripts/ensure-xvfb.sh`), for tests that open windows: the viewer's, the `view`
//! command's and the host example's.

use std::path::{Path, PathBuf};
use std::process::Command;

/// A running Xvfb, stopped when dropped.
pub struct Xvfb {
    /// The display to open windows on, e.g. `:99`.
    pub display: String,
    pid: u32,
}

impl Drop for Xvfb {
    fn drop(&mut self) {
        let _ = Command::new("kill").arg(self.pid.to_string()).status();
    }
}

/// The repository's root.
fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..")
}

/// Starts Xvfb on a free display; fails the test with the script's message if it cannot
/// (a missing Xvfb is installed where the script may; never skipped). `scratch` is a
/// directory the script may write its pid file into.
pub fn start(scratch: &Path) -> Xvfb {
    let pid_file = scratch.join("xvfb.pid");
    let out = Command::new("bash")
        .arg(root().join("scripts/ensure-xvfb.sh"))
        .arg("--start")
        .env("XVFB_PID_FILE", &pid_file)
        .output()
        .expect("cannot run scripts/ensure-xvfb.sh");
    assert!(
        out.status.success(),
        "this test needs an X server and could not start Xvfb: {}{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    let display = String::from_utf8_lossy(&out.stdout).trim().to_string();
    let pid = std::fs::read_to_string(&pid_file)
        .expect("ensure-xvfb.sh wrote no pid")
        .trim()
        .parse()
        .expect("a pid");
    Xvfb { display, pid }
}
