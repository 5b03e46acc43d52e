//! A benchmark group: one scene, film, mode, ladder and seeds, and the settings lists whose cross product are its
//! configurations.

use super::*;
use crate::lab::LabError;

/// One comparison: a scene, film, mode, ladder and seeds, and the settings lists whose cross product are its
/// configurations. The TOML file's `[[group]]` tables have these fields.
#[derive(Clone, Debug, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct BenchGroup {
    /// Title (plots, tables, file names).
    pub name: String,
    /// Built-in scene name or file.
    pub scene: String,
    /// glTF scene index.
    pub gltf_scene: Option<usize>,
    /// Environment map replacing the scene's.
    pub env: Option<PathBuf>,
    /// Its scale.
    pub env_scale: f32,
    /// Its rotation about +Y, degrees.
    pub env_rotation: f32,
    /// Reference EXR; None = render one.
    pub reference: Option<PathBuf>,
    /// spp of a reference rendered here.
    pub reference_spp: u32,
    /// Light selection of a reference rendered here (any is unbiased; the light tree converges fastest where
    /// there are many lights).
    pub reference_light_select: LightSelect,
    /// direct or path.
    pub mode: Mode,
    /// Film width.
    pub width: u32,
    /// Film height.
    pub height: u32,
    /// Use the scene file's Film / hdrfilm size instead of width × height where it has one (the command
    /// line without --width/--height; not in TOML files, whose groups always say their size or take 512).
    #[serde(skip)]
    pub scene_film_size: bool,
    /// Maximum path length.
    pub max_depth: u32,
    /// spp ladder (ignored with `time`).
    pub spp: Vec<u32>,
    /// Time budget per configuration and seed, seconds.
    pub time: Option<f64>,
    /// Seeds per configuration.
    pub seeds: u32,
    /// Samples per pixel in one dispatch (0 = by mode).
    pub dispatch_spp: u32,
    /// Estimators.
    pub strategies: Vec<Strategy>,
    /// Samplers.
    pub samplers: Vec<SamplerKind>,
    /// MIS heuristics.
    pub heuristics: Vec<Heuristic>,
    /// Area-light techniques.
    pub light_samplings: Vec<LightSampling>,
    /// Environment techniques.
    pub env_samplings: Vec<EnvSampling>,
    /// Light selection.
    pub light_selects: Vec<LightSelect>,
    /// MIS flavours.
    pub mis: Vec<MisKind>,
    /// Russian-roulette start depths.
    pub rr_depths: Vec<u32>,
    /// RIS candidate counts M (`ris`, `tree-ris`).
    pub ris_candidates: Vec<u32>,
}

impl Default for BenchGroup {
    fn default() -> Self {
        BenchGroup {
            name: String::new(),
            scene: "veach-mis".into(),
            gltf_scene: None,
            env: None,
            env_scale: 1.0,
            env_rotation: 0.0,
            reference: None,
            reference_spp: 4096,
            reference_light_select: LightSelect::Uniform,
            mode: Mode::Direct,
            width: 512,
            height: 512,
            scene_film_size: false,
            max_depth: 8,
            spp: DEFAULT_LADDER.to_vec(),
            time: None,
            seeds: 3,
            dispatch_spp: 0,
            strategies: vec![],
            samplers: vec![],
            heuristics: vec![],
            light_samplings: vec![],
            env_samplings: vec![],
            light_selects: vec![],
            mis: vec![],
            rr_depths: vec![],
            ris_candidates: vec![],
        }
    }
}

/// A TOML benchmark file: `[[group]]` tables.
#[derive(Clone, Debug, Default, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct BenchFile {
    /// The comparisons.
    pub group: Vec<BenchGroup>,
}

