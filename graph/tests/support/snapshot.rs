//! Golden-file checks for dumps and other generated text. The graph's tests and the root
//! crate's both include this file, so a snapshot fails and is rewritten the same way in
//! each; `CARGO_MANIFEST_DIR` is read where the file is compiled, so each crate keeps its
//! snapshots in its own `tests/snapshots`.

use std::path::Path;

/// Compares `actual` with the snapshot `name`; with `UPDATE_SNAPSHOTS` set it rewrites the
/// snapshot instead, for the diff to be reviewed.
pub fn check(name: &str, actual: &str) {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/snapshots")
        .join(name);
    if std::env::var_os("UPDATE_SNAPSHOTS").is_some() {
        std::fs::create_dir_all(path.parent().unwrap()).unwrap();
        std::fs::write(&path, actual).unwrap();
        return;
    }
    let expected = std::fs::read_to_string(&path).unwrap_or_else(|e| {
        panic!(
            "{}: {e}; run with UPDATE_SNAPSHOTS=1 to create it",
            path.display()
        )
    });
    assert!(
        expected == actual,
        "{name} changed; diff it against {} (UPDATE_SNAPSHOTS=1 rewrites)\n{actual}",
        path.display()
    );
}
