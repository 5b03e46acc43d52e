//! The numerical stress suite: scenes at extreme scales, offsets, angles, sizes and radiances, degenerate
//! geometry, broken environment maps and extreme sample statistics. Every case asserts zero NaN/Inf samples
//! (the device counter) and, where an answer is known, the right mean: an analytic value, or the same image
//! as the case's unstressed twin. `mislab stress` prints the table; `tests/stress.rs` asserts every row.

mod cases;

pub use cases::{cases, polygon_irradiance};

use crate::gpu::GpuContext;
use crate::lab::LabError;
use crate::render::film::Film;
use crate::render::settings::Settings;
use crate::render::Renderer;
use crate::render::{gpu_scene::GpuScene, scene_data::SceneData};
use crate::scene::Scene;
use std::collections::HashMap;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::mpsc;
use std::time::Instant;

/// What a case must show besides zero NaN/Inf samples.
#[derive(Clone, Debug)]
pub enum Check {
    /// Only finiteness (no closed form; the point is that nothing breaks).
    Finite,
    /// Image mean (all pixels and channels) equal to `expected` within `rel_tol` relative plus 5 standard errors.
    Mean { expected: f64, rel_tol: f64 },
    /// A z-test: the image mean equal to its exact expectation (the mean over the pixels' footprints) within 5
    /// standard errors, plus `floor` relative for f32 arithmetic (`F32_FLOOR` unless a case says why it needs
    /// more) — no percent-level tolerance that could hide a bias.
    Exact { expected: f64, floor: f64 },
    /// Image mean equal to that of the case named `twin` (run earlier) within `rel_tol` plus 5 standard errors.
    SameAs { twin: String, rel_tol: f64 },
    /// Every pixel exactly 0.
    Black,
    /// Every pixel's mean equal to `value` within `rel_tol`, and every pixel holding exactly `spp` samples.
    ExactEverywhere { value: f64, rel_tol: f64 },
}

/// One stress configuration.
#[derive(Clone)]
pub struct Case {
    /// What is stressed (a table section).
    pub group: &'static str,
    /// Unique name.
    pub name: String,
    /// The scene, built in code.
    pub scene: Scene,
    /// Estimator settings (film size included).
    pub settings: Settings,
    /// Samples per pixel.
    pub spp: u32,
    /// Samples per pixel per dispatch, for trivial scenes whose sample loops are short (see `Renderer::dispatch_spp`).
    pub dispatch_spp: Option<u32>,
    /// What must hold.
    pub check: Check,
}

/// What a case measured.
#[derive(Clone, Debug)]
pub struct Outcome {
    /// `Case::group`.
    pub group: &'static str,
    /// `Case::name`.
    pub name: String,
    /// Non-finite samples counted on the device.
    pub nonfinite: u64,
    /// Image mean (pixels and channels).
    pub mean: f64,
    /// Standard error of `mean`.
    pub std_error: f64,
    /// The expected mean, where there is one.
    pub expected: Option<f64>,
    /// Whether every assertion held.
    pub pass: bool,
    /// Why not, or what was checked.
    pub detail: String,
    /// Render seconds (pipeline compilation excluded; cases render side by side, so this is not a benchmark).
    pub seconds: f64,
}

