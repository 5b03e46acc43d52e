//! Writing output images without losing work: the output path is checked before anything is rendered (a
//! missing or non-directory parent, a directory in the file's place, an over-long name or a read-only file
//! would otherwise be found only after the render), and the image is written to a temporary file in the same
//! directory and renamed over the target, so a crash or a full disk never leaves a half-written image.
//!
//! A symlink is written through (the file it points to is replaced; the link keeps pointing there), and a
//! read-only file is refused unless the user passes `--force`.

use std::path::{Path, PathBuf};

pub use crate::io::error::OutputError;

/// Longest file name most file systems allow (bytes).
const MAX_NAME_BYTES: usize = 255;

/// Where an output goes: the path as the user gave it (for messages) and the file actually replaced (the
/// symlink's target when the path is a link).
#[derive(Clone, Debug)]
pub struct OutputTarget {
    /// As given on the command line.
    pub given: PathBuf,
    /// The file that is written (symlinks followed).
    pub file: PathBuf,
}

/// Checks that `path` can be written (see the module documentation), before any work is done.
pub fn check(path: &Path, force: bool) -> Result<OutputTarget, OutputError> {
    let path_buf = || path.to_path_buf();
    let name = path.file_name().ok_or_else(|| OutputError::NoFileName { path: path_buf() })?;
    if name.len() > MAX_NAME_BYTES {
        return Err(OutputError::NameTooLong { path: path_buf(), bytes: name.len(), max: MAX_NAME_BYTES });
    }
    let file = resolve_links(path)?;
    match std::fs::metadata(&file) {
        Ok(m) if m.is_dir() => return Err(OutputError::IsDirectory { path: path_buf() }),
        Ok(m) if !m.is_file() => return Err(OutputError::NotRegular { path: path_buf() }),
        Ok(m) if m.permissions().readonly() && !force => return Err(OutputError::ReadOnly { path: path_buf() }),
        _ => {}
    }
    let dir = parent_of(&file);
    match std::fs::metadata(&dir) {
        Ok(m) if m.is_dir() => {}
        Ok(_) => return Err(OutputError::ParentNotDirectory { path: path_buf(), dir }),
        Err(_) => return Err(OutputError::NoDirectory { path: path_buf(), dir }),
    }
    // Creating (and removing) the temporary file now finds an unwritable directory before the render.
    let probe = temp_path(&file);
    std::fs::OpenOptions::new()
        .write(true)
        .create_new(true)
        .open(&probe)
        .map_err(|source| OutputError::Unwritable { path: path_buf(), dir: dir.clone(), source })?;
    let _ = std::fs::remove_file(&probe);
    Ok(OutputTarget { given: path.to_path_buf(), file })
}

/// The directory holding `file` ("." for a bare name).
fn parent_of(file: &Path) -> PathBuf {
    match file.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => PathBuf::from("."),
    }
}

/// Follows a chain of symlinks at `path` (at most 40, as the kernel does) to the file it names, which may
/// not exist yet.
fn resolve_links(path: &Path) -> Result<PathBuf, OutputError> {
    let mut file = path.to_path_buf();
    for _ in 0..40 {
        match std::fs::symlink_metadata(&file) {
            Ok(m) if m.file_type().is_symlink() => {
                let target =
                    std::fs::read_link(&file).map_err(|source| OutputError::Link { path: path.into(), source })?;
                file = parent_of(&file).join(target);
            }
            _ => return Ok(file),
        }
    }
    Err(OutputError::LinkLoop { path: path.into() })
}

/// A temporary name next to `file`: hidden, unique to this process.
fn temp_path(file: &Path) -> PathBuf {
    let name = file.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
    parent_of(file).join(format!(".{name}.{}.partial", std::process::id()))
}

