//! The files `mislab bench --suite lecture` needs beyond the built-in scenes — an environment map with a strong
//! sun and a glTF model of metal and rough spheres, both CC0 (see assets/LICENSES.md) — embedded in the binary
//! and written beside the results, so the suite runs from the binary alone and its inputs stay with its outputs.

use crate::lab::LabError;
use std::path::{Path, PathBuf};

/// Poly Haven's noon_grass_1k.hdr: a small, strong sun (59 % of the power in 0.1 % of the pixels).
const SKY: (&str, &[u8]) = ("noon_grass_1k.hdr", include_bytes!("../../assets/env/noon_grass_1k.hdr"));
/// Khronos' MetalRoughSpheresNoTextures.glb: a sweep of metallic × roughness spheres.
const SPHERES: (&str, &[u8]) =
    ("MetalRoughSpheresNoTextures.glb", include_bytes!("../../assets/models/MetalRoughSpheresNoTextures.glb"));

/// Where the suite's inputs were written.
#[derive(Clone, Debug)]
pub struct SuiteInputs {
    /// The environment map.
    pub sky: PathBuf,
    /// The glTF model.
    pub spheres: PathBuf,
}

/// Writes the inputs into `dir` (rewriting a file only when its content differs) and returns their paths.
pub fn write_to(dir: &Path) -> Result<SuiteInputs, LabError> {
    std::fs::create_dir_all(dir).map_err(|e| LabError::Input(format!("{}: {e}", dir.display())))?;
    let put = |(name, bytes): (&str, &[u8])| -> Result<PathBuf, LabError> {
        let path = dir.join(name);
        if std::fs::read(&path).ok().as_deref() != Some(bytes) {
            std::fs::write(&path, bytes).map_err(|e| LabError::Input(format!("{}: {e}", path.display())))?;
        }
        Ok(path)
    };
    Ok(SuiteInputs { sky: put(SKY)?, spheres: put(SPHERES)? })
}
