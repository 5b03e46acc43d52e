//! Why a lab command (bench, compare, reference, figure, stress) could not do what it was asked: the lab layer's
//! error type. The layers below keep their own types; `Input` is the lab's own: a bench file, an option or a
//! pair of images that cannot be used, with a message that names it.

use crate::api::ApiError;
use crate::gpu::GpuError;
use crate::io::exr_image::ImageReadError;
use crate::io::output_file::OutputError;
use crate::render::{InvalidSettings, RenderError};
use crate::scene::{LoadError, SceneError};
use crate::state::StateError;

/// An error from the lab.
#[derive(Debug, thiserror::Error)]
pub enum LabError {
    /// A bench file, a figure's or comparison's option, or an input image that cannot be used.
    #[error("{0}")]
    Input(String),
    /// A plot or figure could not be drawn.
    #[error("{0}")]
    Plot(String),
    #[error(transparent)]
    Metrics(#[from] crate::testkit::metrics::MetricsError),
    #[error(transparent)]
    Json(#[from] serde_json::Error),
    #[error(transparent)]
    ImageWrite(#[from] image::ImageError),
    #[error(transparent)]
    SceneFile(#[from] SceneError),
    #[error(transparent)]
    Settings(#[from] InvalidSettings),
    #[error(transparent)]
    Scene(#[from] LoadError),
    #[error(transparent)]
    Api(#[from] ApiError),
    #[error(transparent)]
    Render(#[from] RenderError),
    #[error(transparent)]
    Gpu(#[from] GpuError),
    #[error(transparent)]
    State(#[from] StateError),
    #[error(transparent)]
    Image(#[from] ImageReadError),
    #[error(transparent)]
    Output(#[from] OutputError),
}
