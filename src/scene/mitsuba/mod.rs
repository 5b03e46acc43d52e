//! Mitsuba 3 XML scenes (the subset of the Bitterli scenes and what sits next to it): `<default>` / `$param`,
//! `<include>`, shapes `obj` `ply` `rectangle` `cube` `sphere` `disk`, `twosided`, emitters `area` `envmap`
//! `constant` `point` `spot` `directional`, the `perspective` sensor with `to_world` and `fov_axis`, `hdrfilm`
//! size and `bitmap` textures. Our own small XML reader (`xml.rs`) keeps line numbers for errors.

mod loader;
mod xml;

use super::{Scene, SceneError};
use std::path::Path;

/// Loads a Mitsuba 3 `.xml` scene.
pub fn load(path: &Path) -> Result<Scene, SceneError> {
    loader::Loader::new(path).run()
}
