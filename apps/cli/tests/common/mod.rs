//! What the tests of the `meshlight` binary share: running it as a user runs it from the
//! repository's root, and a fresh directory for what a run reads or writes.

mod scratch;

pub use scratch::scratch;
use std::process::{Command, Output};

/// The repository's root, where the binary runs as a user runs it there.
pub const ROOT: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../..");

/// `meshlight args` from the repository's root, to be given more before it runs.
pub fn command(args: &[&str]) -> Command {
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_meshlight"));
    cmd.args(args).current_dir(ROOT);
    cmd
}

/// `meshlight args` run to the end from the repository's root.
pub fn meshlight(args: &[&str]) -> Output {
    command(args).output().expect("runs")
}
