//! Results: one CSV/JSON row per configuration, spp and seed, and the per-configuration summaries.

use super::*;

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
    /// NaN/Inf samples in this seed's image at this spp (counted on the device; they are left out of the mean).
    pub nonfinite: u64,
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
    "nonfinite_samples",
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
            r.nonfinite.to_string(),
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
    /// NaN/Inf samples at the last point, summed over seeds.
    pub nonfinite: u64,
}

pub(super) fn summarize(rows: &[&BenchRow]) -> ConfigSummary {
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
        nonfinite: by_spp.values().last().map_or(0, |rs| rs.iter().map(|r| r.nonfinite).sum()),
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
