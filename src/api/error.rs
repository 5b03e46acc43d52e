//! Why the API could not do what a front end asked. Each kind maps to what a front end reports: the CLI exits 2
//! with the message; Python raises `ValueError` (Settings), `FileNotFoundError` (NotFound), `mislab.SceneError`
//! (Scene) or `RuntimeError` (the rest).

use crate::io::output_file::OutputError;
use crate::render::{InvalidSettings, RenderError};
use crate::scene::LoadError;
use crate::state::StateError;

/// An error from the embeddable API.
#[derive(Debug, thiserror::Error)]
pub enum ApiError {
    /// An unknown setting, a value out of range, or flags that do not go together.
    #[error("{0}")]
    Settings(String),
    /// A scene or other input file that does not exist (and is no built-in name).
    #[error("{0}")]
    NotFound(String),
    /// A scene file that cannot be loaded (the message names the file, and the line for text formats).
    #[error(transparent)]
    Scene(#[from] LoadError),
    /// A scene that loaded but does not fit the device (Python: `mislab.SceneError`, as a file that cannot load).
    #[error("{0}")]
    Upload(String),
    /// No usable device, or the device failed.
    #[error("{0}")]
    Device(String),
    /// The renderer could not do what was asked.
    #[error(transparent)]
    Render(#[from] RenderError),
    /// A state file (checkpoint, part, resume) could not be read, used or written.
    #[error(transparent)]
    State(#[from] StateError),
    /// The image could not be written.
    #[error(transparent)]
    Output(#[from] OutputError),
}

impl From<InvalidSettings> for ApiError {
    fn from(e: InvalidSettings) -> ApiError {
        ApiError::Settings(e.0)
    }
}

impl From<crate::gpu::GpuError> for ApiError {
    fn from(e: crate::gpu::GpuError) -> ApiError {
        ApiError::Device(e.to_string())
    }
}
