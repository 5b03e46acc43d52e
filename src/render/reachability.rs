//! Which lights a strategy cannot reach, for the once-per-run warning of `render` (and the tests): delta lights
//! are found only by light sampling, and light seen through smooth glass or in a mirror (delta BSDF lobes) or
//! through a closed dielectric only by direction (BSDF) samples.

use crate::render::materials::{has_delta_lobe, is_delta, refracts};
use crate::render::scene_data::SceneData;
use crate::render::settings::{Settings, Strategy};

/// The warning, if the strategy in `s` cannot reach some of the scene's light; None if it reaches all of it.
pub fn unreachable_light_warning(data: &SceneData, s: &Settings) -> Option<String> {
    let mut parts = vec![];
    let direction_only = matches!(s.strategy, Strategy::Uniform | Strategy::Cosine | Strategy::Bsdf);
    if direction_only && data.delta_lights > 0 {
        parts.push(format!(
            "--strategy {} cannot reach the scene's {} point/spot/directional light(s) (they are delta distributions that only light sampling finds); their light is missing from this image",
            s.strategy, data.delta_lights
        ));
    }
    // Light sampling counts no emission found by direction samples, and a shadow ray cannot pass a dielectric
    // (nor leave along a delta lobe): light through glass, or seen in a mirror, is then missing.
    let delta = data.materials.iter().filter(|m| is_delta(m) || has_delta_lobe(m)).count();
    let dielectric = data.materials.iter().filter(|m| refracts(m)).count();
    if s.strategy == Strategy::Light && (delta > 0 || dielectric > 0) {
        parts.push(format!(
            "--strategy light cannot reach light through the scene's {dielectric} dielectric material(s) or along its {delta} delta (smooth glass / mirror / smooth coat) material(s): a lamp behind glass, or seen only in a mirror, is missing from this image (BSDF sampling finds it: --strategy bsdf or mis)"
        ));
    }
    (!parts.is_empty()).then(|| parts.join("; "))
}
