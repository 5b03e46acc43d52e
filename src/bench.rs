//! `mislab bench`: time against error. Each configuration (settings from comma-list flags, a TOML file, or the
//! lecture suite) renders an spp ladder (or until a time budget) for several seeds; every point records GPU time
//! (timestamp queries), wall time, RMSE, relMSE, MAE and efficiency against a reference. Pipeline compilation and
//! warm-up are timed separately and left out. `--out DIR` receives results.csv, results.json, summary.md and plots
//! (error vs seconds, error vs spp, per-pixel relMSE heatmaps; PNG and SVG).
//!
//! lavapipe stops an invocation's loops after 65535 iterations in all (BVH traversal included) and the render
//! kernel loops over the samples of a dispatch, so a dispatch of many samples per pixel silently accumulates
//! fewer. Rendering here splits the samples into small dispatches and checks every pixel's count at every point.

use crate::gpu::GpuContext;
use crate::gpu_scene::{GpuScene, SceneData};
use crate::gpu_timer::GpuTimer;
use crate::metrics::{self, ErrorMetrics};
use crate::reference;
use crate::render::{Renderer, Timing};
use crate::samplers;
use crate::scene::SceneSpec;
use crate::settings::*;
use crate::suite_inputs::{self, SuiteInputs};
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// The default spp ladder: 1, 2, 4, … 1024.
pub const DEFAULT_LADDER: [u32; 11] = [1, 2, 4, 8, 16, 32, 64, 128, 256, 512, 1024];

/// Built-in benchmark suites.
#[derive(Clone, Copy, Debug, PartialEq, Eq, clap::ValueEnum, Serialize, Deserialize)]
pub enum Suite {
    /// The lecture's comparisons: direction strategies, light sampling, environment sampling, MIS heuristics,
    /// samplers (on veach-mis, area-vs-cosine, a sphere and DamagedHelmet under noon_grass_1k.hdr, cornell-box).
    Lecture,
}

/// `mislab bench` flags.
#[derive(clap::Args, Clone, Debug)]
pub struct BenchArgs {
    #[command(flatten)]
    pub scene: SceneSpec,
    /// Reference image (EXR, e.g. from `mislab reference`); without one, a reference is rendered (MIS + Sobol,
    /// --ref-spp samples) and cached in --out DIR/refs/.
    #[arg(long = "ref")]
    pub reference: Option<PathBuf>,
    /// Samples per pixel of a reference rendered here.
    #[arg(long, default_value_t = 4096)]
    pub ref_spp: u32,
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
    /// direct or path.
    #[arg(long, value_enum, default_value_t = Mode::Direct)]
    pub mode: Mode,
    /// Image width (default 512; 128 for --suite).
    #[arg(long)]
    pub width: Option<u32>,
    /// Image height (default 512; 128 for --suite).
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
    /// direct or path.
    pub mode: Mode,
    /// Film width.
    pub width: u32,
    /// Film height.
    pub height: u32,
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
            mode: Mode::Direct,
            width: 512,
            height: 512,
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
                                for (mis, rr_depth) in pairs(&or(&self.mis, d.mis), &or(&self.rr_depths, d.rr_depth)) {
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
        if self.samplers.len() > 1 {
            parts.push(s.sampler.name());
        }
        if parts.is_empty() {
            format!("{} {}", s.strategy.name(), s.sampler.name())
        } else {
            parts.join(" ")
        }
    }

    fn scene_spec(&self) -> SceneSpec {
        SceneSpec {
            scene: self.scene.clone(),
            gltf_scene: self.gltf_scene,
            env: self.env.clone(),
            env_scale: self.env_scale,
            env_rotation: self.env_rotation,
        }
    }

    fn check(&self) -> Result<(), String> {
        if self.seeds == 0 {
            return Err(format!("group '{}': seeds must be at least 1", self.name));
        }
        if self.time.is_none() && (self.spp.is_empty() || self.spp.contains(&0)) {
            return Err(format!("group '{}': the spp ladder must be non-empty and positive", self.name));
        }
        if let Some(t) = self.time {
            if !(t.is_finite() && t > 0.0) {
                return Err(format!("group '{}': time {t} must be a positive number of seconds", self.name));
            }
        }
        Settings { width: self.width, height: self.height, max_depth: self.max_depth, ..Settings::default() }.validate()
    }
}

