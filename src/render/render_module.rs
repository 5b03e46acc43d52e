//! The render module's WGSL source: the files of the render entry point, composed as they are (the generic
//! pipeline) or with a small scene baked in (`Features::flat`).

use crate::render::shaders;

/// WGSL files of the render entry point, in order.
pub const RENDER_FILES: &[&str] = &[
    "common.wgsl",
    "geometry_bindings.wgsl",
    "shading_bindings.wgsl",
    "specialize.wgsl",
    "rng.wgsl",
    "samplers.wgsl",
    "warps.wgsl",
    "bvh.wgsl",
    "bvh_wide.wgsl",
    "geometry_loads.wgsl",
    "baked_geometry.wgsl",
    "scene_data.wgsl",
    "bsdf_conductor.wgsl",
    "bsdf_coated_diffuse.wgsl",
    "bsdf_dielectric.wgsl",
    "bsdf_diffuse_transmission.wgsl",
    "bsdf.wgsl",
    "surface.wgsl",
    "alpha.wgsl",
    "lights.wgsl",
    "env_guide.wgsl",
    "light_tree.wgsl",
    "light_tree_loads.wgsl",
    "mis.wgsl",
    "estimators.wgsl",
    "integrator.wgsl",
];

/// The render module that reads the scene from its buffers (the generic pipeline, shared between scenes).
pub fn render_source() -> String {
    shaders::compose(RENDER_FILES, "")
}

/// The render module for one scene: with its data baked in when it is small enough (`Features::flat`), else
/// `render_source()`.
pub fn render_source_for(data: &crate::render::scene_data::SceneData) -> String {
    match crate::render::baked::scene_data_source(data) {
        Some((data, geometry)) => {
            shaders::compose_replacing(RENDER_FILES, &[("scene_data.wgsl", &data), ("baked_geometry.wgsl", &geometry)])
        }
        None => render_source(),
    }
}
