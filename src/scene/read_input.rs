//! The one place the pbrt / Mitsuba importers read files (scene text, PLY/OBJ meshes, images): a missing,
//! unreadable or non-regular file is an error naming it and the reference (`file:line`) that asked for it.

use super::SceneError;
use std::path::Path;

/// Reads `path` whole, if it is a regular file (after symlinks; a FIFO or device never blocks or floods it) of at
/// most `input_file::MAX_GLTF_BYTES` (scene text, meshes and images alike). `referenced_by` (e.g.
/// `scene.pbrt: line 12`) is added to the error message.
pub fn read_bytes(path: &Path, referenced_by: &str) -> Result<Vec<u8>, SceneError> {
    let by = if referenced_by.is_empty() { String::new() } else { format!(" (referenced by {referenced_by})") };
    crate::io::input_file::read_bounded(path, crate::io::input_file::MAX_GLTF_BYTES).map_err(|e| {
        let e = if e == "no such file" { "file not found".to_string() } else { e };
        SceneError::new(path, format!("{e}{by}"))
    })
}
