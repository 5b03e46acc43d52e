//! The render module's WGSL source: the files of the render entry point, composed as they are (the generic
//! pipeline) or with a small scene baked in (`Features::flat`).

use crate::render::shaders;

/// WGSL files of the render entry point, in order. `bsdf_materials.wgsl` is generated from the material registry
/// (`materials::dispatch_wgsl`): every kind's file and the dispatchers over them.
pub const RENDER_FILES: &[&str] = &[
    "common.wgsl",
    "geometry_bindings.wgsl",
    "shading_bindings.wgsl",
    "specialize.wgsl",
    "rng.wgsl",
    "samplers.wgsl",
    "warps.wgsl",
    "pixel_filter.wgsl",
    "bvh.wgsl",
    "bvh_wide.wgsl",
    "geometry_loads.wgsl",
    "baked_geometry.wgsl",
    "scene_data.wgsl",
    "bsdf.wgsl",
    "bsdf_materials.wgsl",
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

/// The generated replacements of the render module's files for one scene, or None when it reads everything from
/// buffers: its data and every intersection test when it is small enough (`Features::flat`), or the tests of its
/// few occluders, run before the BVH (`SceneData::occluders`).
pub fn baked_sources(data: &crate::render::scene_data::SceneData) -> Option<Vec<(&'static str, String)>> {
    if let Some((data, geometry)) = crate::render::baked::scene_data_source(data) {
        return Some(vec![("scene_data.wgsl", data), ("baked_geometry.wgsl", geometry)]);
    }
    if let Some(root) = crate::render::baked::root_source(data) {
        return Some(vec![("baked_geometry.wgsl", root)]);
    }
    let geometry = crate::render::baked::occluder_source(data)?;
    let tables = crate::render::baked::occluder_scene_data_source(data)?;
    let mut files = vec![("scene_data.wgsl", tables), ("baked_geometry.wgsl", geometry)];
    if let Some(tree) = crate::render::baked::occluder_light_tree_source(data) {
        files.push(("light_tree_loads.wgsl", tree));
    }
    Some(files)
}

/// The render module for one scene: with what `baked_sources` generates for it, else `render_source()`.
pub fn render_source_for(data: &crate::render::scene_data::SceneData) -> String {
    match baked_sources(data) {
        Some(files) => {
            let files: Vec<(&str, &str)> = files.iter().map(|(n, s)| (*n, s.as_str())).collect();
            shaders::compose_replacing(RENDER_FILES, &files)
        }
        None => render_source(),
    }
}