/// The lecture suite's groups at `width`×`height`, ladder `spp`, `seeds` seeds.
pub fn lecture_suite(
    inputs: &SuiteInputs,
    width: u32,
    height: u32,
    spp: &[u32],
    seeds: u32,
    reference_spp: u32,
) -> Vec<BenchGroup> {
    let sky = inputs.sky.clone();
    let base = BenchGroup { width, height, spp: spp.to_vec(), seeds, reference_spp, ..BenchGroup::default() };
    let all_samplers = SamplerKind::ALL.to_vec();
    vec![
        BenchGroup {
            name: "Direction sampling: uniform vs cosine vs BSDF (area-vs-cosine)".into(),
            scene: "area-vs-cosine".into(),
            strategies: vec![Strategy::Uniform, Strategy::Cosine, Strategy::Bsdf],
            ..base.clone()
        },
        BenchGroup {
            name: "Area lights: area vs solid-angle sampling (veach-mis, light sampling)".into(),
            scene: "veach-mis".into(),
            strategies: vec![Strategy::Light],
            light_samplings: vec![LightSampling::Area, LightSampling::SolidAngle],
            ..base.clone()
        },
        BenchGroup {
            name: "Environment: uniform vs importance (sphere under noon_grass, light sampling)".into(),
            scene: "furnace".into(),
            env: Some(sky.clone()),
            strategies: vec![Strategy::Light],
            env_samplings: vec![EnvSampling::Uniform, EnvSampling::Importance],
            ..base.clone()
        },
        BenchGroup {
            // MIS here, as a renderer would: the glossy and mirror-like spheres find the sun through BSDF samples.
            name: "Environment: uniform vs importance (metal-rough spheres under noon_grass, MIS)".into(),
            scene: inputs.spheres.to_string_lossy().into_owned(),
            env: Some(sky.clone()),
            strategies: vec![Strategy::Mis],
            env_samplings: vec![EnvSampling::Uniform, EnvSampling::Importance],
            ..base.clone()
        },
        BenchGroup {
            name: "MIS: balance vs power heuristic (veach-mis)".into(),
            scene: "veach-mis".into(),
            strategies: vec![Strategy::Mis],
            heuristics: vec![Heuristic::Balance, Heuristic::Power],
            ..base.clone()
        },
        BenchGroup {
            name: "Samplers (veach-mis, MIS)".into(),
            scene: "veach-mis".into(),
            strategies: vec![Strategy::Mis],
            samplers: all_samplers.clone(),
            ..base.clone()
        },
        BenchGroup {
            name: "Samplers (area-vs-cosine, MIS)".into(),
            scene: "area-vs-cosine".into(),
            strategies: vec![Strategy::Mis],
            samplers: all_samplers.clone(),
            ..base.clone()
        },
        BenchGroup {
            name: "Samplers (sphere under noon_grass, MIS)".into(),
            scene: "furnace".into(),
            env: Some(sky),
            strategies: vec![Strategy::Mis],
            samplers: all_samplers,
            ..base.clone()
        },
        BenchGroup {
            name: "Samplers (cornell-box, path tracing, MIS)".into(),
            scene: "cornell-box".into(),
            mode: Mode::Path,
            strategies: vec![Strategy::Mis],
            samplers: vec![SamplerKind::Independent, SamplerKind::Sobol],
            // Path samples cost several times direct ones: a quarter of the samples still leaves the reference's
            // variance 16× below that of the last point (64 spp) at the default ladder.
            reference_spp: (reference_spp / 4).max(1),
            ..base
        },
    ]
}