/// Renders every case (on one thread per core; cases with equal pipelines share one build) and checks it. `filter` keeps the cases whose
/// name contains it (twins are always run). `progress` is called after each case.
pub fn run(
    ctx: &GpuContext,
    filter: Option<&str>,
    mut progress: impl FnMut(&Outcome),
) -> Result<Vec<Outcome>, LabError> {
    let all = cases()?;
    let wanted: Vec<&Case> = all
        .iter()
        .filter(|c| {
            filter.is_none_or(|f| {
                c.name.contains(f)
                    || c.group.contains(f)
                    || all.iter().any(|o| {
                        o.name.contains(f) && matches!(&o.check, Check::SameAs { twin, .. } if *twin == c.name)
                    })
            })
        })
        .collect();
    // Nearly all of the suite's time is the driver compiling each case's pipeline (a baked scene is its own
    // shader; lavapipe compiles on one thread), so cases render on one worker per core. They are judged in
    // list order, as their results arrive, because a `SameAs` case compares with its twin's mean.
    let next = AtomicUsize::new(0);
    let workers = std::thread::available_parallelism().map_or(1, |n| n.get()).min(wanted.len().max(1));
    let (tx, rx) = mpsc::channel::<(usize, Result<Rendered, LabError>)>();
    std::thread::scope(|scope| {
        for _ in 0..workers {
            let tx = tx.clone();
            let (wanted, next) = (&wanted, &next);
            scope.spawn(move || loop {
                let i = next.fetch_add(1, Ordering::Relaxed);
                let Some(c) = wanted.get(i) else { break };
                let r = render_case(ctx, c);
                let failed = r.is_err();
                if tx.send((i, r)).is_err() || failed {
                    // The lead thread stopped listening (it reports the first error), or this worker's case failed:
                    // no more cases from this worker; `next` past the end stops the others soon.
                    next.fetch_add(wanted.len(), Ordering::Relaxed);
                    break;
                }
            });
        }
        drop(tx);
        let mut means: HashMap<String, (f64, f64)> = HashMap::new();
        let mut arrived: Vec<Option<Rendered>> = (0..wanted.len()).map(|_| None).collect();
        let mut outcomes = Vec::new();
        for (i, r) in rx.iter() {
            arrived[i] = Some(r?);
            while let Some(r) = arrived.get_mut(outcomes.len()).and_then(Option::take) {
                let c = wanted[outcomes.len()];
                let o = judge(c, &r.film, r.nonfinite, r.seconds, &means);
                means.insert(c.name.clone(), (o.mean, o.std_error));
                progress(&o);
                outcomes.push(o);
            }
        }
        if outcomes.len() < wanted.len() {
            return Err(LabError::Input(format!(
                "the stress suite stopped after {} of {} cases",
                outcomes.len(),
                wanted.len()
            )));
        }
        Ok(outcomes)
    })
}

/// A case's rendered film, its device NaN/Inf count and its render time.
struct Rendered {
    film: Film,
    nonfinite: u64,
    seconds: f64,
}

fn render_case(ctx: &GpuContext, c: &Case) -> Result<Rendered, LabError> {
    let data = SceneData::build(&c.scene);
    let gs = GpuScene::upload(ctx, data).map_err(|e| LabError::Input(format!("{}: {e}", c.name)))?;
    let mut r = Renderer::new_unprepared(ctx, &gs, c.scene.camera.clone(), c.settings.clone())?;
    // Cases with equal pipelines share one build (the device's `GpuContext::pipelines`).
    r.prepare()?;
    r.warm_up(ctx).map_err(LabError::from)?;
    r.set_dispatch_spp(c.dispatch_spp);
    let t = Instant::now();
    r.render(ctx, c.spp).map_err(|e| LabError::Input(format!("{}: {e}", c.name)))?;
    let seconds = t.elapsed().as_secs_f64();
    let film = r.film(ctx).map_err(|e| LabError::Input(format!("{}: {e}", c.name)))?;
    Ok(Rendered { film, nonfinite: r.nonfinite_total(), seconds })
}

/// Image mean and its standard error (from the per-pixel sample variances).
fn mean_and_error(film: &Film) -> (f64, f64) {
    let n = film.mean.len() as f64 * 3.0;
    let var: f64 = (0..film.mean.len()).filter_map(|i| film.variance_of_mean(i)).map(|v| v.iter().sum::<f64>()).sum();
    (film.mean_value(), var.sqrt() / n)
}

