//! Why a render state (checkpoint, part, resume, merge) could not be read, used or written: the state layer's
//! error type. Every message names the state file (or the flag) it is about.

use std::path::PathBuf;

use crate::io::input_file::InputError;
use crate::io::output_file::OutputError;
use crate::render::RenderError;

/// An error from the state layer.
#[derive(Debug, thiserror::Error)]
pub enum StateError {
    /// The file is no state this mislab can use (signature, version, size, checksum, header).
    #[error("{file}: not a usable mislab state file: {problem}")]
    Invalid { file: String, problem: String },
    /// The file could not be opened or read.
    #[error("{}: cannot read the state file: {source}", .path.display())]
    Read { path: PathBuf, source: InputError },
    /// The file could not be written (nothing half-written is left).
    #[error("{}: could not write the state file: {message}", .path.display())]
    Write { path: PathBuf, message: String },
    /// Flags that do not go together (`--part`, `--state`, `--checkpoint-every`, `--spp`).
    #[error("{0}")]
    Flags(String),
    /// A state path that cannot hold a state (the output image itself, a directory, a FIFO).
    #[error("{0}")]
    Path(String),
    /// A resumed or merged state of another render, or parts that do not make one render.
    #[error("{0}")]
    Mismatch(String),
    /// A directory of parts could not be listed, or holds none.
    #[error("{0}")]
    Parts(String),
    /// The merged image could not be written.
    #[error(transparent)]
    Output(#[from] OutputError),
    /// The renderer could not take or give the state.
    #[error(transparent)]
    Render(#[from] RenderError),
}
