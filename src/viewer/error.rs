//! Why the viewer could not start or do what was asked: the viewer layer's error type. Errors while it runs (a
//! setting out of range, a failed save) are shown in its status line; those before the window opens end the
//! command with exit code 2.

use crate::gpu::GpuError;
use crate::io::exr_image::ImageReadError;
use crate::io::output_file::OutputError;
use crate::render::{InvalidSettings, RenderError};
use crate::scene::LoadError;

/// An error from the viewer.
#[derive(Debug, thiserror::Error)]
pub enum ViewerError {
    /// Flags that do not go together, a reference of another size, a window that could not open.
    #[error("{0}")]
    Input(String),
    #[error(transparent)]
    Settings(#[from] InvalidSettings),
    #[error(transparent)]
    Scene(#[from] LoadError),
    #[error(transparent)]
    Render(#[from] RenderError),
    #[error(transparent)]
    Gpu(#[from] GpuError),
    #[error(transparent)]
    Image(#[from] ImageReadError),
    #[error(transparent)]
    Output(#[from] OutputError),
}
