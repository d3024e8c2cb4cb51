//! The pipeline file, watched: its modification time polled (no watcher thread or
//! crate), and an error placed at a line of the file so the overlay can say where. The
//! overlay's choices reach the frame as settings, through the pipeline API; the file is
//! never rewritten.

use std::path::{Path, PathBuf};
use std::time::{Duration, Instant, SystemTime};

/// How often the file's modification time is read.
pub const POLL_EVERY: Duration = Duration::from_millis(250);

/// A pipeline file whose changes are noticed by polling.
pub struct PipelineWatch {
    pub path: PathBuf,
    seen: Option<(SystemTime, u64)>,
    last_poll: Instant,
}

impl PipelineWatch {
    /// Watches `path` from its current state (the renderer has just loaded it).
    pub fn new(path: PathBuf) -> Self {
        let seen = stamp(&path);
        Self {
            path,
            seen,
            last_poll: Instant::now(),
        }
    }

    /// True once per change of the file's modification time or length, at most every
    /// [`POLL_EVERY`] unless `now` forces a look.
    pub fn changed(&mut self, force: bool) -> bool {
        if !force && self.last_poll.elapsed() < POLL_EVERY {
            return false;
        }
        self.last_poll = Instant::now();
        let now = stamp(&self.path);
        if now != self.seen {
            self.seen = now;
            return true;
        }
        false
    }
}

fn stamp(path: &Path) -> Option<(SystemTime, u64)> {
    let m = std::fs::metadata(path).ok()?;
    Some((m.modified().ok()?, m.len()))
}

/// An error of the pipeline file, placed where it can be.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct FileError {
    pub file: PathBuf,
    /// 1-based; `None` where the message names nothing found in the file.
    pub line: Option<usize>,
    pub message: String,
}

impl std::fmt::Display for FileError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self.line {
            Some(line) => write!(f, "{}:{line}: {}", self.file.display(), self.message),
            None => write!(f, "{}: {}", self.file.display(), self.message),
        }
    }
}

/// Places `message` (an error of loading `text`, the contents of `file`): at the line a
/// TOML parser names (`line N`), else at the first line holding a name the message
/// quotes in backticks.
pub fn locate(file: &Path, text: &str, message: &str) -> FileError {
    let line = line_named(message).or_else(|| {
        message
            .split('`')
            .skip(1)
            .step_by(2)
            .filter(|name| !name.is_empty())
            .find_map(|name| {
                let quoted = format!("\"{name}\"");
                text.lines()
                    .position(|l| l.contains(&quoted))
                    .or_else(|| text.lines().position(|l| l.contains(name)))
                    .map(|i| i + 1)
            })
    });
    FileError {
        file: file.to_path_buf(),
        line,
        message: message.to_string(),
    }
}

fn line_named(message: &str) -> Option<usize> {
    message.match_indices("line ").find_map(|(at, _)| {
        let digits: String = message[at + 5..]
            .chars()
            .take_while(char::is_ascii_digit)
            .collect();
        digits.parse().ok()
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    const FILE: &str = "name = \"f\"\n\n[[pass]]\nname = \"a\"\nstage = \"sw_raster\"\nimplementation = \"auto\" # best\n\n[[resource]]\nname = \"r\"\nimplementation = \"x\"\n\n[[pass]]\nimplementation = \"single_pass\"\nstage = \"depth_pyramid\"\nparams = { mip = 1 }\n";

    #[test]
    fn errors_are_placed_at_the_parsers_line_or_the_quoted_name() {
        let at = locate(
            Path::new("f.toml"),
            FILE,
            "TOML parse error at line 7, column 2",
        );
        assert_eq!(at.line, Some(7));
        let at = locate(
            Path::new("f.toml"),
            FILE,
            "no implementation `single_pass` of stage `depth_pyramid` is registered",
        );
        assert_eq!(at.line, Some(13));
        assert_eq!(at.to_string(), format!("f.toml:13: {}", at.message));
        let at = locate(Path::new("f.toml"), FILE, "the device is lost");
        assert_eq!(at.line, None);
    }
}
