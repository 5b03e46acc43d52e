//! pbrt-v4 scene files (the subset the Bitterli scenes use, and the directives a user expects next to it). The
//! tokenizer and parameter lists keep every line number, the parser keeps pbrt's graphics state, and what mislab
//! cannot render is listed in one warning. Coordinates are taken as they are; the camera looks down its +z with
//! +y up (the image orientation checked against the scenes' reference renders).

mod params;
mod parser;
mod shapes;
mod tokenizer;

use super::{LoadOptions, Scene, SceneError};
use std::path::Path;

/// Loads a `.pbrt` file (and what it includes) with the default options.
pub fn load(path: &Path) -> Result<Scene, SceneError> {
    load_with(path, &LoadOptions::default())
}

/// Loads a `.pbrt` file; `options.allow_outside_paths` lets its file names leave its folder.
pub fn load_with(path: &Path, options: &LoadOptions) -> Result<Scene, SceneError> {
    parser::Parser::new(path, options).run()
}
