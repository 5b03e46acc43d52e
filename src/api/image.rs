//! A render's result: the per-pixel mean and variance with what produced them (spp, seconds, rays, NaN/Inf
//! samples, whether it was interrupted, the settings), written as the CLI writes it.

use super::budget::RenderStats;
use super::error::ApiError;
use crate::render::film::{Film, Tonemap};
use crate::render::settings::Settings;
use crate::render::sky_probe::SkyProbe;
use crate::scene::SceneSpec;
use std::path::Path;

/// A rendered image.
#[derive(Clone, Debug)]
pub struct Image {
    /// The accumulated film: mean, sum of squared deviations and sample counts per pixel.
    pub film: Film,
    /// What the render did.
    pub stats: RenderStats,
    /// The settings it was rendered with (film size included).
    pub settings: Settings,
    /// The scene as it was named.
    pub scene: SceneSpec,
    /// The sample indices this render added, `[first, next)` (a part's or a resumed render's differ from 0..spp).
    pub sample_range: (u32, u32),
    /// Of the environment guide's slots (region × normal), how many draw sky samples from it, where it is on.
    pub guide_coverage: Option<(usize, usize)>,
    /// What the sky probe saw, where it ran (it decides `--env-sampling auto`; `settings` holds the choice).
    pub sky_probe: Option<SkyProbe>,
}

impl Image {
    /// Width in pixels.
    pub fn width(&self) -> u32 {
        self.film.width
    }

    /// Height in pixels.
    pub fn height(&self) -> u32 {
        self.film.height
    }

    /// Mean radiance per pixel, row-major from the top (linear, RGB).
    pub fn mean(&self) -> &[[f32; 3]] {
        &self.film.mean
    }

    /// Each pixel's sample variance per channel (of one sample: the mean's variance is this over `count`); 0
    /// where a pixel has fewer than two samples.
    pub fn variance(&self) -> impl ExactSizeIterator<Item = [f32; 3]> + '_ {
        self.film.m2.iter().zip(&self.film.count).map(
            |(m2, &n)| {
                if n < 2 {
                    [0.0; 3]
                } else {
                    m2.map(|v| v / (n - 1) as f32)
                }
            },
        )
    }

    /// Samples per pixel of this render in every pixel (a time budget's last partial pass aside).
    pub fn spp(&self) -> u32 {
        self.stats.spp
    }

    /// The header attributes written with the image: spp, seconds, scene, settings (JSON), software.
    pub fn attributes(&self) -> Vec<(String, String)> {
        header_attributes(&self.scene, &self.settings, &self.stats)
    }

    /// Writes PNG (tonemapped with the settings' exposure) or EXR (linear) by the extension of `path`, with the
    /// header attributes; refuses to replace a read-only file unless `force`.
    pub fn save(&self, path: &Path, tonemap: Tonemap, force: bool) -> Result<(), ApiError> {
        let target = crate::io::output_file::check(path, force)?;
        self.save_to(&target, tonemap)
    }

    /// `save` to an output already checked (the CLI checks before rendering).
    pub fn save_to(&self, target: &crate::io::output_file::OutputTarget, tonemap: Tonemap) -> Result<(), ApiError> {
        self.film.save_to(target, self.settings.exposure, tonemap, &self.attributes()).map_err(ApiError::from)
    }
}

/// The custom header attributes of a rendered image: spp, seconds, scene, settings (JSON), software.
pub fn header_attributes(scene: &SceneSpec, settings: &Settings, stats: &RenderStats) -> Vec<(String, String)> {
    vec![
        ("spp".into(), stats.spp.to_string()),
        // Rows of a time-budgeted render whose pixels hold one sample more (its last, partial pass).
        ("extraSampleRows".into(), stats.extra_rows.to_string()),
        ("renderSeconds".into(), format!("{:.3}", stats.seconds)),
        ("nonfiniteSamples".into(), stats.nonfinite.to_string()),
        ("seed".into(), settings.seed.to_string()),
        ("interrupted".into(), stats.interrupted.to_string()),
        ("scene".into(), scene.scene.clone()),
        ("environment".into(), scene.env.as_ref().map(|p| p.display().to_string()).unwrap_or_default()),
        ("envScale".into(), scene.env_scale.to_string()),
        ("envRotation".into(), scene.env_rotation.to_string()),
        ("mislabSettings".into(), serde_json::to_string(settings).unwrap_or_default()),
        ("mislabVersion".into(), env!("CARGO_PKG_VERSION").to_string()),
    ]
}
