//! mislab: a GPU compute-shader Monte Carlo renderer for seeing, measuring and trusting sampling strategies.
//!
//! Data flows one way (see `../shared/DESIGN.md`): scene file → [`scene::Scene`] → [`gpu_scene::GpuScene`]
//! (+ [`bvh`], [`lights`]) → [`render::Renderer`] (progressive accumulation) → [`film`] (PNG / EXR).

pub mod bvh;
pub mod gpu;
pub mod gpu_types;
pub mod probe;
pub mod scene;
pub mod shaders;
pub mod film;
pub mod gpu_scene;
pub mod lights;
pub mod render;
pub mod settings;
pub mod progressive;
pub mod features;
pub mod chi2;
pub mod viewer;
pub mod samplers;
pub mod metrics;
pub mod bench;
pub mod reference;
pub mod sampler_figure;
pub mod figure;
pub mod stress;
