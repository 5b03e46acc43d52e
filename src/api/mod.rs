//! The one embeddable API every front end stands on (the CLI, the viewer, the lab, Python, the web): a [`Lab`]
//! opened once that keeps the device and its compiled pipelines, [`SceneHandle`]s loaded once, and
//! [`render`]`(lab, scene, job, observer) -> `[`Image`], driven by one loop for every budget (samples, time,
//! checkpoints, parts, resume, interrupts). A front end adds presentation only: flags, widgets, arrays, a canvas.
//!
//! ```no_run
//! use mislab::api::{render, Job, Lab, SceneHandle, Unobserved};
//! let lab = Lab::open()?;
//! let scene = SceneHandle::named("veach-mis")?;
//! let mut job = Job::from_pairs(&[("spp", "16"), ("strategy", "mis"), ("width", "128"), ("height", "128")])?;
//! let image = render(&lab, &scene, &mut job, &mut Unobserved)?;
//! assert_eq!(image.spp(), 16);
//! # Ok::<(), mislab::api::ApiError>(())
//! ```

mod budget;
mod drive;
mod error;
mod flags;
mod image;
mod job;
mod lab;
mod merge;
mod observer;
mod render;
mod report;
mod scene;

pub use budget::{Budget, RenderStats};
pub use drive::{drive, Plan, SaveCheckpoint, TARGET_SUBMIT_SECONDS};
pub use error::ApiError;
pub use flags::{scene_spec, FlagInfo, RenderFlags, DEFAULT_SPP};
pub use image::{header_attributes, Image};
pub use job::{take_file_settings, Job};
pub use lab::Lab;
pub use merge::merge;
pub use observer::{Callbacks, Observer, Progress, Startup, Unobserved};
pub use render::{render, Render};
pub use report::adapters;
pub use scene::SceneHandle;
// The types a front end hands to the API or gets from it.
pub use crate::render::film::{Film, Tonemap};
pub use crate::render::settings::Settings;
pub use crate::scene::SceneSpec;
