//! Files given as bytes instead of found on disk: what a web page's user drops on it or opens from it (a
//! browser has no file system), or what a host program holds in memory. While `with_files` runs, every input the
//! loaders read through `input_file` comes from this set and nothing else, so a scene's references (meshes,
//! textures, includes, environment maps) resolve among the given files.
//!
//! A name resolves exactly (after `.` and `..` are folded), else by its file name alone when exactly one given
//! file has that name: a browser hands over dropped files without their folders, so `meshes/bunny.ply` written
//! in a scene finds a dropped `bunny.ply`.

use crate::io::error::InputError;
use std::cell::RefCell;
use std::collections::HashMap;
use std::path::{Component, Path, PathBuf};
use std::rc::Rc;
use std::sync::Arc;

/// A set of named files held in memory.
#[derive(Clone, Debug, Default)]
pub struct MemoryFiles {
    files: HashMap<PathBuf, Arc<[u8]>>,
}

impl MemoryFiles {
    /// An empty set.
    pub fn new() -> MemoryFiles {
        MemoryFiles::default()
    }

    /// Adds (or replaces) the file `name` (a relative path such as `scene.pbrt` or `meshes/a.ply`).
    pub fn insert(&mut self, name: &str, bytes: impl Into<Arc<[u8]>>) {
        self.files.insert(fold(Path::new(name)), bytes.into());
    }

    /// The names held, sorted.
    pub fn names(&self) -> Vec<String> {
        let mut names: Vec<String> = self.files.keys().map(|p| p.display().to_string()).collect();
        names.sort();
        names
    }

    /// Whether no file is held.
    pub fn is_empty(&self) -> bool {
        self.files.is_empty()
    }

    /// The bytes `path` names: exactly, else by its file name when that is unique in the set.
    pub fn get(&self, path: &Path) -> Option<&Arc<[u8]>> {
        if let Some(bytes) = self.files.get(&fold(path)) {
            return Some(bytes);
        }
        let name = path.file_name()?;
        let mut same_name = self.files.iter().filter(|(p, _)| p.file_name() == Some(name));
        match (same_name.next(), same_name.next()) {
            (Some((_, bytes)), None) => Some(bytes),
            _ => None,
        }
    }
}

/// `path` with `.` dropped and `..` folded into what precedes it (lexically: nothing here is a link), relative
/// to the set's root (a leading `/` or `./` means the same).
fn fold(path: &Path) -> PathBuf {
    let mut out = PathBuf::new();
    for c in path.components() {
        match c {
            Component::Normal(part) => out.push(part),
            Component::ParentDir => {
                out.pop();
            }
            Component::CurDir | Component::RootDir | Component::Prefix(_) => {}
        }
    }
    out
}

thread_local! {
    static CURRENT: RefCell<Option<Rc<MemoryFiles>>> = const { RefCell::new(None) };
}

/// Runs `f` with `files` as the only inputs the loaders can read (on this thread), then restores what was before.
pub fn with_files<R>(files: &MemoryFiles, f: impl FnOnce() -> R) -> R {
    struct Restore(Option<Rc<MemoryFiles>>);
    impl Drop for Restore {
        fn drop(&mut self) {
            CURRENT.with(|c| *c.borrow_mut() = self.0.take());
        }
    }
    let previous = CURRENT.with(|c| c.borrow_mut().replace(Rc::new(files.clone())));
    let _restore = Restore(previous);
    f()
}

/// Whether inputs come from a `MemoryFiles` set on this thread.
pub fn active() -> bool {
    CURRENT.with(|c| c.borrow().is_some())
}

/// `path`'s bytes from the active set: `None` when no set is active (read the disk), else the file or `NotFound`.
pub fn lookup(path: &Path) -> Option<Result<Arc<[u8]>, InputError>> {
    CURRENT.with(|c| c.borrow().as_ref().map(|files| files.get(path).cloned().ok_or(InputError::NotFound)))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_resolve_exactly_then_by_unique_file_name() {
        let mut files = MemoryFiles::new();
        files.insert("scene.pbrt", b"a".to_vec());
        files.insert("meshes/a.ply", b"b".to_vec());
        files.insert("x/dup.png", b"c".to_vec());
        files.insert("y/dup.png", b"d".to_vec());
        assert_eq!(&**files.get(Path::new("./scene.pbrt")).unwrap(), b"a");
        assert_eq!(&**files.get(Path::new("meshes/../meshes/a.ply")).unwrap(), b"b");
        // A browser drops files without their folders: a unique file name still finds the file.
        assert_eq!(&**files.get(Path::new("geometry/a.ply")).unwrap(), b"b");
        assert_eq!(&**files.get(Path::new("y/dup.png")).unwrap(), b"d");
        assert!(files.get(Path::new("z/dup.png")).is_none(), "two files of that name: which one is not guessed");
        assert!(files.get(Path::new("missing.ply")).is_none());
    }

    #[test]
    fn the_set_is_active_only_inside_with_files() {
        let mut files = MemoryFiles::new();
        files.insert("a.txt", b"hi".to_vec());
        assert!(lookup(Path::new("a.txt")).is_none());
        with_files(&files, || {
            assert_eq!(&*lookup(Path::new("a.txt")).unwrap().unwrap(), b"hi");
            assert!(matches!(lookup(Path::new("b.txt")), Some(Err(InputError::NotFound))));
        });
        assert!(!active());
    }
}
