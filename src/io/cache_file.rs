//! Files in mislab's cache directory (`gpu::pipeline_store`'s compiled pipelines, `render::bvh_store`'s built
//! BVHs): where the directory is, a frame that makes a damaged file detectable (a magic with the format's version,
//! the length, a CRC-32), and writes that a concurrent reader sees whole or not at all.

use std::io::Write;
use std::path::{Path, PathBuf};

/// The directory mislab keeps caches in: `$XDG_CACHE_HOME/mislab`, else the platform's (`~/.cache/mislab` on
/// Linux, `~/Library/Caches/mislab` on macOS, `%LOCALAPPDATA%\mislab` on Windows). None without a home.
pub fn cache_dir() -> Option<PathBuf> {
    let env = |k: &str| std::env::var_os(k).filter(|v| !v.is_empty()).map(PathBuf::from);
    let base = env("XDG_CACHE_HOME").filter(|p| p.is_absolute()).or_else(|| {
        if cfg!(target_os = "windows") {
            env("LOCALAPPDATA")
        } else if cfg!(target_os = "macos") {
            env("HOME").map(|h| h.join("Library/Caches"))
        } else {
            env("HOME").map(|h| h.join(".cache"))
        }
    })?;
    Some(base.join("mislab"))
}

/// `data` in a file's frame: `magic`, length, CRC-32, data.
pub fn frame(magic: &[u8; 8], data: &[u8]) -> Vec<u8> {
    let mut crc = flate2::Crc::new();
    crc.update(data);
    let mut out = Vec::with_capacity(data.len() + 20);
    out.extend_from_slice(magic);
    out.extend_from_slice(&(data.len() as u64).to_le_bytes());
    out.extend_from_slice(&crc.sum().to_le_bytes());
    out.extend_from_slice(data);
    out
}

/// The data inside a file framed with `magic`, or why it cannot be used.
pub fn unframe<'a>(magic: &[u8; 8], file: &'a [u8]) -> Result<&'a [u8], &'static str> {
    if file.len() < 20 || &file[..8] != magic {
        return Err("not a mislab cache file of this kind (or an older format)");
    }
    let len = u64::from_le_bytes(file[8..16].try_into().unwrap());
    let data = &file[20..];
    if len != data.len() as u64 {
        return Err("truncated");
    }
    let mut crc = flate2::Crc::new();
    crc.update(data);
    if crc.sum().to_le_bytes() != file[16..20] {
        return Err("its checksum does not match (damaged)");
    }
    Ok(data)
}

/// Writes `bytes` to `path` through a private temporary file in the same directory (created if missing), renamed
/// over the old file: atomic on one file system, so concurrent writers and readers see one whole file or another.
pub fn write_atomically(path: &Path, bytes: &[u8]) -> std::io::Result<()> {
    let dir = path.parent().unwrap_or(Path::new("."));
    std::fs::create_dir_all(dir)?;
    let tmp = dir.join(format!(
        ".{}.{}.{:x}.tmp",
        path.file_name().and_then(|n| n.to_str()).unwrap_or("cache"),
        std::process::id(),
        std::time::SystemTime::now().duration_since(std::time::UNIX_EPOCH).map_or(0, |d| d.as_nanos())
    ));
    let written = std::fs::File::create(&tmp).and_then(|mut f| {
        f.write_all(bytes)?;
        f.sync_all()
    });
    if let Err(e) = written.and_then(|_| std::fs::rename(&tmp, path)) {
        let _ = std::fs::remove_file(&tmp);
        return Err(e);
    }
    Ok(())
}

/// Removes the least recently written files of `dir` with extension `ext` until the rest fit in `max_bytes`,
/// `keep` last.
pub fn evict(dir: &Path, ext: &str, max_bytes: u64, keep: &Path) {
    let Ok(entries) = std::fs::read_dir(dir) else { return };
    let mut files: Vec<(std::time::SystemTime, u64, PathBuf)> = entries
        .filter_map(Result::ok)
        .filter(|e| e.path().extension().is_some_and(|x| x == ext))
        .filter_map(|e| {
            let m = e.metadata().ok()?;
            Some((m.modified().ok()?, m.len(), e.path()))
        })
        .collect();
    let mut total: u64 = files.iter().map(|f| f.1).sum();
    // Oldest first; the file just written last of all.
    files.sort_by_key(|f| (f.2 == keep, f.0));
    for (_, len, path) in files {
        if total <= max_bytes {
            break;
        }
        if std::fs::remove_file(&path).is_ok() {
            total -= len;
        }
    }
}
