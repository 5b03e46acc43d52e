//! The one place the pbrt / Mitsuba importers read files (scene text, PLY/OBJ meshes, images): a missing,
//! unreadable or non-regular file is an error naming it and the reference (`file:line`) that asked for it.

use super::SceneError;
use std::path::Path;

/// Reads `path` whole. `referenced_by` (e.g. `scene.pbrt: line 12`) is added to the error message.
pub fn read_bytes(path: &Path, referenced_by: &str) -> Result<Vec<u8>, SceneError> {
    let by = if referenced_by.is_empty() { String::new() } else { format!(" (referenced by {referenced_by})") };
    let meta = std::fs::metadata(path).map_err(|e| match e.kind() {
        std::io::ErrorKind::NotFound => SceneError::new(path, format!("file not found{by}")),
        _ => SceneError::new(path, format!("cannot read: {e}{by}")),
    })?;
    if !meta.is_file() {
        return Err(SceneError::new(path, format!("not a regular file{by}")));
    }
    std::fs::read(path).map_err(|e| SceneError::new(path, format!("cannot read: {e}{by}")))
}