impl BenchArgs {
    /// The groups these flags describe.
    pub fn groups(&self) -> Result<Vec<BenchGroup>, String> {
        if self.suite.is_some() && self.config.is_some() {
            return Err("--suite and --config exclude each other".into());
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
                let text = std::fs::read_to_string(path).map_err(|e| format!("{}: {e}", path.display()))?;
                let file: BenchFile = toml::from_str(&text).map_err(|e| format!("{}: {e}", path.display()))?;
                if file.group.is_empty() {
                    return Err(format!("{}: no [[group]] tables", path.display()));
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
                mode: self.mode,
                width: self.width.unwrap_or(512),
                height: self.height.unwrap_or(512),
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

// ---------------------------------------------------------------------------------------------------------------
// Timed, checked rendering.

/// Seconds spent rendering.
// ---------------------------------------------------------------------------------------------------------------
// Results.

/// One row of results.csv: a configuration at one spp and seed.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct BenchRow {
    /// Group title.
    pub group: String,
    /// Configuration label within the group.
    pub config: String,
    /// Scene.
    pub scene: String,
    /// direct / path.
    pub mode: String,
    /// Estimator.
    pub strategy: String,
    /// Sampler.
    pub sampler: String,
    /// MIS heuristic.
    pub heuristic: String,
    /// Area-light technique.
    pub light_sampling: String,
    /// Environment technique.
    pub env_sampling: String,
    /// Light selection.
    pub light_select: String,
    /// MIS flavour.
    pub mis: String,
    /// Russian roulette from this depth.
    pub rr_depth: u32,
    /// Film width.
    pub width: u32,
    /// Film height.
    pub height: u32,
    /// Samples per pixel.
    pub spp: u32,
    /// Seed.
    pub seed: u32,
    /// GPU seconds (timestamp queries; = wall when unavailable).
    pub seconds_gpu: f64,
    /// Wall seconds of submission + wait.
    pub seconds_wall: f64,
    /// RMSE against the reference.
    pub rmse: f64,
    /// relMSE against the reference.
    pub relmse: f64,
    /// Mean absolute error.
    pub mae: f64,
    /// 1 / (relMSE · seconds_gpu).
    pub efficiency: f64,
    /// 1 / (relMSE · seconds_wall).
    pub efficiency_wall: f64,
    /// Camera samples per second (pixels · spp / seconds_gpu).
    pub samples_per_second: f64,
    /// Rays per second, millions.
    pub mrays_per_second: f64,
    /// Rays traced.
    pub rays: u64,
    /// Pipeline compilation of this configuration, seconds (reported once, with seed 0's rows).
    pub compile_seconds: f64,
    /// First-dispatch warm-up, seconds.
    pub warmup_seconds: f64,
    /// Samples per pixel in one dispatch.
    pub dispatch_spp: u32,
}

/// CSV columns, in order.
pub const CSV_COLUMNS: &[&str] = &[
    "group",
    "config",
    "scene",
    "mode",
    "strategy",
    "sampler",
    "heuristic",
    "light_sampling",
    "env_sampling",
    "light_select",
    "mis",
    "rr_depth",
    "width",
    "height",
    "spp",
    "seed",
    "seconds_gpu",
    "seconds_wall",
    "rmse",
    "relmse",
    "mae",
    "efficiency",
    "efficiency_wall",
    "samples_per_second",
    "mrays_per_second",
    "rays",
    "compile_seconds",
    "warmup_seconds",
    "dispatch_spp",
];

fn csv_field(s: &str) -> String {
    if s.contains([',', '"', '\n']) {
        format!("\"{}\"", s.replace('"', "\"\""))
    } else {
        s.to_string()
    }
}

/// results.csv text.
pub fn to_csv(rows: &[BenchRow]) -> String {
    let mut out = CSV_COLUMNS.join(",") + "\n";
    for r in rows {
        let f: Vec<String> = vec![
            csv_field(&r.group),
            csv_field(&r.config),
            csv_field(&r.scene),
            r.mode.clone(),
            r.strategy.clone(),
            r.sampler.clone(),
            r.heuristic.clone(),
            r.light_sampling.clone(),
            r.env_sampling.clone(),
            r.light_select.clone(),
            r.mis.clone(),
            r.rr_depth.to_string(),
            r.width.to_string(),
            r.height.to_string(),
            r.spp.to_string(),
            r.seed.to_string(),
            format!("{:.6}", r.seconds_gpu),
            format!("{:.6}", r.seconds_wall),
            format!("{:.6e}", r.rmse),
            format!("{:.6e}", r.relmse),
            format!("{:.6e}", r.mae),
            format!("{:.6e}", r.efficiency),
            format!("{:.6e}", r.efficiency_wall),
            format!("{:.6e}", r.samples_per_second),
            format!("{:.4}", r.mrays_per_second),
            r.rays.to_string(),
            format!("{:.3}", r.compile_seconds),
            format!("{:.3}", r.warmup_seconds),
            r.dispatch_spp.to_string(),
        ];
        out += &f.join(",");
        out += "\n";
    }
    out
}

/// The per-configuration summary of one group (means over seeds at each spp).
#[derive(Clone, Debug, Serialize)]
pub struct ConfigSummary {
    /// Label.
    pub config: String,
    /// spp of each point.
    pub spp: Vec<u32>,
    /// Mean GPU seconds per point.
    pub seconds: Vec<f64>,
    /// Mean, min and max relMSE per point over seeds.
    pub relmse: Vec<[f64; 3]>,
    /// Mean RMSE per point.
    pub rmse: Vec<f64>,
    /// Fitted RMSE ∝ spp^slope over the ladder.
    pub rmse_slope: Option<f64>,
    /// Efficiency 1 / (relMSE · seconds) at the last point, of the means over seeds.
    pub efficiency: f64,
    /// Samples per second (mean over points and seeds).
    pub samples_per_second: f64,
    /// Mrays/s.
    pub mrays_per_second: f64,
    /// Seconds to reach relMSE 1e-2 and 1e-3 (log-log interpolation of the mean curve), if reached.
    pub seconds_to: [Option<f64>; 2],
    /// Compilation and warm-up seconds.
    pub compile_seconds: f64,
}

fn summarize(rows: &[&BenchRow]) -> ConfigSummary {
    let mut by_spp: BTreeMap<u32, Vec<&BenchRow>> = BTreeMap::new();
    for r in rows {
        by_spp.entry(r.spp).or_default().push(r);
    }
    let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len().max(1) as f64;
    let mut s = ConfigSummary {
        config: rows.first().map(|r| r.config.clone()).unwrap_or_default(),
        spp: vec![],
        seconds: vec![],
        relmse: vec![],
        rmse: vec![],
        rmse_slope: None,
        efficiency: 0.0,
        samples_per_second: mean(&rows.iter().map(|r| r.samples_per_second).collect::<Vec<_>>()),
        mrays_per_second: mean(&rows.iter().map(|r| r.mrays_per_second).collect::<Vec<_>>()),
        seconds_to: [None, None],
        compile_seconds: rows.iter().map(|r| r.compile_seconds + r.warmup_seconds).fold(0.0, f64::max),
    };
    for (spp, rs) in &by_spp {
        let rel: Vec<f64> = rs.iter().map(|r| r.relmse).collect();
        s.spp.push(*spp);
        s.seconds.push(mean(&rs.iter().map(|r| r.seconds_gpu).collect::<Vec<_>>()));
        s.relmse.push([
            mean(&rel),
            rel.iter().copied().fold(f64::INFINITY, f64::min),
            rel.iter().copied().fold(0.0, f64::max),
        ]);
        s.rmse.push(mean(&rs.iter().map(|r| r.rmse).collect::<Vec<_>>()));
    }
    // Efficiency of the means (not the mean of per-seed efficiencies, which one lucky seed without fireflies
    // would dominate).
    if let (Some(e), Some(t)) = (s.relmse.last(), s.seconds.last()) {
        s.efficiency = metrics::efficiency(e[0], *t);
    }
    let xs: Vec<f64> = s.spp.iter().map(|&n| n as f64).collect();
    s.rmse_slope = metrics::loglog_slope(&xs, &s.rmse);
    for (k, target) in [1e-2f64, 1e-3].iter().enumerate() {
        for i in 0..s.spp.len() {
            let e = s.relmse[i][0];
            if e <= *target {
                s.seconds_to[k] = Some(if i == 0 {
                    s.seconds[0] * e / target
                } else {
                    // Interpolate log seconds against log error between the two points around the target.
                    let (e0, e1) = (s.relmse[i - 1][0].ln(), e.ln());
                    let (t0, t1) = (s.seconds[i - 1].max(1e-9).ln(), s.seconds[i].max(1e-9).ln());
                    let f = if (e1 - e0).abs() > 0.0 { (target.ln() - e0) / (e1 - e0) } else { 1.0 };
                    (t0 + f * (t1 - t0)).exp()
                });
                break;
            }
        }
    }
    s
}

// ---------------------------------------------------------------------------------------------------------------
// Running.

struct GroupResult {
    group: BenchGroup,
    rows: Vec<BenchRow>,
    /// Per configuration label: mean per-pixel relMSE over seeds at the last point.
    heatmaps: Vec<(String, Vec<f64>)>,
    reference: String,
}

fn slug(s: &str) -> String {
    let mut out = String::new();
    for c in s.chars() {
        if c.is_ascii_alphanumeric() {
            out.push(c.to_ascii_lowercase());
        } else if !out.ends_with('-') && !out.is_empty() {
            out.push('-');
        }
    }
    out.trim_end_matches('-').chars().take(60).collect()
}

/// The group's reference: the given file, or one rendered (MIS, Sobol) and cached under `refs`.
fn group_reference(
    ctx: &GpuContext,
    g: &BenchGroup,
    scene: &crate::scene::Scene,
    refs: &Path,
) -> Result<(Vec<[f32; 3]>, String), String> {
    if let Some(path) = &g.reference {
        let r = reference::read_exr(path)?;
        if (r.width, r.height) != (g.width, g.height) {
            return Err(format!(
                "{}: the reference is {}x{}, the benchmark renders {}x{}",
                path.display(),
                r.width,
                r.height,
                g.width,
                g.height
            ));
        }
        return Ok((r.pixels, path.display().to_string()));
    }
    let settings = reference::reference_settings(&Settings {
        width: g.width,
        height: g.height,
        mode: g.mode,
        max_depth: g.max_depth,
        ..Settings::default()
    });
    let key = format!(
        "{}-{}{}-{}x{}-d{}-{}spp",
        slug(Path::new(&g.scene).file_stem().and_then(|s| s.to_str()).unwrap_or(&g.scene)),
        g.mode.name(),
        g.env
            .as_ref()
            .map(|e| format!("-{}", slug(&e.file_stem().unwrap_or_default().to_string_lossy())))
            .unwrap_or_default(),
        g.width,
        g.height,
        g.max_depth,
        g.reference_spp
    );
    let path = refs.join(format!("{key}.exr"));
    if path.exists() {
        if let Ok(r) = reference::read_exr(&path) {
            if (r.width, r.height) == (g.width, g.height)
                && r.attributes.get("spp").map(|s| s.as_str()) == Some(g.reference_spp.to_string().as_str())
            {
                eprintln!("reference: reusing {}", path.display());
                return Ok((r.pixels, path.display().to_string()));
            }
        }
    }
    std::fs::create_dir_all(refs).map_err(|e| format!("{}: {e}", refs.display()))?;
    eprintln!("reference: rendering {} spp of {} ({}) ...", g.reference_spp, g.scene, g.mode.name());
    let t = Instant::now();
    let (film, stats) = reference::render_reference(
        ctx,
        scene,
        &settings,
        crate::progressive::Budget::Samples(g.reference_spp),
        g.dispatch_spp,
    )?;
    eprintln!("reference: {} spp in {:.1} s", stats.spp, t.elapsed().as_secs_f64());
    reference::write_exr(&path, &film, &reference::header_attributes(&g.scene_spec(), &settings, &stats))?;
    Ok((film.mean, path.display().to_string()))
}

fn run_group(ctx: &GpuContext, g: &BenchGroup, refs: &Path) -> Result<GroupResult, String> {
    let scene = g.scene_spec().load()?;
    let (reference, ref_name) = group_reference(ctx, g, &scene, refs)?;
    let configs = g.configurations();
    let data = SceneData::build(&scene);
    let gpu_scene = GpuScene::upload(ctx, data).map_err(|e| format!("{}: {e}", g.scene))?;
    let mut renderer: Option<Renderer> = None;
    let mut rows = vec![];
    let mut heatmaps = vec![];
    let pixels = (g.width * g.height) as f64;
    for settings in &configs {
        let label = g.label(settings);
        // Compile (or find) the pipeline, then one warm-up sample; both timed apart from the measurements.
        let t0 = Instant::now();
        let r = match &mut renderer {
            Some(r) => {
                r.set_settings(settings.clone())?;
                r
            }
            None => renderer.insert(Renderer::new_unprepared(ctx, &gpu_scene, scene.camera.clone(), settings.clone())?),
        };
        r.prepare()?;
        r.warm_up(ctx).map_err(|e| e.to_string())?;
        // The renderer's own dispatch size (as `mislab render` uses), unless the group fixes one.
        let mut dispatch_spp = if g.dispatch_spp > 0 { g.dispatch_spp } else { r.max_dispatch_spp() };
        let compile_seconds = t0.elapsed().as_secs_f64();
        let t1 = Instant::now();
        r.render(ctx, 1).map_err(|e| e.to_string())?;
        let warmup_seconds = t1.elapsed().as_secs_f64();
        eprintln!("{} / {label}: pipeline ready in {compile_seconds:.2} s, warm-up {warmup_seconds:.2} s", g.name);
        let mut sum_heat: Option<Vec<f64>> = None;
        let mut timer = GpuTimer::new(ctx, 64);
        for seed in 0..g.seeds {
            let mut attempt = 0;
            let seed_rows = loop {
                r.set_dispatch_spp(Some(dispatch_spp));
                match run_seed(ctx, r, &mut timer, g, settings, seed, &reference) {
                    Ok(v) => break v,
                    Err(SeedError::Incomplete(spp)) if dispatch_spp > 1 && attempt < 8 => {
                        dispatch_spp /= 2;
                        attempt += 1;
                        eprintln!("  lavapipe's loop budget dropped samples at {spp} spp; retrying with {dispatch_spp} spp per dispatch");
                    }
                    Err(SeedError::Incomplete(spp)) => {
                        return Err(format!("{label}: pixels miss samples at {spp} spp even with 1 spp per dispatch"))
                    }
                    Err(SeedError::Other(e)) => return Err(e),
                }
            };
            for (point, heat) in seed_rows {
                let seconds = point.timing.seconds();
                let m = point.metrics;
                rows.push(BenchRow {
                    group: g.name.clone(),
                    config: label.clone(),
                    scene: g.scene.clone(),
                    mode: settings.mode.name().into(),
                    strategy: settings.strategy.name().into(),
                    sampler: settings.sampler.name().into(),
                    heuristic: settings.heuristic.name().into(),
                    light_sampling: settings.light_sampling.name().into(),
                    env_sampling: settings.env_sampling.name().into(),
                    light_select: settings.light_select.name().into(),
                    mis: settings.mis.name().into(),
                    rr_depth: settings.rr_depth,
                    width: g.width,
                    height: g.height,
                    spp: point.spp,
                    seed,
                    seconds_gpu: seconds,
                    seconds_wall: point.timing.wall,
                    rmse: m.rmse,
                    relmse: m.relmse,
                    mae: m.mae,
                    efficiency: metrics::efficiency(m.relmse, seconds),
                    efficiency_wall: metrics::efficiency(m.relmse, point.timing.wall),
                    samples_per_second: pixels * point.spp as f64 / seconds.max(1e-12),
                    mrays_per_second: point.timing.rays as f64 / seconds.max(1e-12) / 1e6,
                    rays: point.timing.rays,
                    compile_seconds: if seed == 0 { compile_seconds } else { 0.0 },
                    warmup_seconds: if seed == 0 { warmup_seconds } else { 0.0 },
                    dispatch_spp,
                });
                if let Some(h) = heat {
                    match &mut sum_heat {
                        Some(s) => s.iter_mut().zip(&h).for_each(|(a, b)| *a += b),
                        None => sum_heat = Some(h),
                    }
                }
            }
        }
        let last = rows.last().expect("a row");
        eprintln!(
            "  {label}: {} spp: relMSE {:.3e}, {:.3} s GPU, {:.2} M samples/s",
            last.spp,
            last.relmse,
            last.seconds_gpu,
            last.samples_per_second / 1e6
        );
        if let Some(mut h) = sum_heat {
            h.iter_mut().for_each(|v| *v /= g.seeds as f64);
            heatmaps.push((label, h));
        }
    }
    Ok(GroupResult { group: g.clone(), rows, heatmaps, reference: ref_name })
}

struct Point {
    spp: u32,
    timing: Timing,
    metrics: ErrorMetrics,
}

enum SeedError {
    /// Some pixel holds fewer samples than dispatched (at this spp).
    Incomplete(u32),
    Other(String),
}

impl From<String> for SeedError {
    fn from(e: String) -> Self {
        SeedError::Other(e)
    }
}

/// One configuration and seed over the ladder (or the time budget). Progressive samplers render the ladder as
/// prefixes of one run; fixed-count ones (stratified, Hammersley) render each point afresh with their target
/// set to it. Returns the points, the last one with its per-pixel relMSE.
#[allow(clippy::type_complexity)]
fn run_seed(
    ctx: &GpuContext,
    r: &mut Renderer,
    timer: &mut Option<GpuTimer>,
    g: &BenchGroup,
    settings: &Settings,
    seed: u32,
    reference: &[[f32; 3]],
) -> Result<Vec<(Point, Option<Vec<f64>>)>, SeedError> {
    r.set_settings(Settings { seed, ..settings.clone() })?;
    let fixed = samplers::is_fixed_count(settings.sampler);
    let ladder: Vec<u32> = match g.time {
        Some(_) => (0..24).map(|k| 1u32 << k).collect(),
        None => g.spp.clone(),
    };
    let mut points: Vec<(Point, Option<Vec<f64>>)> = vec![];
    let mut cumulative = Timing { gpu: Some(0.0), ..Timing::default() };
    for (k, &requested) in ladder.iter().enumerate() {
        let spp = samplers::check_spp(settings.sampler, requested)?;
        if !fixed && spp < r.samples() {
            continue;
        }
        let timing = if fixed {
            r.reset();
            r.set_sampler_spp(spp);
            r.render_timed(ctx, spp, timer.as_mut())?
        } else {
            r.set_sampler_spp(samplers::DEFAULT_SAMPLER_SPP);
            let t = r.render_timed(ctx, spp - r.samples(), timer.as_mut())?;
            cumulative = Timing {
                gpu: cumulative.gpu.zip(t.gpu).map(|(a, b)| a + b),
                wall: cumulative.wall + t.wall,
                rays: cumulative.rays + t.rays,
            };
            cumulative
        };
        let film = r.film(ctx).map_err(|e| e.to_string())?;
        if !film.is_complete(spp) {
            return Err(SeedError::Incomplete(spp));
        }
        let m = metrics::compare(&film.mean, reference)?;
        let last = match g.time {
            Some(t) => timing.seconds() >= t || k + 1 == ladder.len(),
            None => k + 1 == ladder.len(),
        };
        let heat = if last { Some(metrics::per_pixel_relmse(&film.mean, reference)?) } else { None };
        points.push((Point { spp, timing, metrics: m }, heat));
        if last {
            break;
        }
    }
    Ok(points)
}

/// Runs `mislab bench`.
pub fn run(args: &BenchArgs) -> Result<(), String> {
    let groups = args.groups()?;
    let ctx = GpuContext::new().map_err(|e| e.to_string())?;
    eprintln!(
        "adapter: {} ({:?}); GPU time from {}",
        ctx.info.name,
        ctx.info.device_type,
        if ctx.timestamps { "timestamp queries" } else { "wall clock (no TIMESTAMP_QUERY)" }
    );
    std::fs::create_dir_all(&args.out).map_err(|e| format!("{}: {e}", args.out.display()))?;
    let refs = args.out.join("refs");
    let mut results = vec![];
    for g in &groups {
        if !crate::scene::builtin::NAMES.contains(&g.scene.as_str()) && !Path::new(&g.scene).exists() {
            eprintln!("leaving out '{}': {} not found", g.name, g.scene);
            continue;
        }
        if let Some(env) = g.env.as_ref().filter(|e| !e.exists()) {
            eprintln!("leaving out '{}': {} not found", g.name, env.display());
            continue;
        }
        eprintln!(
            "== {} ({} configurations × {} seeds, {}x{})",
            g.name,
            g.configurations().len(),
            g.seeds,
            g.width,
            g.height
        );
        results.push(run_group(&ctx, g, &refs)?);
    }
    write_outputs(&args.out, &ctx, &results)
}

fn write_outputs(out: &Path, ctx: &GpuContext, results: &[GroupResult]) -> Result<(), String> {
    let rows: Vec<BenchRow> = results.iter().flat_map(|r| r.rows.clone()).collect();
    let write = |name: &str, text: &str| -> Result<(), String> {
        let p = out.join(name);
        std::fs::write(&p, text).map_err(|e| format!("{}: {e}", p.display()))
    };
    write("results.csv", &to_csv(&rows))?;
    let summaries: Vec<(String, Vec<ConfigSummary>)> = results
        .iter()
        .map(|res| {
            let mut labels: Vec<String> = vec![];
            for r in &res.rows {
                if !labels.contains(&r.config) {
                    labels.push(r.config.clone());
                }
            }
            let s = labels
                .iter()
                .map(|l| summarize(&res.rows.iter().filter(|r| &r.config == l).collect::<Vec<_>>()))
                .collect();
            (res.group.name.clone(), s)
        })
        .collect();
    let json = serde_json::json!({
        "device": { "name": ctx.info.name, "type": format!("{:?}", ctx.info.device_type), "driver": format!("{} {}", ctx.info.driver, ctx.info.driver_info), "timestamps": ctx.timestamps },
        "groups": results.iter().zip(&summaries).map(|(r, (_, s))| serde_json::json!({ "group": r.group, "reference": r.reference, "summary": s })).collect::<Vec<_>>(),
        "rows": rows,
    });
    write("results.json", &serde_json::to_string_pretty(&json).map_err(|e| e.to_string())?)?;
    let mut md = format!("# Benchmark results\n\nDevice: {} ({:?}). Times are GPU time from timestamp queries; pipeline compilation and warm-up are excluded (listed separately). relMSE = mean over pixels and channels of (x − r)² / (r² + 0.01); efficiency = 1 / (relMSE · seconds).\n", ctx.info.name, ctx.info.device_type);
    for (res, (name, sums)) in results.iter().zip(&summaries) {
        let base = slug(name);
        plot::error_plots(out, &base, name, sums)?;
        plot::heatmaps(out, &base, name, res.group.width, res.group.height, &res.heatmaps)?;
        md += &format!(
            "\n## {name}\n\n{} at {}x{}, {} seed(s), reference {}.\n\n| configuration | spp | relMSE (mean over seeds) | GPU s | efficiency (of the means) | RMSE slope | M samples/s | Mrays/s | s to relMSE 1e-2 | s to 1e-3 | compile + warm-up s |\n|---|---|---|---|---|---|---|---|---|---|---|\n",
            res.group.scene, res.group.width, res.group.height, res.group.seeds, res.reference
        );
        for s in sums {
            let i = s.spp.len().saturating_sub(1);
            let opt = |v: Option<f64>| v.map(|x| format!("{x:.3}")).unwrap_or_else(|| "—".into());
            md += &format!(
                "| {} | {} | {:.3e} | {:.3} | {:.3e} | {} | {:.2} | {:.2} | {} | {} | {:.2} |\n",
                s.config,
                s.spp.get(i).copied().unwrap_or(0),
                s.relmse.get(i).map(|r| r[0]).unwrap_or(f64::NAN),
                s.seconds.get(i).copied().unwrap_or(f64::NAN),
                s.efficiency,
                s.rmse_slope.map(|x| format!("{x:.2}")).unwrap_or_else(|| "—".into()),
                s.samples_per_second / 1e6,
                s.mrays_per_second,
                opt(s.seconds_to[0]),
                opt(s.seconds_to[1]),
                s.compile_seconds
            );
        }
        if let (Some(best), Some(worst)) = (
            sums.iter().max_by(|a, b| a.efficiency.total_cmp(&b.efficiency)),
            sums.iter().min_by(|a, b| a.efficiency.total_cmp(&b.efficiency)),
        ) {
            if sums.len() > 1 {
                md += &format!(
                    "\nWinner: **{}**, {:.1}× the efficiency of {} (the least efficient) at the last point.\n",
                    best.config,
                    best.efficiency / worst.efficiency.max(1e-300),
                    worst.config
                );
            }
        }
        md += &format!("\n![relMSE vs seconds]({base}-error-vs-time.png) ![relMSE vs spp]({base}-error-vs-spp.png)\n\n![per-pixel relMSE]({base}-heatmaps.png)\n");
    }
    write("summary.md", &md)?;
    eprintln!("wrote {}/results.csv, results.json, summary.md and plots", out.display());
    Ok(())
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

/// Plots (plotters): PNG through an in-memory RGB bitmap encoded by `image`, and SVG. Text uses egui's Hack
/// font, registered with plotters' ab_glyph text backend (no system fonts needed).
pub mod plot {
    use super::ConfigSummary;
    use plotters::coord::Shift;
    use plotters::prelude::*;
    use std::path::Path;

    /// Registers the font once.
    pub fn register_font() {
        static ONCE: std::sync::Once = std::sync::Once::new();
        ONCE.call_once(|| {
            for family in ["sans-serif", "serif", "monospace"] {
                for style in [FontStyle::Normal, FontStyle::Bold, FontStyle::Italic, FontStyle::Oblique] {
                    let _ = plotters::style::register_font(family, style, epaint_default_fonts::HACK_REGULAR);
                }
            }
        });
    }

    /// Something drawn on any backend.
    pub trait Figure {
        /// Draws on `root`.
        fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<(), String>;
    }

    /// Writes `figure` as `base.png` and `base.svg` in `dir`.
    pub fn save(dir: &Path, base: &str, size: (u32, u32), figure: &impl Figure) -> Result<(), String> {
        save_png(&dir.join(format!("{base}.png")), size, figure)?;
        save_svg(&dir.join(format!("{base}.svg")), size, figure)
    }

    /// Writes `figure` as PNG.
    pub fn save_png(path: &Path, (w, h): (u32, u32), figure: &impl Figure) -> Result<(), String> {
        register_font();
        let mut buf = vec![255u8; (w * h * 3) as usize];
        {
            let root = BitMapBackend::with_buffer(&mut buf, (w, h)).into_drawing_area();
            figure.draw(&root)?;
            root.present().map_err(|e| e.to_string())?;
        }
        image::save_buffer(path, &buf, w, h, image::ExtendedColorType::Rgb8)
            .map_err(|e| format!("{}: {e}", path.display()))
    }

    /// Writes `figure` as SVG.
    pub fn save_svg(path: &Path, size: (u32, u32), figure: &impl Figure) -> Result<(), String> {
        register_font();
        let mut text = String::new();
        {
            let root = SVGBackend::with_string(&mut text, size).into_drawing_area();
            figure.draw(&root)?;
            root.present().map_err(|e| e.to_string())?;
        }
        std::fs::write(path, text).map_err(|e| format!("{}: {e}", path.display()))
    }

    /// Line colours (Okabe–Ito, distinguishable for colour-blind readers).
    pub fn color(i: usize) -> RGBColor {
        const C: [RGBColor; 8] = [
            RGBColor(0, 114, 178),
            RGBColor(213, 94, 0),
            RGBColor(0, 158, 115),
            RGBColor(204, 121, 167),
            RGBColor(230, 159, 0),
            RGBColor(86, 180, 233),
            RGBColor(0, 0, 0),
            RGBColor(240, 228, 66),
        ];
        C[i % C.len()]
    }

    /// A viridis-like map of t ∈ [0, 1].
    pub fn colormap(t: f64) -> RGBColor {
        const STOPS: [(f64, f64, f64); 5] =
            [(68.0, 1.0, 84.0), (59.0, 82.0, 139.0), (33.0, 145.0, 140.0), (94.0, 201.0, 98.0), (253.0, 231.0, 37.0)];
        let t = if t.is_finite() { t.clamp(0.0, 1.0) } else { 0.0 } * (STOPS.len() - 1) as f64;
        let i = (t.floor() as usize).min(STOPS.len() - 2);
        let f = t - i as f64;
        let (a, b) = (STOPS[i], STOPS[i + 1]);
        let mix = |x: f64, y: f64| (x + f * (y - x)).round() as u8;
        RGBColor(mix(a.0, b.0), mix(a.1, b.1), mix(a.2, b.2))
    }

    /// Log-log lines of mean relMSE with min–max bars over seeds, against seconds or spp.
    pub struct ErrorPlot {
        /// Caption.
        pub title: String,
        /// x-axis description.
        pub x_desc: String,
        /// Per configuration: label and points (x, mean, min, max).
        pub series: Vec<(String, Vec<(f64, f64, f64, f64)>)>,
    }

    impl Figure for ErrorPlot {
        fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<(), String> {
            let err = |e: DrawingAreaErrorKind<DB::ErrorType>| e.to_string();
            root.fill(&WHITE).map_err(err)?;
            let pts = self.series.iter().flat_map(|s| s.1.iter()).filter(|p| p.0 > 0.0 && p.2 > 0.0 && p.3.is_finite());
            let (mut x0, mut x1, mut y0, mut y1) = (f64::INFINITY, 0.0f64, f64::INFINITY, 0.0f64);
            for p in pts {
                x0 = x0.min(p.0);
                x1 = x1.max(p.0);
                y0 = y0.min(p.2);
                y1 = y1.max(p.3);
            }
            if !(x0.is_finite() && y0.is_finite() && x1 > 0.0 && y1 > 0.0) {
                return Ok(());
            }
            let mut chart = ChartBuilder::on(root)
                .caption(&self.title, ("sans-serif", 18))
                .margin(14)
                .x_label_area_size(42)
                .y_label_area_size(72)
                .build_cartesian_2d((x0 / 1.3..x1 * 1.3).log_scale(), (y0 / 1.5..y1 * 1.5).log_scale())
                .map_err(err)?;
            chart
                .configure_mesh()
                .x_desc(self.x_desc.as_str())
                .y_desc("relMSE")
                .x_label_formatter(&|v| format!("{v:.3}"))
                .y_label_formatter(&|v| format!("{v:.0e}"))
                .draw()
                .map_err(err)?;
            for (i, (label, p)) in self.series.iter().enumerate() {
                let c = color(i);
                let p: Vec<_> = p.iter().copied().filter(|q| q.0 > 0.0 && q.1 > 0.0).collect();
                chart
                    .draw_series(LineSeries::new(p.iter().map(|q| (q.0, q.1)), c.stroke_width(2)))
                    .map_err(err)?
                    .label(label.as_str())
                    .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], c.stroke_width(2)));
                chart
                    .draw_series(
                        p.iter()
                            .map(|q| ErrorBar::new_vertical(q.0, q.2.max(y0 / 1.5), q.1, q.3, c.stroke_width(1), 6)),
                    )
                    .map_err(err)?;
                chart.draw_series(p.iter().map(|q| Circle::new((q.0, q.1), 3, c.filled()))).map_err(err)?;
            }
            chart
                .configure_series_labels()
                .background_style(WHITE.mix(0.85))
                .border_style(BLACK)
                .position(SeriesLabelPosition::LowerLeft)
                .label_font(("sans-serif", 13))
                .draw()
                .map_err(err)?;
            Ok(())
        }
    }

    /// relMSE against seconds and against spp, one line per configuration.
    pub fn error_plots(dir: &Path, base: &str, title: &str, sums: &[ConfigSummary]) -> Result<(), String> {
        let series = |by_time: bool| -> Vec<(String, Vec<(f64, f64, f64, f64)>)> {
            sums.iter()
                .map(|s| {
                    let pts = (0..s.spp.len())
                        .map(|i| {
                            (
                                if by_time { s.seconds[i] } else { s.spp[i] as f64 },
                                s.relmse[i][0],
                                s.relmse[i][1],
                                s.relmse[i][2],
                            )
                        })
                        .collect();
                    (s.config.clone(), pts)
                })
                .collect()
        };
        save(
            dir,
            &format!("{base}-error-vs-time"),
            (900, 600),
            &ErrorPlot { title: title.into(), x_desc: "GPU seconds".into(), series: series(true) },
        )?;
        save(
            dir,
            &format!("{base}-error-vs-spp"),
            (900, 600),
            &ErrorPlot { title: title.into(), x_desc: "samples per pixel".into(), series: series(false) },
        )
    }

    /// A grid of scalar images on one colour scale.
    pub struct Heatmaps {
        /// Caption.
        pub title: String,
        /// Per panel: label, and a row-major image of `cells.0 × cells.1` values.
        pub panels: Vec<(String, Vec<f64>)>,
        /// Image size of every panel.
        pub cells: (usize, usize),
        /// Value range mapped to the colour map (log10 when `log`).
        pub range: (f64, f64),
        /// Whether the scale is log10.
        pub log: bool,
        /// Colour-bar caption.
        pub legend: String,
    }

    impl Figure for Heatmaps {
        fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<(), String> {
            let err = |e: DrawingAreaErrorKind<DB::ErrorType>| e.to_string();
            root.fill(&WHITE).map_err(err)?;
            let (w, h) = root.dim_in_pixel();
            let titled = root.titled(&self.title, ("sans-serif", 18)).map_err(err)?;
            let (body, bar) = titled.split_vertically(h.saturating_sub(80).max(10));
            let n = self.panels.len().max(1);
            let areas = body.split_evenly((1, n));
            let map = |v: f64| -> RGBColor {
                let x = if self.log { v.max(1e-30).log10() } else { v };
                colormap((x - self.range.0) / (self.range.1 - self.range.0).max(1e-30))
            };
            for (area, (label, img)) in areas.iter().zip(&self.panels) {
                let (aw, ah) = area.dim_in_pixel();
                let side = (aw.min(ah.saturating_sub(24)) as f64).max(1.0);
                let cw = side / self.cells.0.max(self.cells.1) as f64;
                let x0 = (aw as f64 - cw * self.cells.0 as f64) / 2.0;
                area.draw(&Text::new(label.clone(), (x0 as i32, 2), ("sans-serif", 14))).map_err(err)?;
                for y in 0..self.cells.1 {
                    for x in 0..self.cells.0 {
                        let c = map(img[y * self.cells.0 + x]);
                        let (px, py) = (x0 + x as f64 * cw, 22.0 + y as f64 * cw);
                        area.draw(&Rectangle::new(
                            [(px as i32, py as i32), ((px + cw).ceil() as i32, (py + cw).ceil() as i32)],
                            c.filled(),
                        ))
                        .map_err(err)?;
                    }
                }
            }
            // Colour bar.
            let steps = 64;
            let bw = (w as f64 * 0.6) / steps as f64;
            let bx = w as f64 * 0.2;
            for i in 0..steps {
                let t = i as f64 / (steps - 1) as f64;
                bar.draw(&Rectangle::new(
                    [((bx + i as f64 * bw) as i32, 10), ((bx + (i + 1) as f64 * bw).ceil() as i32, 30)],
                    colormap(t).filled(),
                ))
                .map_err(err)?;
            }
            let fmt = |v: f64| if self.log { format!("1e{v:.1}") } else { format!("{v:.3}") };
            bar.draw(&Text::new(fmt(self.range.0), (bx as i32 - 60, 14), ("sans-serif", 13))).map_err(err)?;
            bar.draw(&Text::new(fmt(self.range.1), ((bx + steps as f64 * bw) as i32 + 8, 14), ("sans-serif", 13)))
                .map_err(err)?;
            bar.draw(&Text::new(self.legend.clone(), (bx as i32, 38), ("sans-serif", 13))).map_err(err)?;
            Ok(())
        }
    }

    /// Box-filters a `w`×`h` image down to at most `max` cells per side.
    pub fn downsample(img: &[f64], w: usize, h: usize, max: usize) -> (Vec<f64>, usize, usize) {
        let f = w.max(h).div_ceil(max).max(1);
        let (cw, ch) = (w.div_ceil(f), h.div_ceil(f));
        let mut out = vec![0.0; cw * ch];
        let mut n = vec![0u32; cw * ch];
        for y in 0..h {
            for x in 0..w {
                let k = (y / f) * cw + x / f;
                out[k] += img[y * w + x];
                n[k] += 1;
            }
        }
        out.iter_mut().zip(&n).for_each(|(v, &c)| *v /= c.max(1) as f64);
        (out, cw, ch)
    }

    /// Per-pixel relMSE heatmaps (log scale, shared range), PNG at up to 128 cells per side, SVG at up to 48.
    pub fn heatmaps(
        dir: &Path,
        base: &str,
        title: &str,
        w: u32,
        h: u32,
        maps: &[(String, Vec<f64>)],
    ) -> Result<(), String> {
        if maps.is_empty() {
            return Ok(());
        }
        let name = format!("{base}-heatmaps");
        for (max, svg) in [(128usize, false), (48, true)] {
            let mut panels = vec![];
            let mut cells = (0, 0);
            let mut lo = f64::INFINITY;
            let mut hi = f64::NEG_INFINITY;
            for (label, m) in maps {
                let (d, cw, ch) = downsample(m, w as usize, h as usize, max);
                cells = (cw, ch);
                for &v in &d {
                    if v > 0.0 && v.is_finite() {
                        lo = lo.min(v.log10());
                        hi = hi.max(v.log10());
                    }
                }
                panels.push((label.clone(), d));
            }
            // Clip the colour range to 4 decades below the maximum so a few exact pixels do not flatten the rest.
            let lo = lo.max(hi - 4.0);
            let fig = Heatmaps {
                title: format!("{title}: per-pixel relMSE at the last point, mean over seeds"),
                panels,
                cells,
                range: (lo, hi.max(lo + 1e-6)),
                log: true,
                legend: "per-pixel relMSE (log scale)".into(),
            };
            let size = (260 * maps.len() as u32 + 40, 400);
            if svg {
                save_svg(&dir.join(format!("{name}.svg")), size, &fig)?;
            } else {
                save_png(&dir.join(format!("{name}.png")), size, &fig)?;
            }
        }
        Ok(())
    }
}
