//! Writing a run's results: results.csv, results.json, summary.md and the plots.

use super::*;
use crate::lab::LabError;

pub(super) fn write_outputs(out: &Path, ctx: &GpuContext, results: &[GroupResult]) -> Result<(), LabError> {
    let rows: Vec<BenchRow> = results.iter().flat_map(|r| r.rows.clone()).collect();
    let write = |name: &str, text: &str| -> Result<(), LabError> {
        let p = out.join(name);
        std::fs::write(&p, text).map_err(|e| LabError::Input(format!("{}: {e}", p.display())))
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
        "groups": results.iter().zip(&summaries).map(|(r, (_, s))| serde_json::json!({ "group": group_json(r), "reference": r.reference, "reference_spp": r.reference_spp, "summary": s })).collect::<Vec<_>>(),
        "rows": rows,
    });
    write("results.json", &serde_json::to_string_pretty(&json).map_err(LabError::from)?)?;
    let mut md = format!("# Benchmark results\n\nDevice: {} ({:?}). Times are GPU time from timestamp queries; pipeline compilation and warm-up are excluded (listed separately). relMSE = mean over pixels and channels of (x − r)² / (r² + 0.01); efficiency = 1 / (relMSE · seconds).\n", ctx.info.name, ctx.info.device_type);
    for (res, (name, sums)) in results.iter().zip(&summaries) {
        let base = slug(name);
        plot::error_plots(out, &base, name, sums)?;
        plot::heatmaps(out, &base, name, res.group.width, res.group.height, &res.heatmaps)?;
        md += &format!(
            "\n## {name}\n\n{} at {}x{}, {} seed(s), reference {} ({}).\n\n| configuration | spp | relMSE (mean over seeds) | GPU s | efficiency (of the means) | RMSE slope | M samples/s | Mrays/s | s to relMSE 1e-2 | s to 1e-3 | compile + warm-up s | NaN/Inf samples |\n|---|---|---|---|---|---|---|---|---|---|---|---|\n",
            res.group.scene,
            res.group.width,
            res.group.height,
            res.group.seeds,
            res.reference,
            res.reference_spp.map_or("its header records no spp".into(), |n| format!("{n} spp"))
        );
        for s in sums {
            let i = s.spp.len().saturating_sub(1);
            let opt = |v: Option<f64>| v.map(|x| format!("{x:.3}")).unwrap_or_else(|| "—".into());
            md += &format!(
                "| {} | {} | {:.3e} | {:.3} | {:.3e} | {} | {:.2} | {:.2} | {} | {} | {:.2} | {} |\n",
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
                s.compile_seconds,
                s.nonfinite
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

/// A group as JSON, with `reference_spp` the reference's real sample count (from its header; null when it
/// records none) rather than the asked-for one, which a given `--ref` file does not follow.
fn group_json(r: &GroupResult) -> serde_json::Value {
    let mut v = serde_json::to_value(&r.group).unwrap_or_default();
    v["reference_spp"] = serde_json::json!(r.reference_spp);
    v
}
