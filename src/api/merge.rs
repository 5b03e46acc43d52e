//! Merging the state files of a split render (`--part K/N`) into one image, exactly as `mislab merge` does.

use super::budget::RenderStats;
use super::error::ApiError;
use super::image::Image;
use crate::scene::SceneSpec;
use crate::state::merge::{check_parts, merge as merge_parts, Part};
use crate::state::RenderState;
use std::path::{Path, PathBuf};

/// Reads the parts' state files (any order), checks that they are the complete parts of one render, and merges
/// them; writes the merged state to `state` when given. Missing, duplicate, overlapping, incomplete or foreign
/// parts are refused by name.
pub fn merge(paths: &[PathBuf], state: Option<&Path>) -> Result<Image, ApiError> {
    let parts = paths
        .iter()
        .map(|p| RenderState::read(p).map(|state| Part { path: p.clone(), state }))
        .collect::<Result<Vec<_>, _>>()?;
    let parts = check_parts(parts)?;
    let merged = merge_parts(&parts);
    if let Some(path) = state {
        merged.write(path)?;
    }
    let h = &merged.header;
    Ok(Image {
        film: merged.film(),
        stats: RenderStats {
            spp: h.spp_total,
            extra_rows: 0,
            seconds: h.seconds,
            rays: h.rays_total,
            nonfinite: h.nonfinite_total,
            interrupted: false,
        },
        settings: h.settings.clone(),
        scene: SceneSpec::named(&h.scene),
        sample_range: (0, h.spp_total),
        guide_coverage: None,
        sky_probe: None,
    })
}
