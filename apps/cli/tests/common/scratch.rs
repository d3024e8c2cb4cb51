//! A fresh directory for a test, shared by the binary's tests and the library's unit
//! tests (which include this file by path).

use std::path::PathBuf;

/// An empty directory of this test process's own, named for the test's `name`.
pub fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("meshlight-cli-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}
