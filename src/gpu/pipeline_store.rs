//! The driver's compiled pipelines kept across processes: a Vulkan pipeline cache (wgpu's `PipelineCache`) loaded
//! from and saved to one file per adapter and driver in the platform's cache directory.
//!
//! Why it is safe: the file holds what the driver itself serialised, and the driver keys every pipeline in it by a
//! hash of the whole pipeline (SPIR-V, entry point, constants, layout), so a changed shader is a miss, never a stale
//! hit. The file name carries wgpu's adapter key and the driver's version; wgpu checks its own header (adapter,
//! driver, `pipelineCacheUUID`) and the driver its own, and either drops data that is not its. Our frame around
//! the data adds a length and a CRC-32, so a truncated or damaged file is reported and ignored rather than handed
//! to the driver. Concurrent processes each write a private temporary file and rename it over the old one: a reader
//! sees one whole file or the other (the last writer's pipelines win; the other's compile again next time).
//! The file is bounded: past `MAX_BYTES` it is started afresh.

use crate::io::cache_file;
use std::path::{Path, PathBuf};
use std::sync::Mutex;

/// The file's first bytes, with the frame's version.
const MAGIC: &[u8; 8] = b"MISLPC01";
/// A cache past this size is not loaded (it starts empty and is rewritten with this run's pipelines).
pub const MAX_BYTES: u64 = 256 << 20;

/// A driver pipeline cache tied to its file.
pub struct PipelineStore {
    cache: wgpu::PipelineCache,
    path: PathBuf,
    /// Bytes last read or written, to skip rewriting what did not change.
    saved_len: Mutex<usize>,
    /// Whether a failed save was reported (once is enough: a read-only cache directory stays so).
    warned: std::sync::atomic::AtomicBool,
}

/// What opening the store found, for the user to read: None when it loaded cleanly or there was nothing to load.
pub type OpenNote = Option<String>;

pub use crate::io::cache_file::cache_dir;

/// The cache file for `info`'s adapter and driver in `dir`, or None where the backend has no pipeline cache.
pub fn file_for(dir: &Path, info: &wgpu::AdapterInfo) -> Option<PathBuf> {
    let key = wgpu::util::pipeline_cache_key(info)?;
    // The driver's version in the name too: an updated driver starts a new file instead of rejecting the old one.
    let driver: String = format!("{} {}", info.driver, info.driver_info)
        .chars()
        .map(|c| if c.is_ascii_alphanumeric() || c == '.' { c } else { '-' })
        .take(64)
        .collect();
    Some(dir.join(format!("{key}_{driver}.bin")))
}

/// `data` in the file's frame: magic, length, CRC-32, data (`cache_file::frame`).
pub fn frame(data: &[u8]) -> Vec<u8> {
    cache_file::frame(MAGIC, data)
}

/// The data inside a framed file, or why it cannot be used.
pub fn unframe(file: &[u8]) -> Result<&[u8], &'static str> {
    cache_file::unframe(MAGIC, file)
}

impl PipelineStore {
    /// Opens the cache file for `info` in `dir` on `device` (which must have `Features::PIPELINE_CACHE`): loads
    /// it when it is whole and ours, else starts empty and says why in the note.
    pub fn open(device: &wgpu::Device, info: &wgpu::AdapterInfo, dir: &Path) -> (Option<PipelineStore>, OpenNote) {
        let Some(path) = file_for(dir, info) else { return (None, None) };
        let mut note = None;
        let bytes = match std::fs::metadata(&path) {
            Err(_) => None,
            Ok(m) if m.len() > MAX_BYTES => {
                note = Some(format!("{}: over {} MiB, started afresh", path.display(), MAX_BYTES >> 20));
                None
            }
            Ok(_) => match std::fs::read(&path) {
                Ok(b) => Some(b),
                Err(e) => {
                    note = Some(format!("{}: cannot be read ({e}), ignored", path.display()));
                    None
                }
            },
        };
        let data = bytes.as_deref().and_then(|b| match unframe(b) {
            Ok(d) => Some(d),
            Err(why) => {
                note = Some(format!("{}: {why}, ignored (it will be rewritten)", path.display()));
                None
            }
        });
        // SAFETY: `data` is what `PipelineCache::get_data` returned for an adapter with this file's key (the name
        // says so, our checksum says it is whole), which is the contract; wgpu and the driver still check their
        // headers and fall back to an empty cache (`fallback: true`) when it is not theirs.
        let cache = unsafe {
            device.create_pipeline_cache(&wgpu::PipelineCacheDescriptor {
                label: Some("mislab pipeline store"),
                data,
                fallback: true,
            })
        };
        let saved_len = data.map_or(0, <[u8]>::len);
        let store = PipelineStore { cache, path, saved_len: Mutex::new(saved_len), warned: Default::default() };
        (Some(store), note)
    }

