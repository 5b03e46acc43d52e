//! pbrt-v4's named spectra for conductors (`"spectrum eta" "metal-Au-eta"`, `"metal-Au-k"`, ...) as RGB η and k.
//!
//! Source: the tabulated η(λ), k(λ) that pbrt-v4 ships for these names (src/pbrt/util/spectrum.cpp, Apache-2.0: Ag,
//! Al, Au, Cu on a 299–886 nm grid, MgO 310–768 nm and TiO2 306–900 nm as dielectrics); that file does not name the
//! measurement behind each metal table. Only the reduced RGB numbers below are ours to keep; the spectra are not
//! copied here.
//! Reduction to RGB, computed once (not at run time): each spectrum s(λ) is projected onto the linear sRGB
//! channels, c = ∫ s(λ)·w_c(λ) dλ / ∫ w_c(λ) dλ over 360–830 nm at 1 nm, with w_c the sRGB colour-matching
//! functions (the XYZ→linear-sRGB matrix of IEC 61966-2-1 applied to the CIE 1931 x̄ ȳ z̄, here the multi-lobe
//! fits of Wyman, Sloan & Shirley 2013, JCGT 2(2)); dividing by ∫ w_c maps a constant spectrum to a grey.
//! η and k are reduced separately (as Tungsten's and Mitsuba's RGB conductor tables are); the normal-incidence
//! reflectances they give agree with the usual published F0 values to ~0.01 (Ag 0.970/0.959/0.912, Au
//! 0.960/0.811/0.352, Cu 0.943/0.634/0.536). k < 0 from the colour-matching functions' negative lobes is set to 0.
//! CuZn (brass): no spectral data was at hand, so its η/k are those of η = 1 with the commonly published
//! normal-incidence reflectance (0.910, 0.778, 0.423) (`MaterialKind::conductor_from_reflectance`'s mapping).

use glam::Vec3;

/// (name as in `metal-<name>-eta`, RGB η, RGB k).
// Measured optical constants; gold's 0.3926 is not π/8 (clippy's approx_constant).
#[allow(clippy::approx_constant)]
pub const NAMED_SPECTRA: &[(&str, [f32; 3], [f32; 3])] = &[
    ("Ag", [0.1288, 0.1231, 0.1522], [3.9987, 3.2990, 2.3606]),
    ("Al", [1.3692, 0.9326, 0.5728], [7.6438, 6.6205, 5.3188]),
    ("Au", [0.1213, 0.3926, 1.5868], [3.2964, 2.5224, 1.7622]),
    ("Cu", [0.1697, 0.9709, 1.2128], [3.2363, 2.5937, 2.3554]),
    ("CuZn", [1.0, 1.0, 1.0], [6.3596, 3.7441, 1.7124]),
    ("MgO", [1.7344, 1.7408, 1.7540], [0.0, 0.0, 0.0]),
    ("TiO2", [2.8696, 2.9540, 3.1951], [0.0001, 0.0, 0.0007]),
];

/// Which half of a named conductor spectrum.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Part {
    /// `metal-X-eta`.
    Eta,
    /// `metal-X-k`.
    K,
}

/// The RGB value of a pbrt named spectrum such as `metal-Au-eta`, if it is one of the table's.
pub fn lookup(name: &str, part: Part) -> Option<Vec3> {
    let rest = name.strip_prefix("metal-")?;
    let (metal, suffix) = rest.rsplit_once('-')?;
    let want = match part {
        Part::Eta => "eta",
        Part::K => "k",
    };
    if suffix != want {
        return None;
    }
    let (_, eta, k) = NAMED_SPECTRA.iter().find(|(n, _, _)| *n == metal)?;
    Some(Vec3::from_array(if part == Part::Eta { *eta } else { *k }))
}

/// Whether `name` is one of pbrt-v4's named spectra (its `GetNamedSpectrum` table, src/pbrt/util/spectrum.cpp):
/// the glasses, metals and standard illuminants, and the camera sensors' `_r` / `_g` / `_b` curves.
pub fn is_pbrt_name(name: &str) -> bool {
    const GLASSES: &[&str] = &["BK7", "BAF10", "FK51A", "LASF9", "F5", "F10", "F11"];
    const METALS: &[&str] = &["Ag", "Al", "Au", "Cu", "CuZn", "MgO", "TiO2"];
    const CAMERAS: &[&str] = &[
        "canon_eos_100d",
        "canon_eos_1dx_mkii",
        "canon_eos_200d",
        "canon_eos_200d_mkii",
        "canon_eos_5d",
        "canon_eos_5d_mkii",
        "canon_eos_5d_mkiii",
        "canon_eos_5d_mkiv",
        "canon_eos_5ds",
        "canon_eos_m",
        "hasselblad_l1d_20c",
        "nikon_d810",
        "nikon_d850",
        "sony_ilce_6400",
        "sony_ilce_7m3",
        "sony_ilce_7rm3",
        "sony_ilce_9",
    ];
    if let Some(g) = name.strip_prefix("glass-") {
        return GLASSES.contains(&g);
    }
    if let Some((metal, part)) = name.strip_prefix("metal-").and_then(|r| r.rsplit_once('-')) {
        return METALS.contains(&metal) && (part == "eta" || part == "k");
    }
    if let Some(i) = name.strip_prefix("stdillum-") {
        const ILLUMINANTS: &[&str] =
            &["A", "D50", "D65", "F1", "F2", "F3", "F4", "F5", "F6", "F7", "F8", "F9", "F10", "F11", "F12"];
        return ILLUMINANTS.contains(&i);
    }
    if name == "illum-acesD60" {
        return true;
    }
    name.rsplit_once('_').is_some_and(|(camera, c)| CAMERAS.contains(&camera) && matches!(c, "r" | "g" | "b"))
}

/// Normal-incidence reflectance of RGB η + i·k: ((η − 1)² + k²) / ((η + 1)² + k²) per channel.
pub fn f0(eta: Vec3, k: Vec3) -> Vec3 {
    let f = |n: f32, k: f32| ((n - 1.0).powi(2) + k * k) / ((n + 1.0).powi(2) + k * k);
    Vec3::new(f(eta.x, k.x), f(eta.y, k.y), f(eta.z, k.z))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lookup_and_f0() {
        let (e, k) = (lookup("metal-Au-eta", Part::Eta).unwrap(), lookup("metal-Au-k", Part::K).unwrap());
        let r = f0(e, k);
        // Gold: red over blue, and the published F0 to ~0.01.
        assert!((r - Vec3::new(0.960, 0.811, 0.352)).abs().max_element() < 2e-3, "{r}");
        assert!(lookup("metal-Au-k", Part::Eta).is_none() && lookup("metal-Xx-eta", Part::Eta).is_none());
        assert!(lookup("glass-BK7", Part::Eta).is_none());
        // CuZn: η = 1 and k from its F0.
        let brass = f0(lookup("metal-CuZn-eta", Part::Eta).unwrap(), lookup("metal-CuZn-k", Part::K).unwrap());
        assert!((brass - Vec3::new(0.910, 0.778, 0.423)).abs().max_element() < 1e-3, "{brass}");
    }

    #[test]
    fn pbrt_names() {
        for n in ["glass-BK7", "metal-Au-k", "metal-TiO2-eta", "stdillum-F12", "stdillum-D65", "nikon_d850_g"] {
            assert!(is_pbrt_name(n), "{n}");
        }
        for n in ["glass-XX", "metal-Au-x", "stdillum-F13", "stdillum-F01", "nikon_d850_x", "metal-Xx-eta", ""] {
            assert!(!is_pbrt_name(n), "{n}");
        }
    }
}
