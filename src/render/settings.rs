//! Settings: one plain struct shared by the CLI flags, the viewer panel and benchmark rows.
//! `Settings` decide *which* techniques run; scene features decide *which code exists*.

use crate::render::error::InvalidSettings;
use serde::{Deserialize, Serialize};

/// Default bounce count from which Russian roulette decides whether a path continues (issue 3: "after depth 3").
pub const RR_DEPTH: u32 = 3;

/// Default light-technique splitting at a path's first vertex where the environment guide applies: three times
/// the light samples there, at unchanged MIS weights (docs/estimators.md, "Light samples split at the first
/// vertex").
pub const FIRST_HIT_LIGHT_SPLIT: u32 = 3;

/// Declares a settings enum whose discriminants are the WGSL tag constants, with kebab-case names
/// (the CLI / viewer / bench spelling) and an `ALL` list that tests and the viewer iterate over.
macro_rules! settings_enum {
    ($(#[$m:meta])* $name:ident, $wgsl_prefix:literal { $($(#[$vm:meta])* $variant:ident = $value:literal => $text:literal),+ $(,)? }) => {
        $(#[$m])*
        #[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize, clap::ValueEnum)]
        #[serde(rename_all = "kebab-case")]
        #[repr(u32)]
        pub enum $name { $($(#[$vm])* #[value(name = $text)] #[serde(rename = $text)] $variant = $value),+ }
        impl $name {
            /// Every value, in tag order.
            pub const ALL: &'static [$name] = &[$($name::$variant),+];
            /// Prefix of the matching WGSL constants (e.g. `STRATEGY_` for `STRATEGY_MIS`).
            pub const WGSL_PREFIX: &'static str = $wgsl_prefix;
            /// The name used on the command line, in the viewer and in benchmark files.
            pub fn name(self) -> &'static str { match self { $($name::$variant => $text),+ } }
            /// The WGSL tag value.
            pub fn tag(self) -> u32 { self as u32 }
        }
        impl std::fmt::Display for $name {
            fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result { f.write_str(self.name()) }
        }
        impl std::str::FromStr for $name {
            type Err = String;
            fn from_str(s: &str) -> Result<Self, String> {
                $name::ALL.iter().copied().find(|v| v.name() == s).ok_or_else(|| {
                    format!("unknown {} '{}' (expected one of: {})", stringify!($name), s,
                        $name::ALL.iter().map(|v| v.name()).collect::<Vec<_>>().join(", "))
                })
            }
        }
    };
}

settings_enum!(
    /// What is estimated: the lecture's shade() at the first hit, or full path tracing.
    Mode, "MODE_" {
        /// Emission seen by the camera + direct illumination at the first hit.
        Direct = 0 => "direct",
        /// Path tracing with next-event estimation at every vertex.
        Path = 1 => "path",
    }
);

settings_enum!(
    /// How directions for direct illumination are chosen (the lecture's estimators).
    Strategy, "STRATEGY_" {
        /// Uniform on the hemisphere, p = 1/2π.
        Uniform = 0 => "uniform",
        /// Cosine-weighted hemisphere, p = cos/π.
        Cosine = 1 => "cosine",
        /// Sample the BSDF.
        Bsdf = 2 => "bsdf",
        /// Sample the emitters.
        Light = 3 => "light",
        /// Multiple importance sampling of light and BSDF samples.
        Mis = 4 => "mis",
    }
);

settings_enum!(
    /// How a point or direction on a chosen area light is sampled.
    LightSampling, "LIGHT_SAMPLING_" {
        /// Uniform by area, converted to solid angle by distance²/cos.
        Area = 0 => "area",
        /// Uniform in the subtended solid angle (cone, spherical triangle/rectangle).
        SolidAngle = 1 => "solid-angle",
    }
);

settings_enum!(
    /// How the environment map is sampled.
    EnvSampling, "ENV_SAMPLING_" {
        /// Uniform on the sphere.
        Uniform = 0 => "uniform",
        /// Proportional to luminance·sinθ of the equirectangular map; a constant environment by the cosine about
        /// the receiving surface's normal (its L·cos, exactly).
        Importance = 1 => "importance",
        /// As importance, but a constant environment is drawn from the cosine mixed with a guide learned from the
        /// render's first sample — where the sky is visible from, per region and normal (through windows, say;
        /// src/render/env_guide.rs).
        Guided = 2 => "guided",
        /// Guided where the camera's surfaces see little of a constant sky (inside a room), importance otherwise:
        /// decided per view by a few thousand rays on the CPU (src/render/sky_probe.rs). The renderer resolves it
        /// before compiling; its settings then hold the choice.
        Auto = 3 => "auto",
    }
);

impl Default for EnvSampling {
    fn default() -> Self {
        Settings::default().env_sampling
    }
}

settings_enum!(
    /// How one light is chosen among many.
    LightSelect, "LIGHT_SELECT_" {
        /// Every light equally likely.
        Uniform = 0 => "uniform",
        /// Proportional to emitted power (alias table).
        Power = 1 => "power",
        /// By the light tree: power, distance, orientation and the surface's normal (src/accel/light_tree.rs).
        Tree = 2 => "tree",
        /// Resampled importance sampling: `--ris-candidates` light samples by power, one kept ∝ its unshadowed
        /// contribution (docs/estimators.md).
        Ris = 3 => "ris",
        /// RIS whose `--ris-candidates` candidates the light tree draws, one kept ∝ its unshadowed contribution
        /// (docs/estimators.md).
        TreeRis = 4 => "tree-ris",
    }
);

settings_enum!(
    /// The MIS weighting heuristic.
    Heuristic, "HEURISTIC_" {
        /// w_i = n_i p_i / Σ n_k p_k.
        Balance = 0 => "balance",
        /// w_i = (n_i p_i)^β / Σ (n_k p_k)^β.
        Power = 1 => "power",
    }
);

settings_enum!(
    /// Multi-sample MIS (fixed counts per technique) or one-sample MIS (a technique chosen at random).
    MisKind, "MIS_" {
        /// n_light light samples + n_bsdf BSDF samples per shading point (Veach ch. 9).
        Multi = 0 => "multi",
        /// One sample from a technique chosen with probability n_i / Σ n_k.
        One = 1 => "one",
    }
);

settings_enum!(
    /// The sample sequence.
    SamplerKind, "SAMPLER_" {
        /// Independent uniform random numbers (PCG hash).
        Independent = 0 => "independent",
        /// Jittered strata over a target sample count.
        Stratified = 1 => "stratified",
        /// Randomised Halton.
        Halton = 2 => "halton",
        /// Hammersley (fixed sample count).
        Hammersley = 3 => "hammersley",
        /// Owen-scrambled Sobol.
        Sobol = 4 => "sobol",
        /// Screen-space blue-noise error distribution.
        BlueNoise = 5 => "blue-noise",
    }
);

settings_enum!(
    /// The pixel filter, as pbrt-v4 defines it (Mitsuba's `box`, `tent` and `gaussian` are the same shapes):
    /// a pixel's value is its radiance weighted by the filter centred on it. Samples are drawn from the filter
    /// (filter importance sampling, as pbrt-v4 does), so no sample is shared between pixels.
    PixelFilter, "FILTER_" {
        /// Constant over [−r, r]² (r = 0.5: the pixel itself).
        Box = 0 => "box",
        /// (r − |x|)(r − |y|), pbrt-v4's `triangle` and Mitsuba's `tent`.
        Triangle = 1 => "triangle",
        /// (G(x) − G(r))(G(y) − G(r)) with G a normal density of deviation `--filter-sigma`.
        Gaussian = 2 => "gaussian",
    }
);

impl PixelFilter {
    /// The radius pbrt-v4 gives the filter when none is stated (box 0.5, triangle 2, gaussian 1.5).
    pub fn default_radius(self) -> f32 {
        match self {
            PixelFilter::Box => 0.5,
            PixelFilter::Triangle => 2.0,
            PixelFilter::Gaussian => 1.5,
        }
    }
}

/// Every setting that changes what is estimated or how. Film size and sample budget live here too so
/// one struct describes a render (and a benchmark row). Each field is declared once: its doc comment is the
/// `--flag`'s help, its default is `Settings::default()`'s.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize, clap::Args)]
#[serde(default, deny_unknown_fields)]
pub struct Settings {
    /// Image width in pixels.
    #[arg(long, default_value_t = Settings::default().width)]
    pub width: u32,
    /// Image height in pixels.
    #[arg(long, default_value_t = Settings::default().height)]
    pub height: u32,
    /// direct = emission seen by the camera + direct light at the first hit (the lecture's shade()); path = path
    /// tracing with the same estimator for next-event estimation at every vertex.
    #[arg(long, value_enum, default_value_t = Settings::default().mode)]
    pub mode: Mode,
    /// Estimator for direct illumination.
    #[arg(long, value_enum, default_value_t = Settings::default().strategy)]
    pub strategy: Strategy,
    /// Area-light sampling technique.
    #[arg(long, value_enum, default_value_t = Settings::default().light_sampling)]
    pub light_sampling: LightSampling,
    /// Environment sampling technique.
    #[arg(long, value_enum, default_value_t = Settings::default().env_sampling)]
    pub env_sampling: EnvSampling,
    /// Light selection.
    #[arg(long, value_enum, default_value_t = Settings::default().light_select)]
    pub light_select: LightSelect,
    /// MIS heuristic.
    #[arg(long, value_enum, default_value_t = Settings::default().heuristic)]
    pub heuristic: Heuristic,
    /// β of the power heuristic.
    #[arg(long, default_value_t = Settings::default().power_beta)]
    pub power_beta: f32,
    /// Multi-sample or one-sample MIS.
    #[arg(long, value_enum, default_value_t = Settings::default().mis)]
    pub mis: MisKind,
    /// Candidates per light sample under `--light-select ris` (1..=64).
    #[arg(long, default_value_t = Settings::default().ris_candidates)]
    pub ris_candidates: u32,
    /// Light samples per shading point (MIS multi, light strategy).
    #[arg(long, default_value_t = Settings::default().light_samples)]
    pub light_samples: u32,
    /// BSDF samples per shading point (MIS multi, BSDF strategies).
    #[arg(long, default_value_t = Settings::default().bsdf_samples)]
    pub bsdf_samples: u32,
    /// Path mode: at a path's first vertex, where the environment guide applies (the sky seldom seen from there),
    /// the light technique takes this many times --light-samples samples and averages them (splitting), with the
    /// MIS weights of --light-samples; 1 = no splitting.
    #[arg(long, default_value_t = Settings::default().first_hit_light_split)]
    pub first_hit_light_split: u32,
    /// Sample sequence.
    #[arg(long, value_enum, default_value_t = Settings::default().sampler)]
    pub sampler: SamplerKind,
    /// Maximum path length in bounces (path mode; 1 = direct lighting only).
    #[arg(long, default_value_t = Settings::default().max_depth)]
    pub max_depth: u32,
    /// Russian roulette decides whether paths continue from this many bounces on (path mode; ≥ --max-depth turns
    /// it off).
    #[arg(long, default_value_t = Settings::default().rr_depth)]
    pub rr_depth: u32,
    /// Seed of every random number (an integer from 0 to 4294967295).
    #[arg(long, default_value_t = Settings::default().seed)]
    pub seed: u32,
    /// Pixel filter (what a pixel's value is an average of).
    #[arg(long, value_enum, default_value_t = Settings::default().filter)]
    pub filter: PixelFilter,
    /// Radius of the pixel filter in pixels (0.05 to 16; default: box 0.5, triangle 2, gaussian 1.5, as pbrt-v4).
    #[arg(long)]
    pub filter_radius: Option<f32>,
    /// Standard deviation of the gaussian filter in pixels (0.05 to 16).
    #[arg(long, default_value_t = Settings::default().filter_sigma)]
    pub filter_sigma: f32,
    /// Exposure in stops (-64 to 64) for PNG output and display (EXR output is linear radiance and ignores it).
    #[arg(long, allow_hyphen_values = true, default_value_t = Settings::default().exposure, value_parser = crate::io::cli_values::exposure)]
    pub exposure: f32,
}

impl Default for Settings {
    fn default() -> Self {
        Settings {
            width: 512,
            height: 512,
            mode: Mode::Direct,
            strategy: Strategy::Mis,
            light_sampling: LightSampling::SolidAngle,
            env_sampling: EnvSampling::Auto,
            light_select: LightSelect::Uniform,
            heuristic: Heuristic::Power,
            power_beta: 2.0,
            mis: MisKind::Multi,
            ris_candidates: 8,
            light_samples: 1,
            bsdf_samples: 1,
            first_hit_light_split: FIRST_HIT_LIGHT_SPLIT,
            sampler: SamplerKind::Independent,
            max_depth: 8,
            rr_depth: RR_DEPTH,
            seed: 0,
            exposure: 0.0,
            filter: PixelFilter::Box,
            filter_radius: None,
            filter_sigma: 0.5,
        }
    }
}

impl Settings {
    /// The pixel filter's radius: the one given, else the filter's own default.
    pub fn filter_radius(&self) -> f32 {
        self.filter_radius.unwrap_or(self.filter.default_radius())
    }

    /// Checks values that the type system does not: sizes, counts, β.
    pub fn validate(&self) -> Result<(), InvalidSettings> {
        if self.width == 0 || self.height == 0 || self.width > 16384 || self.height > 16384 {
            return Err(InvalidSettings(format!(
                "image size {}x{} is out of range (1..=16384 per side)",
                self.width, self.height
            )));
        }
        if !(self.power_beta.is_finite() && self.power_beta > 0.0 && self.power_beta <= 16.0) {
            return Err(InvalidSettings(format!("--power-beta {} is out of range (0, 16]", self.power_beta)));
        }
        if self.light_samples > 64 || self.bsdf_samples > 64 || self.light_samples + self.bsdf_samples == 0 {
            return Err(InvalidSettings("--light-samples and --bsdf-samples must be in 0..=64 and not both 0".into()));
        }
        if self.first_hit_light_split == 0 || self.light_samples * self.first_hit_light_split > 64 {
            return Err(InvalidSettings(format!(
                "--first-hit-light-split {} is out of range (1 to 64 / --light-samples)",
                self.first_hit_light_split
            )));
        }
        if self.ris_candidates == 0 || self.ris_candidates > 64 {
            return Err(InvalidSettings(format!("--ris-candidates {} is out of range (1..=64)", self.ris_candidates)));
        }
        if self.rr_depth == 0 {
            return Err(InvalidSettings("--rr-depth must be at least 1".into()));
        }
        if !(self.exposure.is_finite() && self.exposure.abs() <= crate::io::cli_values::MAX_EXPOSURE) {
            return Err(InvalidSettings(format!("exposure {} is out of range (-64..=64 stops)", self.exposure)));
        }
        let radius = self.filter_radius();
        if !(radius.is_finite() && (0.05..=16.0).contains(&radius)) {
            return Err(InvalidSettings(format!("--filter-radius {radius} is out of range (0.05 to 16 pixels)")));
        }
        if !(self.filter_sigma.is_finite() && (0.05..=16.0).contains(&self.filter_sigma)) {
            return Err(InvalidSettings(format!(
                "--filter-sigma {} is out of range (0.05 to 16 pixels)",
                self.filter_sigma
            )));
        }
        if self.max_depth == 0 || self.max_depth > 256 {
            return Err(InvalidSettings(format!("--max-depth {} is out of range (1..=256)", self.max_depth)));
        }
        Ok(())
    }
}
