//! Opening input files safely: every loader (scene files, glTF buffers and images, environment maps, TOML
//! includes, and the importers that come later) reads through here, so a FIFO, a device such as `/dev/zero`,
//! a directory or a symlink loop is a clear error instead of a hang or an unbounded read.
//!
//! The rules: an input is opened only if it is a regular file after following symlinks (checked before the
//! open, and again on the open descriptor, which is opened non-blocking so a FIFO swapped in between cannot
//! block); it is read up to a limit, documented per kind of input below, and never past it even if the file
//! grows (or lies about its size, as `/proc` files do) while it is read.
//!
//! Errors are the problem alone ("is a FIFO (named pipe), not a regular file"); the caller names the file,
//! and no error ever quotes the file's content.

use std::fs::File;
use std::io::Read;
use std::path::{Path, PathBuf};

pub use crate::io::error::InputError;

const MIB: u64 = 1 << 20;
/// TOML scene files: text written by hand or by scripts; far larger is a mistake (or an attack).
pub const MAX_TOML_BYTES: u64 = 64 * MIB;
/// `.gltf` / `.glb` files and glTF buffers: meshes of tens of millions of triangles fit.
pub const MAX_GLTF_BYTES: u64 = 2048 * MIB;
/// Encoded images (glTF textures): a 16384² texture compresses to well under this.
pub const MAX_IMAGE_BYTES: u64 = 512 * MIB;
/// Environment maps (.hdr / .exr): a 16k × 8k float RGB EXR is 1.5 GiB uncompressed.
pub const MAX_ENVMAP_BYTES: u64 = 2048 * MIB;
/// pbrt / Mitsuba scene text and the meshes and images they reference, and what a gzip'd mesh (`.ply.gz`)
/// inflates to: the limit counts the inflated bytes, so a "zip bomb" stops there (`read_limited`).
pub const MAX_IMPORT_BYTES: u64 = MAX_GLTF_BYTES;

/// What a non-regular file is, for the message.
fn kind_of(ft: &std::fs::FileType) -> &'static str {
    #[cfg(unix)]
    {
        use std::os::unix::fs::FileTypeExt;
        if ft.is_fifo() {
            return "a FIFO (named pipe)";
        }
        if ft.is_char_device() {
            return "a character device";
        }
        if ft.is_block_device() {
            return "a block device";
        }
        if ft.is_socket() {
            return "a socket";
        }
    }
    if ft.is_dir() {
        "a directory"
    } else {
        "not a regular file"
    }
}

/// What an I/O error on opening or inspecting `path` means.
fn describe_io(path: &Path, e: std::io::Error) -> InputError {
    // ELOOP: a symlink cycle (or a chain longer than the system follows).
    #[cfg(target_os = "linux")]
    if e.raw_os_error() == Some(40) {
        return InputError::LinkLoop;
    }
    match e.kind() {
        std::io::ErrorKind::NotFound if path.symlink_metadata().is_ok() => InputError::DanglingLink,
        std::io::ErrorKind::NotFound => InputError::NotFound,
        std::io::ErrorKind::PermissionDenied => InputError::PermissionDenied,
        _ => InputError::Read(e),
    }
}

/// Opens `path` for reading if it is a regular file (after following symlinks); returns it and its size.
pub fn open_regular(path: &Path) -> Result<(File, u64), InputError> {
    let meta = std::fs::metadata(path).map_err(|e| describe_io(path, e))?;
    let via_link = path.symlink_metadata().is_ok_and(|m| m.file_type().is_symlink());
    let not_regular = |ft: &std::fs::FileType| InputError::NotRegular { kind: kind_of(ft), via_link };
    if !meta.is_file() {
        return Err(not_regular(&meta.file_type()));
    }
    let mut options = std::fs::OpenOptions::new();
    options.read(true);
    #[cfg(unix)]
    {
        use std::os::unix::fs::OpenOptionsExt;
        // Non-blocking: a FIFO put in the file's place after the check above must not block the open.
        options.custom_flags(libc::O_NONBLOCK);
    }
    let file = options.open(path).map_err(|e| describe_io(path, e))?;
    let meta = file.metadata().map_err(|e| describe_io(path, e))?;
    if !meta.is_file() {
        return Err(not_regular(&meta.file_type()));
    }
    Ok((file, meta.len()))
}

/// Whether `path` is an input that can be read (a regular file, or a file of the active `memory_files` set), and
/// its size: the check a loader makes before it hands a file to another.
pub fn check_readable(path: &Path) -> Result<u64, InputError> {
    match crate::io::memory_files::lookup(path) {
        Some(held) => held.map(|b| b.len() as u64),
        None => open_regular(path).map(|(_, len)| len),
    }
}

