//! Mitsuba 3 XML scenes (the subset of the Bitterli scenes and what sits next to it): `<default>` / `$param`,
//! `<include>`, shapes `obj` `ply` `rectangle` `cube` `sphere` `disk`, `twosided`, emitters `area` `envmap`
//! `constant` `point` `spot` `directional`, the `perspective` sensor with `to_world` and `fov_axis`, `hdrfilm`
//! size and `bitmap` textures. Our own small XML reader (`xml.rs`) keeps line numbers for errors. File names
//! (includes, meshes, textures, maps) must stay inside the scene's folder unless `--allow-outside-paths`.

mod loader;
mod xml;

use super::{LoadOptions, Scene, SceneError};
use std::path::Path;

/// Loads a Mitsuba 3 `.xml` scene with the default options.
pub fn load(path: &Path) -> Result<Scene, SceneError> {
    load_with(path, &LoadOptions::default())
}

/// Loads a Mitsuba 3 `.xml` scene; `options.allow_outside_paths` lets its file names leave its folder.
pub fn load_with(path: &Path, options: &LoadOptions) -> Result<Scene, SceneError> {
    loader::Loader::new(path, options).run()
}
