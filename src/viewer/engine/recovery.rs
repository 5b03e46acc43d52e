//! Device loss and GPU errors: the callbacks that report them, and recreating the device and everything
//! on it (scene, sides, display pass, compile worker, timer) so the render restarts instead of stopping.

use super::side::SideState;
use super::Engine;
use crate::gpu::timer::GpuTimer;
use crate::gpu::GpuContext;
use crate::render::display::DisplayPass;
use crate::render::{gpu_scene::GpuScene, scene_data::SceneData};
use crate::viewer::ViewerError;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};

impl Engine {
    pub(super) fn watch_device(ctx: &GpuContext, lost: &Arc<AtomicBool>, gpu_error: &Arc<Mutex<Option<String>>>) {
        let l = lost.clone();
        let err = gpu_error.clone();
        ctx.device.set_device_lost_callback(move |reason, msg| {
            l.store(true, Ordering::SeqCst);
            *err.lock().unwrap_or_else(|p| p.into_inner()) = Some(format!("device lost ({reason:?}): {msg}"));
        });
        // Without a handler wgpu panics on errors; keep the first one and recover from it instead.
        let err = gpu_error.clone();
        ctx.device.on_uncaptured_error(Arc::new(move |e: wgpu::Error| {
            let mut slot = err.lock().unwrap_or_else(|p| p.into_inner());
            if slot.is_none() {
                *slot = Some(e.to_string());
            }
        }));
    }

    /// Recreates the device and everything on it after a device loss or a GPU error; gives up (with
    /// a message, never a hang) after three failures.
    pub(super) fn recover(&mut self, why: String) {
        self.recoveries += 1;
        log::warn!("render device error: {why}");
        if self.recoveries > 3 {
            self.shared().fatal =
                Some(format!("the GPU device failed repeatedly ({why}); close the window and restart mislab"));
            (self.repaint)();
            return;
        }
        self.message(format!("GPU error ({why}): recreating the device…"));
        let attempt = (|| -> Result<(), ViewerError> {
            let ctx = GpuContext::new()?;
            let gs = GpuScene::upload(&ctx, SceneData::build(&self.scene))?;
            let mut sides = Vec::new();
            for s in &self.settings {
                sides.push(SideState::new(&ctx, &gs, self.camera.clone(), s.clone())?);
            }
            let (w, h) = (self.settings[0].width, self.settings[0].height);
            let display = DisplayPass::new(&ctx, w, h)?;
            self.worker_stop.store(true, Ordering::SeqCst);
            let (jobs, compiled, stop) =
                Self::start_worker(&ctx, &sides[0].renderer, self.warm_device, self.wanted.clone());
            let lost = Arc::new(AtomicBool::new(false));
            Self::watch_device(&ctx, &lost, &self.gpu_error);
            self.timer = GpuTimer::new(&ctx, 3);
            let (warm_scene, warm) = Self::warm_renderer(&ctx)?;
            self.warm_scene = warm_scene;
            self.warm = warm;
            self.reference = None;
            self.ctx = ctx;
            self.gs = gs;
            self.sides = sides;
            self.display = display;
            self.jobs = jobs;
            self.compiled = compiled;
            self.worker_stop = stop;
            self.lost = lost;
            self.pipelines.clear();
            self.requested.clear();
            *self.gpu_error.lock().unwrap_or_else(|p| p.into_inner()) = None;
            self.request_pipelines();
            Ok(())
        })();
        match attempt {
            Ok(()) => {
                let n = self.recoveries;
                {
                    let mut s = self.shared();
                    s.recoveries = n;
                    s.has_reference = false;
                }
                self.message(format!("the GPU device was lost ({why}); recreated it and restarted the render"));
            }
            Err(e) => {
                self.shared().fatal = Some(format!("the GPU device was lost ({why}) and could not be recreated: {e}"));
                (self.repaint)();
            }
        }
    }
}