/// Reads a whole regular file of at most `limit` bytes (see `open_regular`), refusing larger ones before
/// reading them and never reading more than `limit` bytes however the file changes meanwhile.
pub fn read_bounded(path: &Path, limit: u64) -> Result<Vec<u8>, InputError> {
    if let Some(held) = crate::io::memory_files::lookup(path) {
        let bytes = held?;
        if bytes.len() as u64 > limit {
            return Err(InputError::TooLarge { bytes: bytes.len() as u64, limit });
        }
        return Ok(bytes.to_vec());
    }
    let (file, len) = open_regular(path)?;
    let over = |bytes: u64| InputError::TooLarge { bytes, limit };
    if len > limit {
        return Err(over(len));
    }
    let mut bytes = Vec::with_capacity(len as usize);
    file.take(limit + 1).read_to_end(&mut bytes).map_err(InputError::Read)?;
    if bytes.len() as u64 > limit {
        return Err(over(bytes.len() as u64));
    }
    Ok(bytes)
}

/// The first `max` bytes of a regular file (all of it when shorter): for inputs that declare their own
/// length, such as glTF buffers, which may be followed by more data that is not read.
pub fn read_prefix(path: &Path, max: u64) -> Result<Vec<u8>, InputError> {
    if let Some(held) = crate::io::memory_files::lookup(path) {
        let bytes = held?;
        return Ok(bytes[..bytes.len().min(max as usize)].to_vec());
    }
    let (file, len) = open_regular(path)?;
    let mut bytes = Vec::with_capacity(len.min(max) as usize);
    file.take(max).read_to_end(&mut bytes).map_err(InputError::Read)?;
    Ok(bytes)
}

/// Reads `reader` to its end if that is at most `limit` bytes, growing the buffer step by step (never past the
/// limit, and never by an allocation that fails: that is an error too) so that a stream that never ends, such as
/// a gzip "zip bomb", costs at most `limit` bytes of memory before the error.
pub fn read_limited(mut reader: impl Read, limit: u64) -> Result<Vec<u8>, InputError> {
    let over = || InputError::InflatesTooLarge { limit };
    let mut bytes: Vec<u8> = Vec::new();
    let mut chunk = vec![0u8; 1 << 16];
    loop {
        let n = match reader.read(&mut chunk) {
            Ok(0) => return Ok(bytes),
            Ok(n) => n,
            Err(e) if e.kind() == std::io::ErrorKind::Interrupted => continue,
            Err(e) => return Err(InputError::Read(e)),
        };
        if (bytes.len() + n) as u64 > limit {
            return Err(over());
        }
        if bytes.capacity() - bytes.len() < n {
            // Double, but never past the limit.
            let want = (bytes.capacity() * 2).max(1 << 20).min(limit as usize) - bytes.len();
            let at = bytes.len() as u64;
            bytes.try_reserve_exact(want.max(n)).map_err(|_| InputError::OutOfMemory { at })?;
        }
        bytes.extend_from_slice(&chunk[..n]);
    }
}

/// Why `resolve_inside` refused a file name.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Outside {
    /// An absolute path.
    Absolute,
    /// `..` climbs above the base directory.
    ParentDir,
    /// The path exists and, with its symbolic links followed, lies outside the base directory.
    Symlink,
}

impl Outside {
    /// What is wrong, as words after the name ("'x' is an absolute path").
    pub fn describe(self, base_is: &str) -> String {
        match self {
            Outside::Absolute => "is an absolute path".into(),
            Outside::ParentDir => format!("leads outside {base_is}"),
            Outside::Symlink => format!("leads outside {base_is} through a symbolic link"),
        }
    }
}

/// `base.join(rel)`, if it stays inside `base` (or `allow_outside`): not absolute, never climbing above `base`
/// by `..`, and — when the file exists — not reaching out of it through a symbolic link. A scene file may then
/// name only files of its own folder, as the glTF loader's URIs (`--allow-outside-paths` lifts it).
pub fn resolve_inside(base: &Path, rel: &Path, allow_outside: bool) -> Result<PathBuf, Outside> {
    use std::path::Component;
    let path = base.join(rel);
    if allow_outside {
        return Ok(path);
    }
    let mut depth = 0i64;
    for c in rel.components() {
        match c {
            Component::Normal(_) => depth += 1,
            Component::CurDir => {}
            Component::ParentDir => {
                depth -= 1;
                if depth < 0 {
                    return Err(Outside::ParentDir);
                }
            }
            Component::RootDir | Component::Prefix(_) => return Err(Outside::Absolute),
        }
    }
    // `Path::new("")` (a scene named without a directory) is the current one.
    let base = if base.as_os_str().is_empty() { Path::new(".") } else { base };
    if let (Ok(target), Ok(base)) = (base.join(rel).canonicalize(), base.canonicalize()) {
        if !target.starts_with(&base) {
            return Err(Outside::Symlink);
        }
    }
    Ok(path)
}

