//! The one place the pbrt / Mitsuba importers read files (scene text, PLY/OBJ meshes, images): a missing,
//! unreadable or non-regular file is an error naming it and the reference (`file:line`) that asked for it, and a
//! file name that leads outside the scene's folder is refused before anything is read (`SceneDir`).

use super::SceneError;
use crate::io::input_file::{clip, resolve_inside, MAX_IMPORT_BYTES};
use std::path::{Path, PathBuf};

/// Reads `path` whole, if it is a regular file (after symlinks; a FIFO or device never blocks or floods it) of at
/// most `input_file::MAX_IMPORT_BYTES` (scene text, meshes and images alike). `referenced_by` (e.g.
/// `scene.pbrt: line 12`) is added to the error message.
pub fn read_bytes(path: &Path, referenced_by: &str) -> Result<Vec<u8>, SceneError> {
    crate::io::input_file::read_bounded(path, MAX_IMPORT_BYTES).map_err(|e| {
        let e = match e {
            crate::io::input_file::InputError::NotFound => "file not found".to_string(),
            e => e.to_string(),
        };
        SceneError::new(path, format!("{e}{}", by(referenced_by)))
    })
}

/// " (referenced by scene.pbrt: line 12)", or nothing for the main file.
pub fn by(referenced_by: &str) -> String {
    if referenced_by.is_empty() {
        String::new()
    } else {
        format!(" (referenced by {referenced_by})")
    }
}

/// `e` with "(included by `by`)" added when it is about `path` itself, an included scene file: its own file and
/// line, and where it was included from. Errors about other files (which it includes or references) say their own.
pub fn included_from(path: &Path, by: &str, e: SceneError) -> SceneError {
    if by.is_empty() || e.path != path.display().to_string() || e.message.contains("(referenced by ") {
        e
    } else {
        SceneError { message: format!("{} (included by {by})", e.message), ..e }
    }
}

/// `file: line N`, as `referenced_by` names a reference.
pub fn at(file: &Path, line: usize) -> String {
    format!("{}: line {line}", file.display())
}

/// The folder a scene's file names resolve against (its main file's), and whether they may leave it.
#[derive(Clone, Debug)]
pub struct SceneDir {
    /// The main scene file's directory.
    pub dir: PathBuf,
    /// Follow absolute paths, `..` and symbolic links out of `dir` (`--allow-outside-paths`).
    pub allow_outside: bool,
}

impl SceneDir {
    /// The directory of `main`.
    pub fn of(main: &Path, allow_outside: bool) -> SceneDir {
        SceneDir { dir: main.parent().map(Path::to_path_buf).unwrap_or_default(), allow_outside }
    }

    /// The file that `name` (written at `file`: `line`) names, refused — an error about that place, naming no
    /// content of the file it points at — when it is absolute or leads out of the scene's folder.
    pub fn resolve(&self, name: &str, file: &Path, line: usize) -> Result<PathBuf, SceneError> {
        resolve_inside(&self.dir, Path::new(name), self.allow_outside).map_err(|why| {
            SceneError::new(
                file,
                format!(
                    "line {line}: the file name '{}' {} (scene files may name only files under their own folder; \
                     allow it with --allow-outside-paths)",
                    clip(name, 120),
                    why.describe("the scene's folder")
                ),
            )
        })
    }
}
