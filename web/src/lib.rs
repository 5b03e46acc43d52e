//! mislab on a web page: the renderer and its shaders on the browser's WebGPU, under an egui panel that switches
//! the estimator live while the image converges. Built by `scripts/web/build.sh` into `target/web/`.
//!
//! Nothing here blocks: each frame records one sample per pixel, copies the accumulators to a staging buffer and
//! asks for it mapped; a later frame, once the browser has mapped it, turns it into the image. The scene's tables
//! are packed into one buffer where the adapter binds fewer storage buffers than the separate layout needs
//! (`mislab::render::packed_scene`).

mod files;
mod lab;
mod page;

pub use lab::WebLab;

#[cfg(target_arch = "wasm32")]
/// eframe's options: a WebGPU device with every feature and limit mislab uses that the adapter offers.
pub fn web_options() -> eframe::WebOptions {
    use eframe::egui_wgpu::{WgpuConfiguration, WgpuSetup, WgpuSetupCreateNew};
    let mut setup = WgpuSetupCreateNew::without_display_handle();
    setup.instance_descriptor.backends = wgpu::Backends::BROWSER_WEBGPU;
    setup.device_descriptor = std::sync::Arc::new(|adapter| {
        let (required_features, required_limits) = mislab::gpu::GpuContext::wanted(adapter);
        wgpu::DeviceDescriptor { label: Some("mislab"), required_features, required_limits, ..Default::default() }
    });
    let wgpu_options = WgpuConfiguration { wgpu_setup: WgpuSetup::CreateNew(setup), ..Default::default() };
    eframe::WebOptions { wgpu_options, ..Default::default() }
}

#[cfg(target_arch = "wasm32")]
mod entry {
    use wasm_bindgen::prelude::*;
    use wasm_bindgen::JsCast;

    /// The page's entry point: the egui app on the canvas `#mislab`.
    #[wasm_bindgen(start)]
    pub fn start() {
        std::panic::set_hook(Box::new(|info| {
            let message = format!("mislab panicked: {info}");
            web_sys::console::error_1(&message.clone().into());
            super::page::report(&message);
        }));
        wasm_bindgen_futures::spawn_local(async {
            let document = web_sys::window().and_then(|w| w.document()).expect("a document");
            let canvas = document
                .get_element_by_id("mislab")
                .and_then(|e| e.dyn_into::<web_sys::HtmlCanvasElement>().ok())
                .expect("a canvas #mislab");
            let started = eframe::WebRunner::new()
                .start(canvas, super::web_options(), Box::new(|cc| Ok(Box::new(super::WebLab::new(cc)?))))
                .await;
            if let Err(e) = started {
                super::page::report(&format!("error: no WebGPU device for mislab ({e:?})"));
            }
        });
    }
}
