//! The render pipeline a repeated command will ask for, built while its scene loads.
//!
//! A repeated `mislab render` of the same scene and settings needs the same pipeline as the last run, and creating
//! it (parsing, pruning, and the driver's SPIR-V → NIR even when its own cache has the compiled code: 0.15–0.25 s on
//! lavapipe) is the largest part of such a start-up left after the caches. So each run records what its render
//! pipeline was built from (`gpu::PipelineRequest`: source, entry point, constants, layout) under a key of the
//! command and the adapter, and the next run of that command builds that pipeline on a second thread while the
//! scene loads on the first.
//!
//! A forecast is never trusted: the renderer takes the pipeline only where its own request is equal to the
//! forecast's in every byte (`PipelineMemo::take_offer`), which makes it the very pipeline the renderer would
//! have built. A changed scene, setting or program builds its own, and the forecast cost only a second core's
//! time. The files (one per command and adapter, in the cache directory's `forecast/`) are framed with a length
//! and a CRC-32 (`io::cache_file`), written atomically, and bounded in all to [`MAX_BYTES`]; a damaged one is
//! reported and ignored.

use crate::gpu::{GpuContext, PipelineRequest};
use crate::io::cache_file;
use crate::render::packed_scene::SceneLayout;
use crate::render::render_pipeline::{bind_group_layouts, layout_tag, pipeline_layout};
use crate::render::shaders;
use std::hash::{Hash, Hasher};
use std::path::{Path, PathBuf};

/// A forecast file's first bytes, with its format's version.
const MAGIC: &[u8; 8] = b"MISLPF01";
/// The folder's bound: past it, the least recently written files go (a file is about the render source's size,
/// 0.1–0.3 MB).
pub const MAX_BYTES: u64 = 64 << 20;
/// The files' extension.
const EXT: &str = "forecast";

/// The forecast file of `command` (whatever tells one run's request from another's: the scene as named, the
/// settings, the working directory) on the adapter `info`, in `dir`.
pub fn file_for(dir: &Path, command: &str, info: &wgpu::AdapterInfo) -> PathBuf {
    let mut h = std::collections::hash_map::DefaultHasher::new();
    (command, &info.name, &info.driver, &info.driver_info, info.vendor, info.device).hash(&mut h);
    dir.join(format!("{:016x}.{EXT}", h.finish()))
}

/// The folder of forecast files in the platform's cache directory, where there is one.
pub fn dir() -> Option<PathBuf> {
    cache_file::cache_dir().map(|d| d.join("forecast"))
}

/// The request kept at `path`: None where there is none; a damaged file is reported and ignored.
pub fn load(path: &Path) -> Option<PipelineRequest> {
    let bytes = std::fs::read(path).ok()?;
    match cache_file::unframe(MAGIC, &bytes).and_then(PipelineRequest::decode) {
        Ok(r) => Some(r),
        Err(e) => {
            eprintln!("warning: pipeline forecast {}: ignored ({e})", path.display());
            None
        }
    }
}

/// Keeps `request` at `path` (unless it is there already), then bounds the folder. A failed write is reported.
pub fn save(path: &Path, request: &PipelineRequest) {
    let framed = cache_file::frame(MAGIC, &request.encode());
    if std::fs::read(path).is_ok_and(|old| old == framed) {
        return;
    }
    match cache_file::write_atomically(path, &framed) {
        Ok(()) => cache_file::evict(path.parent().unwrap_or(Path::new(".")), EXT, MAX_BYTES, path),
        Err(e) => eprintln!("warning: pipeline forecast {}: not saved ({e})", path.display()),
    }
}

/// Builds the pipeline `request` describes on `ctx` and offers it to the renderer that will ask for an equal one
/// (`PipelineMemo::offer`).
pub fn prebuild(ctx: &GpuContext, request: PipelineRequest) -> Result<(), String> {
    let layout = [SceneLayout::Separate, SceneLayout::Packed]
        .into_iter()
        .find(|&l| layout_tag(l) == request.layout)
        .ok_or_else(|| format!("unknown scene layout '{}'", request.layout))?;
    let groups = bind_group_layouts(&ctx.device, layout);
    let layout = pipeline_layout(&ctx.device, [&groups[0], &groups[1]]);
    let constants: Vec<(&str, f64)> = request.constants.iter().map(|(n, v)| (n.as_str(), *v)).collect();
    let store = ctx.pipelines.store();
    let pipeline = shaders::compute_pipeline(
        &ctx.device,
        store,
        "render",
        &request.source,
        &request.entry,
        &constants,
        Some(&layout),
    )?;
    ctx.pipelines.offer(request, pipeline);
    Ok(())
}
