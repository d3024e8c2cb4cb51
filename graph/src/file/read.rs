//! Reading a pipeline file's text safely: a regular file of bounded size, UTF-8.

use crate::error::{GraphError, Result};
use crate::problem::{MAX_PIPELINE_FILE_BYTES, SourceProblem};
use std::io::Read;
use std::path::Path;

/// The text of a pipeline file: a regular file of at most [`MAX_PIPELINE_FILE_BYTES`].
/// A device, FIFO or directory is refused before it is opened (`/dev/zero` would
/// otherwise be read until memory runs out), and the read stops past the limit even if
/// the file grows while it is read.
pub fn read_pipeline_text(path: &Path) -> Result<String> {
    let refuse = |problem| GraphError::PipelineSource {
        file: path.display().to_string(),
        problem,
    };
    let unreadable = |e: std::io::Error| {
        refuse(SourceProblem::Unreadable {
            reason: e.to_string(),
        })
    };
    let meta = std::fs::metadata(path).map_err(unreadable)?;
    if !meta.is_file() {
        return Err(refuse(SourceProblem::NotARegularFile {
            what: file_kind(&meta.file_type()),
        }));
    }
    let too_large = |bytes| {
        refuse(SourceProblem::TooLarge {
            bytes,
            limit: MAX_PIPELINE_FILE_BYTES,
        })
    };
    if meta.len() > MAX_PIPELINE_FILE_BYTES {
        return Err(too_large(meta.len()));
    }
    let mut bytes = Vec::with_capacity(meta.len() as usize);
    std::fs::File::open(path)
        .and_then(|f| f.take(MAX_PIPELINE_FILE_BYTES + 1).read_to_end(&mut bytes))
        .map_err(unreadable)?;
    if bytes.len() as u64 > MAX_PIPELINE_FILE_BYTES {
        return Err(too_large(bytes.len() as u64));
    }
    String::from_utf8(bytes).map_err(|e| {
        refuse(SourceProblem::Unreadable {
            reason: format!(
                "it is not UTF-8 text (byte {})",
                e.utf8_error().valid_up_to()
            ),
        })
    })
}

/// What a path that is not a regular file is, for the error.
fn file_kind(t: &std::fs::FileType) -> &'static str {
    #[cfg(unix)]
    {
        use std::os::unix::fs::FileTypeExt;
        if t.is_char_device() {
            return "a character device";
        }
        if t.is_block_device() {
            return "a block device";
        }
        if t.is_fifo() {
            return "a FIFO";
        }
        if t.is_socket() {
            return "a socket";
        }
    }
    if t.is_dir() {
        "a directory"
    } else {
        "not a regular file"
    }
}
