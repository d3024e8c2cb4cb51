//! The pipeline file, watched and edited: its modification time polled (no watcher
//! thread or crate), the stages the overlay chose written into a copy of it, and an
//! error placed at a line of the file so the overlay can say where.

use std::collections::BTreeMap;
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

/// `text` with the `implementation` of every `[[pass]]` of a stage in `chosen` set to
/// the chosen name; every other line stays where it was, so line numbers still match
/// the file.
pub fn with_implementations(text: &str, chosen: &BTreeMap<String, String>) -> String {
    let mut lines: Vec<String> = text.lines().map(str::to_string).collect();
    let mut blocks: Vec<(usize, Option<String>, Option<usize>)> = Vec::new();
    let value = |l: &str, key: &str| -> Option<String> {
        let (k, v) = l.split_once('=')?;
        (k.trim() == key).then(|| {
            v.split('#')
                .next()
                .unwrap_or_default()
                .trim()
                .trim_matches('"')
                .to_string()
        })
    };
    for (i, line) in lines.iter().enumerate() {
        let t = line.trim();
        if t.starts_with('[') {
            if t == "[[pass]]" {
                blocks.push((i, None, None));
            } else if t.starts_with("[[") || !t.starts_with("[pass") {
                blocks.push((i, Some(String::new()), None));
            }
            continue;
        }
        if let Some((_, stage, implementation)) = blocks.last_mut() {
            if stage.is_none()
                && let Some(s) = value(t, "stage")
            {
                *stage = Some(s);
            } else if value(t, "implementation").is_some() {
                *implementation = Some(i);
            }
        }
    }
    for (start, stage, implementation) in blocks.into_iter().rev() {
        let Some(name) = stage.as_deref().and_then(|s| chosen.get(s)) else {
            continue;
        };
        let line = format!("implementation = \"{name}\"");
        match implementation {
            Some(i) => lines[i] = line,
            None => lines[start] = format!("[[pass]]\n{line}"),
        }
    }
    let mut out = lines.join("\n");
    out.push('\n');
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    const FILE: &str = "name = \"f\"\n\n[[pass]]\nname = \"a\"\nstage = \"sw_raster\"\nimplementation = \"auto\" # best\n\n[[resource]]\nname = \"r\"\nimplementation = \"x\"\n\n[[pass]]\nimplementation = \"single_pass\"\nstage = \"depth_pyramid\"\nparams = { mip = 1 }\n";

    #[test]
    fn chosen_implementations_replace_their_stages_lines_only() {
        let chosen = BTreeMap::from([
            ("sw_raster".to_string(), "buffer".to_string()),
            ("depth_pyramid".to_string(), "two_pass".to_string()),
        ]);
        let out = with_implementations(FILE, &chosen);
        let lines: Vec<&str> = out.lines().collect();
        assert_eq!(lines.len(), FILE.lines().count());
        assert_eq!(lines[5], "implementation = \"buffer\"");
        assert_eq!(
            lines[9], "implementation = \"x\"",
            "a resource's line changed"
        );
        assert_eq!(lines[12], "implementation = \"two_pass\"");
        let parsed: toml::Table = toml::from_str(&out).expect("still TOML");
        assert_eq!(parsed["pass"].as_array().map(Vec::len), Some(2));
    }

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