impl BenchGroup {
    /// The configurations: the cross product of the lists (an empty list = the default setting).
    pub fn configurations(&self) -> Vec<Settings> {
        fn or<T: Copy>(v: &[T], d: T) -> Vec<T> {
            if v.is_empty() {
                vec![d]
            } else {
                v.to_vec()
            }
        }
        fn pairs<A: Copy, B: Copy>(a: &[A], b: &[B]) -> Vec<(A, B)> {
            a.iter().flat_map(|&x| b.iter().map(move |&y| (x, y))).collect()
        }
        let d = Settings::default();
        let mut out = vec![];
        for &strategy in &or(&self.strategies, d.strategy) {
            for &sampler in &or(&self.samplers, d.sampler) {
                for &heuristic in &or(&self.heuristics, d.heuristic) {
                    for &light_sampling in &or(&self.light_samplings, d.light_sampling) {
                        for &env_sampling in &or(&self.env_samplings, d.env_sampling) {
                            for &light_select in &or(&self.light_selects, d.light_select) {
                                let ms = or(&self.ris_candidates, d.ris_candidates);
                                let mis_rr = pairs(&or(&self.mis, d.mis), &or(&self.rr_depths, d.rr_depth));
                                for ((mis, rr_depth), ris_candidates) in pairs(&mis_rr, &ms) {
                                    out.push(Settings {
                                        width: self.width,
                                        height: self.height,
                                        mode: self.mode,
                                        max_depth: self.max_depth,
                                        strategy,
                                        sampler,
                                        heuristic,
                                        light_sampling,
                                        env_sampling,
                                        light_select,
                                        mis,
                                        rr_depth,
                                        ris_candidates,
                                        ..d.clone()
                                    });
                                }
                            }
                        }
                    }
                }
            }
        }
        out
    }

    /// A label for a configuration: the values of the settings that vary within the group.
    pub fn label(&self, s: &Settings) -> String {
        let mut parts = vec![];
        if self.strategies.len() > 1 {
            parts.push(s.strategy.name());
        }
        if self.heuristics.len() > 1 {
            parts.push(s.heuristic.name());
        }
        if self.light_samplings.len() > 1 {
            parts.push(s.light_sampling.name());
        }
        if self.env_samplings.len() > 1 {
            parts.push(s.env_sampling.name());
        }
        if self.light_selects.len() > 1 {
            parts.push(s.light_select.name());
        }
        if self.mis.len() > 1 {
            parts.push(s.mis.name());
        }
        let rr = format!("rr{}", s.rr_depth);
        if self.rr_depths.len() > 1 {
            parts.push(&rr);
        }
        let m = format!("M{}", s.ris_candidates);
        if self.ris_candidates.len() > 1 {
            parts.push(&m);
        }
        if self.samplers.len() > 1 {
            parts.push(s.sampler.name());
        }
        if parts.is_empty() {
            format!("{} {}", s.strategy.name(), s.sampler.name())
        } else {
            parts.join(" ")
        }
    }

    pub(super) fn scene_spec(&self) -> SceneSpec {
        SceneSpec {
            scene: self.scene.clone(),
            gltf_scene: self.gltf_scene,
            env: self.env.clone(),
            env_scale: self.env_scale,
            env_rotation: self.env_rotation,
            allow_outside_paths: false,
        }
    }

    pub(super) fn check(&self) -> Result<(), LabError> {
        if self.seeds == 0 {
            return Err(LabError::Input(format!("group '{}': seeds must be at least 1", self.name)));
        }
        if self.time.is_none() && (self.spp.is_empty() || self.spp.contains(&0)) {
            return Err(LabError::Input(format!(
                "group '{}': the spp ladder must be non-empty and positive",
                self.name
            )));
        }
        if let Some(t) = self.time {
            if !(t.is_finite() && t > 0.0) {
                return Err(LabError::Input(format!(
                    "group '{}': time {t} must be a positive number of seconds",
                    self.name
                )));
            }
        }
        for &ris_candidates in &self.ris_candidates {
            let s = Settings { ris_candidates, ..Settings::default() };
            s.validate().map_err(|e| LabError::Input(format!("group '{}': {e}", self.name)))?;
        }
        Ok(Settings { width: self.width, height: self.height, max_depth: self.max_depth, ..Settings::default() }
            .validate()?)
    }
}
