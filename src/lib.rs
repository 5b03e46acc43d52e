//! mislab: a GPU compute-shader Monte Carlo renderer for seeing, measuring and trusting sampling strategies.
//!
//! Data flows one way (see `../shared/DESIGN.md`): scene file → [`scene::Scene`] → [`render::scene_data::SceneData`]
//! (+ [`accel::bvh`], [`render::lights`]) → [`render::gpu_scene::GpuScene`] → [`render::Renderer`] (progressive
//! accumulation) → [`render::film`] (PNG / EXR).
//!
//! The folders are the layers, each using only those below it: [`io`] (files) and [`gpu`] (the device and the
//! structs shared with WGSL) at the bottom; [`scene`] (loaders) and [`accel`] (BVH, light tree) on
//! them; [`render`] (the renderer); [`state`] (checkpointed and split renders); [`api`] (the one embeddable API
//! every front end stands on: a lab, scene handles, `render(...) -> Image`, one loop for every budget); [`lab`]
//! (bench, references, figures, stress) and [`viewer`] at the top. [`testkit`] (chi-square, probes, metrics) serves the tests and the lab.

pub mod accel;
pub mod api;
pub mod gpu;
pub mod io;
// The lab's commands and the native viewer are processes with threads, signals and terminals; a wasm32 build (the
// browser, issue 45) has the layers below them, and of the viewer its panel's widgets.
#[cfg(not(target_arch = "wasm32"))]
pub mod lab;
pub mod render;
pub mod scene;
pub mod state;
pub mod testkit;
pub mod viewer;
