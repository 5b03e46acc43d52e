//! Mitsuba 3 XML scenes (placeholder while the parser is written).

use super::{Scene, SceneError};
use std::path::Path;

/// Loads a Mitsuba 3 `.xml` scene.
pub fn load(path: &Path) -> Result<Scene, SceneError> {
    Err(SceneError::new(path, "Mitsuba XML is not supported yet"))
}
