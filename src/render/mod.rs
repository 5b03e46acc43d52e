//! The renderer: a scene flattened and uploaded (`scene_data`, `gpu_scene`, `lights`) through one binding table
//! (`bindings`), the shaders composed (`shaders`) and specialised by settings and scene features (`settings`,
//! `features`, `baked`, `pipeline_cache`), the `Renderer` that owns the accumulation and is advanced one way
//! (`renderer`; `api::drive` drives it to a budget), and the film it produces.

pub mod baked;
pub mod bindings;
pub mod bvh_store;
pub mod display;
pub mod env_guide;
pub mod error;
pub mod features;
pub mod film;
pub mod gpu_scene;
pub mod lights;
pub mod materials;
pub mod packed_scene;
pub mod pipeline_cache;
pub mod pipeline_forecast;
pub mod pixel_filter;
pub mod reachability;
pub mod render_module;
pub mod render_pipeline;
pub mod renderer;
pub mod samplers;
pub mod scene_data;
pub mod settings;
pub mod shader_prune;
pub mod shaders;
pub mod shading_data;
pub mod sky_probe;
pub mod tile_order;
pub mod void_and_cluster;

pub use render_module::{render_source, render_source_for, RENDER_FILES};
pub use renderer::*;
