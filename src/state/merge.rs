//! `mislab merge`: combine the state files of `--part K/N` renders into one image and one state (Chan, Golub &
//! LeVeque's parallel update of mean and second moment), refusing missing, duplicate, overlapping, incomplete or
//! foreign parts by name; and `mislab merge --status DIR`: how far a split render is.

use super::{RenderState, StateError, StateHeader};
use crate::gpu::types::GpuAccum;
use crate::render::film::Tonemap;
use std::path::{Path, PathBuf};

/// `mislab merge` flags.
#[derive(clap::Args, Clone, Debug)]
pub struct MergeArgs {
    /// The parts' state files (any order).
    #[arg(required_unless_present = "status", conflicts_with = "status")]
    pub parts: Vec<PathBuf>,
    /// The merged image: .exr (linear, with a reference's header: `mislab bench --ref` reads it) or .png.
    #[arg(short, long, required_unless_present = "status")]
    pub output: Option<PathBuf>,
    /// The merged state file (default: the output's name with extension .state).
    #[arg(long, value_name = "FILE")]
    pub state: Option<PathBuf>,
    /// Report how many samples of the target the state files in DIR hold and which are missing; exit 0 when
    /// complete, 1 when not.
    #[arg(long, value_name = "DIR")]
    pub status: Option<PathBuf>,
    /// Tonemapper for PNG output.
    #[arg(long, value_enum, default_value_t = Tonemap::Clamp)]
    pub tonemap: Tonemap,
    /// Exposure in stops for PNG output.
    #[arg(long, allow_hyphen_values = true, default_value_t = 0.0)]
    pub exposure: f32,
}

/// A part read from a file.
pub struct Part {
    /// Where it came from.
    pub path: PathBuf,
    /// Its contents.
    pub state: RenderState,
}

fn range_text(r: (u32, u32)) -> String {
    format!("{}..{}", r.0, r.1)
}

/// Checks that `parts` are complete parts of one render that together hold each of its sample indices exactly
/// once; returns them sorted by first sample index.
pub fn check_parts(mut parts: Vec<Part>) -> Result<Vec<Part>, StateError> {
    let first = parts.first().ok_or_else(|| StateError::Parts("no state files to merge".into()))?;
    let (name0, h0) = (first.path.display().to_string(), first.state.header.clone());
    for p in &parts[1..] {
        if let Some(d) = p.state.header.differences(&h0) {
            return Err(StateError::Mismatch(format!(
                "{}: a foreign part (not of the render {name0} is of): {d}",
                p.path.display()
            )));
        }
    }
    for (i, a) in parts.iter().enumerate() {
        for b in &parts[i + 1..] {
            let same = match (a.path.canonicalize(), b.path.canonicalize()) {
                (Ok(x), Ok(y)) => x == y,
                _ => a.path == b.path,
            };
            if same {
                return Err(StateError::Mismatch(format!("{}: given twice", a.path.display())));
            }
        }
    }
    for p in &parts {
        let h = &p.state.header;
        if !h.is_complete() {
            return Err(StateError::Mismatch(format!(
                "{}: an incomplete part: it holds samples {} of {} (finish it with `mislab render … --resume {}`)",
                p.path.display(),
                range_text((h.range.0, h.next)),
                range_text(h.range),
                p.path.display()
            )));
        }
    }
    parts.sort_by_key(|p| p.state.header.range);
    let mut missing = Vec::new();
    let mut covered = 0u32;
    for (i, p) in parts.iter().enumerate() {
        let r = p.state.header.range;
        if r.0 < covered {
            let prev = &parts[i - 1];
            let pr = prev.state.header.range;
            let what = if pr == r { "duplicate parts" } else { "overlapping parts" };
            return Err(StateError::Mismatch(format!(
                "{what}: {} (samples {}) and {} (samples {})",
                prev.path.display(),
                range_text(pr),
                p.path.display(),
                range_text(r)
            )));
        }
        if r.0 > covered {
            missing.push((covered, r.0));
        }
        covered = r.1;
    }
    if covered < h0.spp_total {
        missing.push((covered, h0.spp_total));
    }
    if !missing.is_empty() {
        return Err(StateError::Mismatch(format!(
            "missing parts: samples {} of the {} are in none of the files{}",
            missing.iter().map(|&r| range_text(r)).collect::<Vec<_>>().join(", "),
            h0.spp_total,
            missing_part_names(&missing, h0.part.map(|p| p.1), h0.spp_total)
        )));
    }
    Ok(parts)
}

