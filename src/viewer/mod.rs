//! `mislab view`: the interactive viewer. A window (eframe on wgpu) with a panel that switches every
//! estimator setting live, display modes with a false-colour legend, an A | B comparison, statistics,
//! camera control and file loading/saving. The rendering runs on its own thread and device (see
//! `engine`), in bounded-time bands, so the window stays responsive on a software rasterizer.

// The native window's parts; the panel's widgets also draw the web page's panel (wasm32).
#[cfg(not(target_arch = "wasm32"))]
pub mod app;
#[cfg(not(target_arch = "wasm32"))]
pub mod camera;
#[cfg(not(target_arch = "wasm32"))]
pub mod engine;
#[cfg(not(target_arch = "wasm32"))]
pub mod error;
pub mod widgets;
#[cfg(not(target_arch = "wasm32"))]
mod window;

#[cfg(not(target_arch = "wasm32"))]
pub use error::ViewerError;
#[cfg(not(target_arch = "wasm32"))]
pub use window::*;
