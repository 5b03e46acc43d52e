//! Why a file could not be read or written: the io layer's error types. An [`InputError`] is the problem alone
//! ("is a FIFO (named pipe), not a regular file"), for the caller to put after the file's name (and line); an
//! [`OutputError`] names the output as the user gave it.

use std::path::PathBuf;

const MIB: u64 = 1 << 20;

/// Human size for messages: "12.0 MiB (12582912 bytes)".
pub(crate) fn size(bytes: u64) -> String {
    format!("{:.1} MiB ({bytes} bytes)", bytes as f64 / MIB as f64)
}

/// Why an input could not be read. Never quotes the file's content.
#[derive(Debug, thiserror::Error)]
pub enum InputError {
    #[error("no such file")]
    NotFound,
    #[error("is a symbolic link to a file that does not exist")]
    DanglingLink,
    #[error("is a symbolic link loop (too many levels of symbolic links)")]
    LinkLoop,
    #[error("permission denied")]
    PermissionDenied,
    /// A FIFO, a device, a socket or a directory where a file was expected.
    #[error("is {kind}{}, not a regular file", if *.via_link { " (through a symbolic link)" } else { "" })]
    NotRegular { kind: &'static str, via_link: bool },
    /// Larger than the limit for its kind of input (`input_file::MAX_*`).
    #[error("is {}, over the limit of {} for this kind of input", size(*.bytes), size(*.limit))]
    TooLarge { bytes: u64, limit: u64 },
    /// A compressed stream that inflates past the limit.
    #[error("inflates to more than {}, the limit for this kind of input", size(*.limit))]
    InflatesTooLarge { limit: u64 },
    #[error("needs more memory than is available (at {} inflated)", size(*.at))]
    OutOfMemory { at: u64 },
    #[error("is not UTF-8 text (invalid byte at offset {offset})")]
    NotUtf8 { offset: usize },
    #[error("cannot be read: {0}")]
    Read(#[source] std::io::Error),
}

/// Why an output could not be written; `path` is the output as given.
#[derive(Debug, thiserror::Error)]
pub enum OutputError {
    #[error("{}: the output path names no file", .path.display())]
    NoFileName { path: PathBuf },
    #[error(
        "{}: the output file name is {bytes} bytes, longer than the {max} a file system allows",
        .path.display()
    )]
    NameTooLong { path: PathBuf, bytes: usize, max: usize },
    #[error("{}: the output path is a directory", .path.display())]
    IsDirectory { path: PathBuf },
    #[error("{}: the output path exists and is not a regular file", .path.display())]
    NotRegular { path: PathBuf },
    #[error("{}: the output file is read-only; pass --force to replace it", .path.display())]
    ReadOnly { path: PathBuf },
    #[error("{}: {} is not a directory", .path.display(), .dir.display())]
    ParentNotDirectory { path: PathBuf, dir: PathBuf },
    #[error("{}: the output directory {} does not exist", .path.display(), .dir.display())]
    NoDirectory { path: PathBuf, dir: PathBuf },
    #[error("{}: cannot write in {}: {source}", .path.display(), .dir.display())]
    Unwritable { path: PathBuf, dir: PathBuf, source: std::io::Error },
    #[error("{}: {source}", .path.display())]
    Link { path: PathBuf, source: std::io::Error },
    #[error("{}: the output path is a symbolic link loop", .path.display())]
    LinkLoop { path: PathBuf },
    /// Encoding, writing, syncing or renaming failed; nothing was left half-written.
    #[error("{}: could not write the image: {message}", .path.display())]
    Write { path: PathBuf, message: String },
}

/// Why an EXR image could not be read (the message names the file).
#[derive(Debug, thiserror::Error)]
pub enum ImageReadError {
    #[error("{}: {source}", .path.display())]
    Input { path: PathBuf, source: InputError },
    #[error(
        "{}: not an OpenEXR file; a reference must be linear EXR (e.g. from `mislab reference`) or a .state, \
         not a tonemapped 8-bit image",
        .path.display()
    )]
    NotExr { path: PathBuf },
    #[error("{}: {message}", .path.display())]
    Decode { path: PathBuf, message: String },
}