/// " (part 2/4 …)" for missing ranges that are whole parts of an N-part split.
fn missing_part_names(missing: &[(u32, u32)], n: Option<u32>, total: u32) -> String {
    let Some(n) = n else { return String::new() };
    let names: Vec<String> = (0..n)
        .filter(|&k| {
            let r = super::session::part_range(k, n, total);
            missing.iter().any(|m| m.0 <= r.0 && r.1 <= m.1 && r.0 < r.1)
        })
        .map(|k| format!("{k}/{n}"))
        .collect();
    if names.is_empty() {
        String::new()
    } else {
        format!(" (--part {})", names.join(", "))
    }
}

/// Merges per-pixel accumulators (Chan et al.): n = na + nb, δ = mean_b − mean_a, mean = mean_a + δ·nb/n,
/// M2 = M2_a + M2_b + δ²·na·nb/n; in f64, rounded to f32 once at the end. Parts in a fixed order (by sample
/// range, `check_parts`) so the result does not depend on the order the files were named in.
pub fn merge_accum(parts: &[&[GpuAccum]]) -> Vec<GpuAccum> {
    let pixels = parts.first().map_or(0, |p| p.len());
    (0..pixels)
        .map(|i| {
            let (mut n, mut mean, mut m2, mut bad) = (0u64, [0f64; 3], [0f64; 3], 0u32);
            for p in parts {
                let a = &p[i];
                bad += a.nonfinite;
                let nb = a.count as u64;
                if nb == 0 {
                    continue;
                }
                let total = n + nb;
                for c in 0..3 {
                    let delta = a.mean[c] as f64 - mean[c];
                    mean[c] += delta * nb as f64 / total as f64;
                    m2[c] += a.m2[c] as f64 + delta * delta * n as f64 * nb as f64 / total as f64;
                }
                n = total;
            }
            GpuAccum { mean: mean.map(|v| v as f32), count: n as u32, m2: m2.map(|v| v as f32), nonfinite: bad }
        })
        .collect()
}

/// Merges checked parts into the state of the whole render.
pub fn merge(parts: &[Part]) -> RenderState {
    let h0 = &parts[0].state.header;
    let accum = merge_accum(&parts.iter().map(|p| p.state.accum.as_slice()).collect::<Vec<_>>());
    let header = StateHeader {
        part: None,
        range: (0, h0.spp_total),
        next: h0.spp_total,
        nonfinite_total: parts.iter().map(|p| p.state.header.nonfinite_total).sum(),
        rays_total: parts.iter().map(|p| p.state.header.rays_total).sum(),
        seconds: parts.iter().map(|p| p.state.header.seconds).sum(),
        ..h0.clone()
    };
    RenderState { header, accum }
}

/// The header attributes of a merged EXR: those of a `mislab reference` EXR, plus the scene hash and parts.
pub fn exr_attributes(h: &StateHeader, parts: usize) -> Vec<(String, String)> {
    vec![
        ("spp".into(), h.done().to_string()),
        ("renderSeconds".into(), format!("{:.3}", h.seconds)),
        ("nonfiniteSamples".into(), h.nonfinite_total.to_string()),
        ("scene".into(), h.scene.clone()),
        ("sceneHash".into(), h.scene_hash.clone()),
        ("mergedParts".into(), parts.to_string()),
        ("mislabSettings".into(), serde_json::to_string(&h.settings).unwrap_or_default()),
        ("mislabVersion".into(), env!("CARGO_PKG_VERSION").to_string()),
    ]
}

