//! The lab: a device opened once, whose compiled pipelines every render through it reuses (building one takes
//! seconds on lavapipe; a second render of the same scene and settings starts sampling at once).

use super::error::ApiError;
use crate::gpu::GpuContext;
use crate::render::pipeline_forecast as forecast;
use std::sync::atomic::{AtomicU64, Ordering};

/// An open device and what it has compiled. Open one per process and render everything through it.
pub struct Lab {
    ctx: GpuContext,
    /// Tells labs apart, for the scenes uploaded to each (`SceneHandle::upload`).
    pub(crate) id: u64,
}

impl Lab {
    /// Opens the chosen Vulkan adapter (`WGPU_ADAPTER_NAME` picks one by name; lavapipe serves where no GPU is).
    pub fn open() -> Result<Lab, ApiError> {
        static NEXT: AtomicU64 = AtomicU64::new(1);
        let ctx = GpuContext::new().map_err(|e| ApiError::Device(e.to_string()))?;
        Ok(Lab { ctx, id: NEXT.fetch_add(1, Ordering::Relaxed) })
    }

    /// A lab on a device opened elsewhere (the lab's tools that hold a `GpuContext`): the same device and pipelines.
    pub fn on(ctx: &GpuContext) -> Lab {
        static NEXT: AtomicU64 = AtomicU64::new(1 << 32);
        Lab { ctx: ctx.clone(), id: NEXT.fetch_add(1, Ordering::Relaxed) }
    }

    /// The device, for the lab's own tools (stress cases, probes) that work below scenes and images.
    pub fn gpu(&self) -> &GpuContext {
        &self.ctx
    }

    /// The adapter's name and type, as `mislab info` prints them.
    pub fn adapter(&self) -> String {
        format!("{} ({:?})", self.ctx.info.name, self.ctx.info.device_type)
    }

    /// Render pipelines compiled so far (shared by every render through this lab).
    pub fn pipelines_compiled(&self) -> usize {
        self.ctx.pipelines.len()
    }

    /// Builds the render pipeline that the last run of `command` on this adapter used, if one was recorded
    /// (`save_forecast`; `render::pipeline_forecast`): a render whose pipeline is built from an equal request takes
    /// it instead of building one. For a front end that can do this while the scene loads (`mislab render` opens
    /// the lab on a second thread). `command` is whatever tells one run's pipeline from another's (the scene as
    /// named, the settings). Returns whether a pipeline was built.
    pub fn build_forecast(&self, command: &str) -> bool {
        let Some(request) =
            forecast::dir().and_then(|d| forecast::load(&forecast::file_for(&d, command, &self.ctx.info)))
        else {
            return false;
        };
        match forecast::prebuild(&self.ctx, request) {
            Ok(()) => true,
            Err(e) => {
                eprintln!("warning: pipeline forecast not built: {e}");
                false
            }
        }
    }

    /// How many renders took a pipeline `build_forecast` built, instead of building one.
    pub fn forecasts_taken(&self) -> usize {
        self.ctx.pipelines.offers_taken()
    }

    /// Records the render pipeline this lab's renders used last as the forecast of `command` (`build_forecast`).
    pub fn save_forecast(&self, command: &str) {
        if let (Some(dir), Some(request)) = (forecast::dir(), self.ctx.pipelines.last_request()) {
            forecast::save(&forecast::file_for(&dir, command, &self.ctx.info), &request);
        }
    }
}
