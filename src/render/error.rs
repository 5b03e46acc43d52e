//! Why the renderer could not do what it was asked: the render layer's error type. Every variant's message
//! stands alone (the CLI prints it after the scene's name and exits 2).

use std::path::PathBuf;

use crate::gpu::GpuError;
use crate::io::output_file::OutputError;

/// An error from the renderer (`render::Renderer`).
#[derive(Debug, thiserror::Error)]
pub enum RenderError {
    /// Waiting on or reading back from the device failed.
    #[error(transparent)]
    Gpu(#[from] GpuError),
    /// The settings are out of range.
    #[error(transparent)]
    Settings(#[from] InvalidSettings),
    /// A render pipeline could not be built (shader composition or validation).
    #[error("{0}")]
    Pipeline(String),
    /// The film's accumulation buffer does not fit one storage binding.
    #[error(
        "a {width}x{height} film needs {need_mib} MiB of accumulation buffer, more than the device's \
         storage-binding limit of {limit_mib} MiB"
    )]
    FilmTooLarge { width: u32, height: u32, need_mib: u64, limit_mib: u64 },
    /// A saved state of another film size was handed to `restore`.
    #[error("a state of {got} pixels cannot continue a {want}-pixel film")]
    StateSize { got: usize, want: usize },
    /// The image could not be written.
    #[error(transparent)]
    Output(#[from] OutputError),
    /// An output file name whose extension names no format mislab writes.
    #[error("{}: unknown output format '.{ext}' (use .png or .exr)", .path.display())]
    OutputFormat { path: PathBuf, ext: String },
    /// `configure` was asked to change the film size.
    #[error("the film size cannot change on an existing renderer")]
    FilmSizeChange,
}

/// Settings out of range, or that do not go together (`Settings::validate`, `samplers::check_spp`): the message
/// names the flag as the command line spells it.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("{0}")]
pub struct InvalidSettings(pub String);