/// Runs `mislab merge`; returns the exit code.
pub fn run(args: &MergeArgs) -> Result<u8, StateError> {
    if let Some(dir) = &args.status {
        return status(dir);
    }
    let output = args.output.clone().ok_or_else(|| StateError::Flags("give -o OUT.exr (or .png)".into()))?;
    let ext = output.extension().and_then(|e| e.to_str()).map(|e| e.to_ascii_lowercase()).unwrap_or_default();
    if ext != "exr" && ext != "png" {
        return Err(StateError::Flags(format!("{}: unknown output format (use .exr or .png)", output.display())));
    }
    let parts = args
        .parts
        .iter()
        .map(|p| RenderState::read(p).map(|state| Part { path: p.clone(), state }))
        .collect::<Result<Vec<_>, _>>()?;
    let parts = check_parts(parts)?;
    let merged = merge(&parts);
    let state_path = args.state.clone().unwrap_or_else(|| output.with_extension("state"));
    merged.write(&state_path)?;
    let film = merged.film();
    if ext == "exr" {
        crate::io::exr_image::write(&output, film.pixels(), &exr_attributes(&merged.header, parts.len()))?;
    } else {
        film.save(&output, args.exposure, args.tonemap)?;
    }
    eprintln!(
        "merged {} parts ({} spp, {} NaN/Inf samples): wrote {} and {}",
        parts.len(),
        merged.header.spp_total,
        merged.header.nonfinite_total,
        output.display(),
        state_path.display()
    );
    Ok(0)
}

/// Samples per pixel a state holds at its least and most complete pixel (finite + NaN/Inf).
fn pixel_counts(s: &RenderState) -> (u32, u32) {
    let counts = s.accum.iter().map(|a| a.count + a.nonfinite);
    (counts.clone().min().unwrap_or(0), counts.max().unwrap_or(0))
}

/// `mislab merge --status DIR`: per render found in DIR, the samples done of the target, each file's sample range,
/// and the ranges no file holds.
pub fn status(dir: &Path) -> Result<u8, StateError> {
    let entries = std::fs::read_dir(dir).map_err(|e| StateError::Parts(format!("{}: {e}", dir.display())))?;
    let mut files: Vec<PathBuf> = entries
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|e| e == "state"))
        .collect();
    files.sort();
    if files.is_empty() {
        return Err(StateError::Parts(format!("{}: no .state files", dir.display())));
    }
    // Group by render (scene, settings, total).
    let mut groups: Vec<(StateHeader, Vec<Part>)> = Vec::new();
    let mut unreadable = Vec::new();
    for path in files {
        match RenderState::read(&path) {
            Ok(state) => match groups.iter_mut().find(|(h, _)| h.differences(&state.header).is_none()) {
                Some((_, g)) => g.push(Part { path, state }),
                None => groups.push((state.header.clone(), vec![Part { path, state }])),
            },
            Err(e) => unreadable.push(e),
        }
    }
    let mut complete = unreadable.is_empty();
    for (h, parts) in &mut groups {
        parts.sort_by_key(|p| (p.state.header.range.0, p.state.header.next));
        println!(
            "render of {} (scene hash {}, {}x{}, seed {}), target {} spp:",
            h.scene, h.scene_hash, h.settings.width, h.settings.height, h.seed, h.spp_total
        );
        let mut covered = vec![false; h.spp_total as usize];
        for p in parts.iter() {
            let s = &p.state.header;
            let (lo, hi) = pixel_counts(&p.state);
            println!(
                "  {}: part {}, samples {} of {}: {} done{}, per pixel {lo}..{hi} samples",
                p.path.display(),
                s.part.map_or("whole".to_string(), |(k, n)| format!("{k}/{n}")),
                range_text((s.range.0, s.next)),
                range_text(s.range),
                s.done(),
                if s.is_complete() { " (complete)" } else { " (incomplete)" }
            );
            for c in &mut covered[s.range.0 as usize..s.next as usize] {
                *c = true;
            }
        }
        let done = covered.iter().filter(|&&c| c).count();
        let mut missing = Vec::new();
        let mut i = 0;
        while i < covered.len() {
            if !covered[i] {
                let j = (i..covered.len()).find(|&j| covered[j]).unwrap_or(covered.len());
                missing.push((i as u32, j as u32));
                i = j;
            } else {
                i += 1;
            }
        }
        println!(
            "  {done} of {} samples per pixel done ({:.1} %)",
            h.spp_total,
            100.0 * done as f64 / h.spp_total.max(1) as f64
        );
        if missing.is_empty() {
            println!("  nothing missing: `mislab merge` can combine these files");
        } else {
            complete = false;
            println!(
                "  missing samples: {}{}",
                missing.iter().map(|&r| range_text(r)).collect::<Vec<_>>().join(", "),
                missing_part_names(&missing, h.part.map(|p| p.1), h.spp_total)
            );
        }
    }
    for e in &unreadable {
        println!("unreadable: {e}");
    }
    if groups.len() > 1 {
        println!("note: {} different renders in {}", groups.len(), dir.display());
    }
    Ok(if complete { 0 } else { 1 })
}
