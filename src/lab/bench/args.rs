//! The `mislab bench` flags and the groups they describe (comma lists, a TOML file or a built-in suite).

use super::*;
use crate::lab::LabError;

/// `mislab bench` flags.
#[derive(clap::Args, Clone, Debug)]
pub struct BenchArgs {
    #[command(flatten)]
    pub scene: SceneSpec,
    /// Reference image (linear EXR, e.g. from `mislab reference`, or a .state; an 8-bit PNG is refused); without one, a reference is rendered (MIS + Sobol,
    /// --ref-spp samples) and cached in --out DIR/refs/.
    #[arg(long = "ref")]
    pub reference: Option<PathBuf>,
    /// Samples per pixel of a reference rendered here (--suite lecture renders its path-traced Cornell group's at a
    /// quarter of this: path samples cost several times direct ones, and a quarter still leaves the reference's
    /// variance 16× below that of the last point). Reports give each reference's real spp, from its header.
    #[arg(long, default_value_t = 4096)]
    pub ref_spp: u32,
    /// Light selection of a reference rendered here (the light tree converges fastest with many lights).
    #[arg(long, value_enum, default_value_t = LightSelect::Uniform)]
    pub ref_light_select: LightSelect,
    /// Configurations from a TOML file (`[[group]]` tables with the fields of the flags; see docs/samplers.md).
    #[arg(long)]
    pub config: Option<PathBuf>,
    /// Run a built-in suite instead of one configuration list.
    #[arg(long, value_enum)]
    pub suite: Option<Suite>,
    /// Estimators to compare (comma list).
    #[arg(long, value_delimiter = ',')]
    pub strategies: Vec<Strategy>,
    /// Samplers to compare (comma list).
    #[arg(long, value_delimiter = ',')]
    pub samplers: Vec<SamplerKind>,
    /// MIS heuristics to compare (comma list).
    #[arg(long, value_delimiter = ',')]
    pub heuristics: Vec<Heuristic>,
    /// Area-light sampling techniques to compare (comma list).
    #[arg(long, value_delimiter = ',')]
    pub light_samplings: Vec<LightSampling>,
    /// Environment sampling techniques to compare (comma list).
    #[arg(long, value_delimiter = ',')]
    pub env_samplings: Vec<EnvSampling>,
    /// Light selection schemes to compare (comma list).
    #[arg(long, value_delimiter = ',')]
    pub light_selects: Vec<LightSelect>,
    /// MIS flavours to compare (comma list: multi, one).
    #[arg(long = "mis", value_delimiter = ',')]
    pub mis_kinds: Vec<MisKind>,
    /// Russian-roulette start depths to compare (comma list; default 3, as `render --rr-depth`).
    #[arg(long, value_delimiter = ',')]
    pub rr_depths: Vec<u32>,
    /// RIS candidate counts M to compare (comma list, 1..=64; default 8, as `render --ris-candidates`).
    #[arg(long = "ris-candidates", value_delimiter = ',')]
    pub ris_candidates: Vec<u32>,
    /// direct or path.
    #[arg(long, value_enum, default_value_t = Mode::Direct)]
    pub mode: Mode,
    /// Image width (default: the scene file's Film size, else 512; 128 for --suite).
    #[arg(long)]
    pub width: Option<u32>,
    /// Image height (default: the scene file's Film size, else 512; 128 for --suite).
    #[arg(long)]
    pub height: Option<u32>,
    /// Maximum path length (path mode).
    #[arg(long, default_value_t = 8)]
    pub max_depth: u32,
    /// spp ladder (comma list; default 1, 2, 4, … 1024; 1 … 64 for --suite).
    #[arg(long, value_delimiter = ',')]
    pub spp: Vec<u32>,
    /// Instead of a fixed ladder: double the spp until a configuration has used this many seconds.
    #[arg(long)]
    pub time: Option<f64>,
    /// Seeds per configuration (0, 1, …), for the spread.
    #[arg(long, default_value_t = 3)]
    pub seeds: u32,
    /// Samples per pixel in one dispatch (default: the renderer's, 16, or 4 for path tracing through a BVH; halved
    /// automatically when lavapipe's loop budget drops samples).
    #[arg(long)]
    pub dispatch_spp: Option<u32>,
    /// Output directory.
    #[arg(long, default_value = "bench-out")]
    pub out: PathBuf,
}
impl BenchArgs {
    /// The groups these flags describe.
    pub fn groups(&self) -> Result<Vec<BenchGroup>, LabError> {
        if self.suite.is_some() && self.config.is_some() {
            return Err(LabError::Input("--suite and --config exclude each other".into()));
        }
        let ladder = if self.spp.is_empty() { None } else { Some(self.spp.clone()) };
        let mut groups = match (self.suite, &self.config) {
            (Some(Suite::Lecture), _) => {
                let spp = ladder.clone().unwrap_or_else(|| vec![1, 2, 4, 8, 16, 32, 64]);
                let inputs = suite_inputs::write_to(&self.out.join("inputs"))?;
                lecture_suite(
                    &inputs,
                    self.width.unwrap_or(128),
                    self.height.unwrap_or(128),
                    &spp,
                    self.seeds,
                    self.ref_spp,
                )
            }
            (None, Some(path)) => {
                let text =
                    std::fs::read_to_string(path).map_err(|e| LabError::Input(format!("{}: {e}", path.display())))?;
                let file: BenchFile =
                    toml::from_str(&text).map_err(|e| LabError::Input(format!("{}: {e}", path.display())))?;
                if file.group.is_empty() {
                    return Err(LabError::Input(format!("{}: no [[group]] tables", path.display())));
                }
                // Relative paths in the file are relative to the file.
                let dir = path.parent().unwrap_or(Path::new("."));
                file.group
                    .into_iter()
                    .enumerate()
                    .map(|(i, mut g)| {
                        if g.name.is_empty() {
                            g.name = format!("group {}", i + 1);
                        }
                        for p in [&mut g.env, &mut g.reference].into_iter().flatten() {
                            if p.is_relative() {
                                *p = dir.join(&*p);
                            }
                        }
                        if !crate::scene::builtin::NAMES.contains(&g.scene.as_str())
                            && Path::new(&g.scene).is_relative()
                        {
                            g.scene = dir.join(&g.scene).to_string_lossy().into_owned();
                        }
                        g
                    })
                    .collect()
            }
            (None, None) => vec![BenchGroup {
                name: format!("{} {}", self.scene.scene, self.mode.name()),
                scene: self.scene.scene.clone(),
                gltf_scene: self.scene.gltf_scene,
                env: self.scene.env.clone(),
                env_scale: self.scene.env_scale,
                env_rotation: self.scene.env_rotation,
                reference: self.reference.clone(),
                reference_spp: self.ref_spp,
                reference_light_select: self.ref_light_select,
                mode: self.mode,
                width: self.width.unwrap_or(512),
                height: self.height.unwrap_or(512),
                scene_film_size: self.width.is_none() && self.height.is_none(),
                max_depth: self.max_depth,
                spp: ladder.clone().unwrap_or_else(|| DEFAULT_LADDER.to_vec()),
                time: self.time,
                seeds: self.seeds,
                dispatch_spp: self.dispatch_spp.unwrap_or(0),
                strategies: self.strategies.clone(),
                samplers: self.samplers.clone(),
                heuristics: self.heuristics.clone(),
                light_samplings: self.light_samplings.clone(),
                env_samplings: self.env_samplings.clone(),
                light_selects: self.light_selects.clone(),
                mis: self.mis_kinds.clone(),
                rr_depths: self.rr_depths.clone(),
                ris_candidates: self.ris_candidates.clone(),
            }],
        };
        if self.suite.is_some() {
            for g in &mut groups {
                g.time = self.time;
                g.dispatch_spp = self.dispatch_spp.unwrap_or(0);
            }
        }
        for g in &groups {
            g.check()?;
        }
        Ok(groups)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn toml_groups_parse_and_expand() {
        let file: BenchFile = toml::from_str(
            "[[group]]\nname = \"a\"\nscene = \"veach-mis\"\nwidth = 64\nheight = 32\nspp = [1, 4]\nstrategies = [\"mis\", \"light\"]\nsamplers = [\"independent\", \"sobol\", \"blue-noise\"]\n",
        )
        .unwrap();
        let g = &file.group[0];
        assert_eq!(g.configurations().len(), 6);
        assert_eq!(g.label(&g.configurations()[5]), "light blue-noise");
        assert!(toml::from_str::<BenchFile>("[[group]]\nbogus = 1\n").is_err());
        let row_csv = to_csv(&[]);
        assert!(row_csv.starts_with("group,config,scene,mode,strategy,sampler,heuristic"));
    }
}