fn judge(c: &Case, film: &Film, nonfinite: u64, seconds: f64, means: &HashMap<String, (f64, f64)>) -> Outcome {
    let (mean, se) = mean_and_error(film);
    let mut o = Outcome {
        group: c.group,
        name: c.name.clone(),
        nonfinite,
        mean,
        std_error: se,
        expected: None,
        pass: true,
        detail: String::new(),
        seconds,
    };
    let fail = |o: &mut Outcome, why: String| {
        o.pass = false;
        if !o.detail.is_empty() {
            o.detail.push_str("; ");
        }
        o.detail.push_str(&why);
    };
    if nonfinite != 0 {
        fail(&mut o, format!("{nonfinite} NaN/Inf samples"));
    }
    if !mean.is_finite() || film.mean.iter().flatten().any(|v| !v.is_finite()) {
        fail(&mut o, "a non-finite pixel mean".into());
    }
    let missing = film.count.iter().zip(&film.nonfinite).filter(|(&n, &b)| n + b != c.spp).count();
    if missing > 0 {
        let (lo, hi) = film
            .count
            .iter()
            .zip(&film.nonfinite)
            .map(|(&n, &b)| n + b)
            .fold((u32::MAX, 0), |(lo, hi), n| (lo.min(n), hi.max(n)));
        fail(
            &mut o,
            format!("{missing} pixels hold other than {} samples ({lo} … {hi}; a driver cut a loop short?)", c.spp),
        );
    }
    let compare = |o: &mut Outcome, expected: f64, tol: f64, extra_se: f64| {
        o.expected = Some(expected);
        let allowed = tol * expected.abs() + 5.0 * (se * se + extra_se * extra_se).sqrt();
        let dev = mean - expected;
        if !(dev.abs() <= allowed) {
            fail(
                o,
                format!(
                    "mean {mean:.6e} differs from {expected:.6e} by {:.2e} relative (allowed {:.2e})",
                    dev / expected,
                    allowed / expected.abs()
                ),
            );
        } else if o.detail.is_empty() {
            o.detail = format!("within {:.1e} relative", (dev / expected).abs());
        }
    };
    match &c.check {
        Check::Finite => {
            if o.detail.is_empty() {
                o.detail = "finite".into();
            }
        }
        Check::Mean { expected, rel_tol } => compare(&mut o, *expected, *rel_tol, 0.0),
        Check::Exact { expected, floor } => {
            compare(&mut o, *expected, *floor, 0.0);
            // Deterministic samples (a directional light on Lambert) have no variance: no z to report.
            if se > 0.0 {
                o.detail = format!("{}, z = {:.1}", o.detail, (mean - expected) / se);
            } else {
                o.detail = format!("{}, no sample variance", o.detail);
            }
        }
        Check::SameAs { twin, rel_tol } => match means.get(twin) {
            Some(&(m, s)) => compare(&mut o, m, *rel_tol, s),
            None => fail(&mut o, format!("its twin '{twin}' did not run")),
        },
        Check::Black => {
            o.expected = Some(0.0);
            if film.mean.iter().flatten().any(|&v| v != 0.0) {
                fail(&mut o, format!("not black: mean {mean:e}"));
            } else if o.detail.is_empty() {
                o.detail = "every pixel exactly 0".into();
            }
        }
        Check::ExactEverywhere { value, rel_tol } => {
            o.expected = Some(*value);
            let worst = film.mean.iter().flatten().map(|&v| ((v as f64 - value) / value).abs()).fold(0.0, f64::max);
            if !(worst <= *rel_tol) {
                fail(&mut o, format!("a pixel mean is off by {worst:.2e} relative (allowed {rel_tol:e})"));
            } else if o.detail.is_empty() {
                o.detail = format!("every pixel within {worst:.1e} relative after {} samples", c.spp);
            }
        }
    }
    o
}

/// Relative allowance of `Check::Exact` for f32 rendering (a few hundred ulps through camera, BSDF and light
/// arithmetic); where the samples barely vary (a tiny light's cone) the standard error alone would be below it.
pub const F32_FLOOR: f64 = 2e-5;

/// One line per outcome, as `mislab stress` and the test print them while the suite runs.
pub fn progress_line(o: &Outcome) -> String {
    format!(
        "{} {:<12} {:<50} NaN/Inf {:>3}  {}",
        if o.pass { "pass" } else { "FAIL" },
        o.group,
        o.name,
        o.nonfinite,
        o.detail
    )
}

/// The outcomes as a Markdown table.
pub fn table(outcomes: &[Outcome]) -> String {
    let mut s = String::from(
        "| group | case | NaN/Inf | mean | expected | s.e. | render s | result |\n|---|---|---|---|---|---|---|---|\n",
    );
    for o in outcomes {
        s.push_str(&format!(
            "| {} | {} | {} | {:.5e} | {} | {:.1e} | {:.2} | {} {} |\n",
            o.group,
            o.name,
            o.nonfinite,
            o.mean,
            o.expected.map(|e| format!("{e:.5e}")).unwrap_or_else(|| "—".into()),
            o.std_error,
            o.seconds,
            if o.pass { "pass" } else { "FAIL" },
            o.detail
        ));
    }
    s
}
