//! What can be wrong with a pipeline file as a whole or with one of its resources,
//! typed so that callers and tests match on the problem rather than on its wording.

use thiserror::Error;

/// The largest pipeline file read, in bytes. The shipped files are a few kilobytes; a
/// limit far above them keeps a mistaken path (a log, a device, a disk image) from
/// being read into memory.
pub const MAX_PIPELINE_FILE_BYTES: u64 = 1 << 20;

/// Why a pipeline file could not be read.
#[derive(Debug, Clone, PartialEq, Eq, Error)]
pub enum SourceProblem {
    /// The path names a directory, a device or something else that is not a file.
    #[error("it is not a regular file but {what}; give the path of a TOML pipeline file")]
    NotARegularFile {
        /// What the path is instead, e.g. "a directory".
        what: &'static str,
    },

    /// The file is over [`MAX_PIPELINE_FILE_BYTES`].
    #[error(
        "it is {bytes} bytes, over the limit of {limit} bytes for a pipeline file; a pipeline file lists resources and passes and is a few kilobytes"
    )]
    TooLarge {
        /// The file's size, in bytes.
        bytes: u64,
        /// [`MAX_PIPELINE_FILE_BYTES`].
        limit: u64,
    },

    /// Opening or reading the file failed.
    #[error("cannot read it: {reason}")]
    Unreadable {
        /// The operating system's error.
        reason: String,
    },
}

/// Why a `[[resource]]` entry was refused.
#[derive(Debug, Clone, PartialEq, Eq, Error)]
pub enum ResourceProblem {
    /// A texture or visibility target with a zero width, height, mip count or layer
    /// count, written in the file or read from a parameter: wgpu would refuse it only
    /// when it is allocated, with a message naming no resource.
    #[error(
        "a {what} of {width} × {height} with {mip_levels} mip level(s) and {layers} layer(s): every dimension must be at least 1; change the size or the parameter it reads"
    )]
    ZeroExtent {
        /// The kind of resource: "texture" or "visibility target".
        what: &'static str,
        /// Width, in texels.
        width: u32,
        /// Height, in texels.
        height: u32,
        /// Mip levels.
        mip_levels: u32,
        /// Array layers.
        layers: u32,
    },

    /// A buffer of zero bytes written in the file: `count = 0` or `element_size = 0`
    /// (wgpu refuses to bind it only when a frame runs).
    #[error(
        "a buffer of {} elements of {element_size} bytes holds nothing; give a count and an element size of at least 1",
        count.map_or_else(|| "`count_param`".to_string(), |n| n.to_string())
    )]
    EmptyBuffer {
        /// The element count written; `None` when it comes from `count_param`.
        count: Option<u64>,
        /// Bytes per element.
        element_size: u32,
    },

    /// A `usage` name wgpu does not know, on any kind of resource.
    #[error("unknown {kind} usage `{usage}`; known: {known}")]
    UnknownUsage {
        /// Which usage flags were searched: "buffer", "texture" or both.
        kind: &'static str,
        /// The name as written.
        usage: String,
        /// The names that exist, to pick from.
        known: String,
    },
}
