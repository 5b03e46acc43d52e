//! mislab: a GPU compute-shader Monte Carlo renderer for seeing, measuring and trusting sampling strategies.
//!
//! Data flows one way (see `../shared/DESIGN.md`): scene file → [`scene::Scene`] → [`gpu_scene::GpuScene`]
//! (+ [`bvh`], [`lights`]) → [`render::Renderer`] (progressive accumulation) → [`film`] (PNG / EXR).

pub mod baked;
pub mod bench;
pub mod bindings;
pub mod bvh;
pub mod chi2;
pub mod cli_values;
pub mod compare;
pub mod convex_solids;
pub mod exr_image;
pub mod features;
pub mod figure;
pub mod film;
pub mod gpu;
pub mod gpu_scene;
pub mod gpu_timer;
pub mod gpu_types;
pub mod input_file;
pub mod light_tree;
pub mod lights;
pub mod metrics;
pub mod output_file;
pub mod pipeline_cache;
pub mod probe;
pub mod progressive;
pub mod reachability;
pub mod reference;
pub mod render;
pub mod render_error;
pub mod sampler_figure;
pub mod samplers;
pub mod scene;
pub mod scene_data;
pub mod settings;
pub mod shaders;
pub mod state;
pub mod stress;
pub mod suite_inputs;
pub mod viewer;
