//! Where the command line's results go: files (their directories made first) and
//! standard output, every failure an error naming where, never a panic or a silent loss.

use std::path::{Path, PathBuf};

/// A file the command line could not write: the path, what was being done, and why.
/// Every output goes through here, so no write error reaches the user without its path.
#[derive(Debug, thiserror::Error)]
#[error("cannot {action} {}: {reason}", path.display())]
pub struct OutputError {
    pub path: PathBuf,
    pub action: &'static str,
    pub reason: String,
}

impl OutputError {
    fn new(path: &Path, action: &'static str, reason: impl ToString) -> Self {
        Self {
            path: path.to_path_buf(),
            action,
            reason: reason.to_string(),
        }
    }
}

/// An image path whose extension names a format other than PNG, the only one written:
/// refused before rendering, so `-o x.jpg` never holds PNG bytes under a JPEG name.
#[derive(Debug, thiserror::Error)]
#[error(
    "{}: images are written as PNG only, not .{extension}; give a path ending in .png, e.g. -o {}",
    path.display(),
    path.with_extension("png").display()
)]
pub struct NotPngError {
    pub path: PathBuf,
    pub extension: String,
}

/// Accepts a path ending in `.png` (any case) or without an extension.
pub fn check_png_path(path: &Path) -> Result<(), NotPngError> {
    match path.extension() {
        Some(ext) if !ext.eq_ignore_ascii_case("png") => Err(NotPngError {
            path: path.to_path_buf(),
            extension: ext.to_string_lossy().into_owned(),
        }),
        _ => Ok(()),
    }
}

/// Creates the directory `path` is to be written in, if it has one.
pub fn create_parent(path: &Path) -> Result<(), OutputError> {
    match path.parent().filter(|d| !d.as_os_str().is_empty()) {
        Some(dir) => std::fs::create_dir_all(dir)
            .map_err(|e| OutputError::new(dir, "create the directory", e)),
        None => Ok(()),
    }
}

/// Checks, before any work, that `path` can be written: not a directory, its folder made
/// (or makeable), the file openable for writing. A file this creates to find out is
/// removed again, so a later failure leaves nothing behind. A device or a pipe that
/// exists (`/dev/null`, `/dev/stdout`, a named pipe) is left to the write: opening a
/// pipe to test it would wait for a reader, or end a waiting reader's input early.
pub fn check_output_path(path: &Path) -> Result<(), OutputError> {
    if path.is_dir() {
        return Err(OutputError::new(
            path,
            "write",
            "it is a directory; give a file path (inside it, say)",
        ));
    }
    if std::fs::metadata(path).is_ok_and(|m| !m.is_file()) {
        return Ok(());
    }
    create_parent(path)?;
    let existed = path.exists();
    std::fs::OpenOptions::new()
        .write(true)
        .create(true)
        .truncate(false)
        .open(path)
        .map_err(|e| OutputError::new(path, "write", e))?;
    if !existed {
        let _ = std::fs::remove_file(path);
    }
    Ok(())
}

/// Writes `bytes` to `path` (its directory created first).
pub fn write_file(path: &Path, bytes: &[u8]) -> Result<(), OutputError> {
    create_parent(path)?;
    std::fs::write(path, bytes).map_err(|e| OutputError::new(path, "write", e))
}

/// Writes an RGBA8 image as a PNG. The encoder's end and the buffer's flush are checked
/// rather than left to `Drop`, which drops their errors: a full device (`/dev/full`)
/// fails there when the image is small enough to sit in the buffer until then.
pub fn write_png(path: &Path, width: u32, height: u32, rgba: &[u8]) -> Result<(), OutputError> {
    create_parent(path)?;
    let write = |e: &dyn std::fmt::Display| OutputError::new(path, "write", e);
    let file = std::fs::File::create(path).map_err(|e| OutputError::new(path, "create", e))?;
    let mut encoder = png::Encoder::new(std::io::BufWriter::new(file), width, height);
    encoder.set_color(png::ColorType::Rgba);
    encoder.set_depth(png::BitDepth::Eight);
    let mut writer = encoder.write_header().map_err(|e| write(&e))?;
    writer.write_image_data(rgba).map_err(|e| write(&e))?;
    writer.finish().map_err(|e| write(&e))?;
    Ok(())
}

/// Writes `text` to standard output and flushes it. A closed pipe ends the process
/// quietly by SIGPIPE (the binary restores its default action); any other failure (a
/// full device) is an error naming standard output, where `print!` would panic.
pub fn write_stdout(text: &str) -> Result<(), OutputError> {
    use std::io::Write;
    let mut out = std::io::stdout().lock();
    out.write_all(text.as_bytes())
        .and_then(|()| out.flush())
        .map_err(|e| OutputError::new(Path::new("standard output"), "write", e))
}