    /// The driver's cache, to hand to every pipeline built.
    pub fn cache(&self) -> &wgpu::PipelineCache {
        &self.cache
    }

    /// The file.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Writes the cache to its file when it has grown since the last save: to a private temporary file first,
    /// then renamed over the old one (atomic on one file system). A failure is returned for the caller to warn of;
    /// nothing depends on the file.
    pub fn save(&self) -> std::io::Result<()> {
        let Some(data) = self.cache.get_data() else { return Ok(()) };
        let mut saved = self.saved_len.lock().unwrap_or_else(|e| e.into_inner());
        if data.len() == *saved {
            return Ok(());
        }
        cache_file::write_atomically(&self.path, &frame(&data))?;
        *saved = data.len();
        Ok(())
    }
}

impl PipelineStore {
    /// `save`, with a failure printed as a warning the first time only.
    pub fn save_or_warn(&self) {
        if let Err(e) = self.save() {
            if !self.warned.swap(true, std::sync::atomic::Ordering::Relaxed) {
                eprintln!("warning: pipeline cache {}: not saved ({e})", self.path.display());
            }
        }
    }
}

impl Drop for PipelineStore {
    /// Saves what was compiled since the last save: drivers that compile a pipeline at its first dispatch (lavapipe)
    /// fill the cache after `create_compute_pipeline` returns.
    fn drop(&mut self) {
        self.save_or_warn();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_framed_cache_unframes_to_its_data_and_any_damage_is_refused() {
        let data: Vec<u8> = (0..1000u32).map(|i| (i * 7 % 251) as u8).collect();
        let file = frame(&data);
        assert_eq!(unframe(&file), Ok(&data[..]));
        assert_eq!(unframe(&frame(&[])), Ok(&[][..]));
        assert!(unframe(&file[..file.len() - 1]).unwrap_err().contains("truncated"));
        let mut flipped = file.clone();
        flipped[500] ^= 0x10;
        assert!(unframe(&flipped).unwrap_err().contains("checksum"));
        let mut other = file.clone();
        other[7] = b'9'; // a later frame version
        assert!(unframe(&other).is_err());
        assert!(unframe(b"short").is_err());
    }

    #[test]
    fn the_file_is_named_by_adapter_and_driver_with_nothing_that_leaves_its_folder() {
        let mut info = wgpu::AdapterInfo::new(wgpu::DeviceType::Cpu, wgpu::Backend::Vulkan);
        info.name = "llvmpipe".into();
        info.vendor = 0x10005;
        info.driver = "../llvmpipe".into();
        info.driver_info = "Mesa 25.0.7/x (LLVM 15)".into();
        let path = file_for(Path::new("/c"), &info).expect("Vulkan has a pipeline cache key");
        assert_eq!(path.parent(), Some(Path::new("/c")));
        let name = path.file_name().unwrap().to_str().unwrap();
        assert!(name.contains("Mesa-25.0.7-x--LLVM-15-"), "{name}");
        assert!(!name.contains('/'));
        let mut newer = info.clone();
        newer.driver_info = "Mesa 25.1.0".into();
        assert_ne!(file_for(Path::new("/c"), &newer), Some(path), "an updated driver starts a new file");
    }
}