/// Replaces `file` by what `write` creates at a temporary path beside it: write, fsync the file, rename over
/// `file`, fsync the directory (so the rename itself survives a crash). A kill or a full disk at any moment
/// leaves the old file or the new one, never a torn one; a failed write leaves no temporary behind. The one
/// way mislab writes its outputs (images, figures, state files). The error is the writer's message, or the
/// file system's.
pub fn replace_atomically<E: std::fmt::Display>(
    file: &Path,
    write: impl FnOnce(&Path) -> Result<(), E>,
) -> Result<(), String> {
    let tmp = temp_path(file);
    let result = write(&tmp).map_err(|e| e.to_string()).and_then(|()| {
        let synced = std::fs::OpenOptions::new().write(true).open(&tmp).and_then(|f| f.sync_all());
        synced.and_then(|()| std::fs::rename(&tmp, file)).map_err(|e| e.to_string())?;
        // Directories cannot be opened for syncing everywhere; the rename is done either way.
        if let Ok(d) = std::fs::File::open(parent_of(file)) {
            let _ = d.sync_all();
        }
        Ok(())
    });
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    result
}

impl OutputTarget {
    /// Writes the output through `write` (given the temporary path to create) and renames it into place.
    pub fn write<E: std::fmt::Display>(&self, write: impl FnOnce(&Path) -> Result<(), E>) -> Result<(), OutputError> {
        replace_atomically(&self.file, write)
            .map_err(|message| OutputError::Write { path: self.given.clone(), message })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn refuses_before_work_and_writes_through_links() {
        let dir = std::env::temp_dir().join(format!("mislab-output-file-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(dir.join("sub")).unwrap();
        let e = check(&dir.join("missing/x.png"), false).unwrap_err();
        assert!(e.to_string().contains("does not exist"), "{e}");
        let e = check(&dir.join("sub"), false).unwrap_err();
        assert!(e.to_string().contains("is a directory"), "{e}");
        std::fs::write(dir.join("file"), b"x").unwrap();
        let e = check(&dir.join("file/x.png"), false).unwrap_err();
        assert!(e.to_string().contains("is not a directory"), "{e}");
        let e = check(&dir.join(format!("{}.png", "a".repeat(300))), false).unwrap_err();
        assert!(e.to_string().contains("longer than"), "{e}");

        // Read-only: refused, unless forced.
        let ro = dir.join("ro.png");
        std::fs::write(&ro, b"old").unwrap();
        let mut perm = std::fs::metadata(&ro).unwrap().permissions();
        perm.set_readonly(true);
        std::fs::set_permissions(&ro, perm).unwrap();
        assert!(check(&ro, false).unwrap_err().to_string().contains("read-only"));
        check(&ro, true).unwrap().write(|p| std::fs::write(p, b"new").map_err(|e| e.to_string())).unwrap();
        assert_eq!(std::fs::read(&ro).unwrap(), b"new");

        // A symlink stays a symlink; its target gets the image.
        #[cfg(unix)]
        {
            let real = dir.join("sub/real.png");
            std::fs::write(&real, b"old").unwrap();
            let link = dir.join("link.png");
            std::os::unix::fs::symlink("sub/real.png", &link).unwrap();
            check(&link, false).unwrap().write(|p| std::fs::write(p, b"new").map_err(|e| e.to_string())).unwrap();
            assert!(std::fs::symlink_metadata(&link).unwrap().file_type().is_symlink());
            assert_eq!(std::fs::read(&real).unwrap(), b"new");
        }
        // A failed write leaves nothing behind.
        let t = check(&dir.join("fail.png"), false).unwrap();
        assert!(t
            .write(|p| std::fs::write(p, b"half").map_err(|e| e.to_string()).and(Err("disk full".to_string())))
            .is_err());
        let names: Vec<_> = std::fs::read_dir(&dir).unwrap().map(|e| e.unwrap().file_name()).collect();
        assert!(!names.iter().any(|n| n.to_string_lossy().contains("partial") || n == "fail.png"), "{names:?}");
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