/// `read_bounded` for UTF-8 text.
pub fn read_bounded_text(path: &Path, limit: u64) -> Result<String, InputError> {
    let bytes = read_bounded(path, limit)?;
    String::from_utf8(bytes).map_err(|e| InputError::NotUtf8 { offset: e.utf8_error().valid_up_to() })
}

/// Cuts text echoed from an input (a key, a name, a URI) to at most `max` characters, marking the cut.
pub fn clip(text: &str, max: usize) -> String {
    if text.chars().count() <= max {
        return text.to_string();
    }
    let kept: String = text.chars().take(max).collect();
    format!("{kept}… ({} characters)", text.chars().count())
}

/// A path echoed in a message, cut to its last `max` characters when longer: the file name at the end
/// is what tells the user which file it is.
pub fn clip_path(path: &Path, max: usize) -> String {
    let text = path.display().to_string();
    let n = text.chars().count();
    if n <= max {
        return text;
    }
    let kept: String = text.chars().skip(n - max).collect();
    format!("…{kept} ({n} characters)")
}

/// A parser's message with every `backtick-quoted` span (where parsers echo keys and values) cut to `max`
/// characters: a 10 MB key is not echoed in full.
pub fn clip_quoted(message: &str, max: usize) -> String {
    let mut out = String::with_capacity(message.len().min(4096));
    for (i, part) in message.split('`').enumerate() {
        if i > 0 {
            out.push('`');
        }
        // Odd parts lie between backticks.
        out.push_str(&if i % 2 == 1 { clip(part, max) } else { clip(part, 400) });
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn refuses_what_is_not_a_regular_file() {
        let e = read_bounded(Path::new("/dev/zero"), 1 << 20).unwrap_err();
        assert!(e.to_string().contains("character device"), "{e}");
        let e = read_bounded(Path::new("/"), 1 << 20).unwrap_err();
        assert!(e.to_string().contains("a directory"), "{e}");
        let e = read_bounded(Path::new("/no/such/file"), 1 << 20).unwrap_err();
        assert!(matches!(e, InputError::NotFound), "{e}");
    }

    #[test]
    fn limit_is_enforced_and_content_never_echoed() {
        let dir = std::env::temp_dir().join(format!("mislab-input-file-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let p = dir.join("ten.bin");
        std::fs::write(&p, b"secretsecr").unwrap();
        assert_eq!(read_bounded(&p, 10).unwrap().len(), 10);
        let e = read_bounded(&p, 9).unwrap_err();
        assert!(e.to_string().contains("over the limit") && !e.to_string().contains("secret"), "{e}");
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn read_limited_stops_an_endless_stream() {
        let zeros = std::io::repeat(0).take(10 << 20);
        let e = read_limited(zeros, 1 << 20).unwrap_err();
        assert!(e.to_string().contains("more than 1.0 MiB"), "{e}");
        assert_eq!(read_limited(&b"abc"[..], 3).unwrap(), b"abc");
    }

    #[test]
    fn resolve_inside_refuses_what_leaves_the_base() {
        let base = &std::env::temp_dir().join("scene");
        assert_eq!(resolve_inside(base, Path::new("/etc/passwd"), false), Err(Outside::Absolute));
        assert_eq!(resolve_inside(base, Path::new("a/../../x"), false), Err(Outside::ParentDir));
        assert_eq!(resolve_inside(base, Path::new("a/../x"), false), Ok(base.join("a/../x")));
        assert_eq!(resolve_inside(base, Path::new("/etc/passwd"), true), Ok(PathBuf::from("/etc/passwd")));
    }

    #[test]
    fn clip_marks_the_cut() {
        assert_eq!(clip("abc", 3), "abc");
        assert_eq!(clip("abcdef", 3), "abc… (6 characters)");
        assert_eq!(
            clip_quoted("unknown field `abcdef`, expected `x`", 3),
            "unknown field `abc… (6 characters)`, expected `x`"
        );
        assert_eq!(clip_path(Path::new("/a/b/file.bin"), 8), "…file.bin (13 characters)");
        assert_eq!(clip_path(Path::new("/a/file.bin"), 80), "/a/file.bin");
    }
}
