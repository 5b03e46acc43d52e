//! Real-scene speed (issue 13): the bench scenes of ../shared/bench-scenes (BVH path), path tracing at depth 8 with
//! MIS and the power heuristic, independent samples. Prints samples/s, Mrays/s and the estimated seconds to reach a
//! relMSE (MISLAB_BENCH_RELMSE, default 1e-2). `cargo bench --bench real_scenes`; MISLAB_BENCH_SECONDS per scene
//! (default 8), MISLAB_BENCH_SIZE (film height, default 256; width from the scene's aspect), MISLAB_BENCH_SCENES
//! (comma-separated stems), MISLAB_BENCH_EXTRA (more .toml paths, e.g. a generated scaling_1m).
//!
//! Seconds to a relMSE are estimated from the film's own per-pixel variance of the mean (Welford m2 / n): with
//! independent samples the expected relMSE against the converged image is Σ var/(mean² + 0.01) / pixels, and it
//! falls as 1/spp, so t(target) = t · relMSE(t) / target. No reference image is needed; the estimate leaves out
//! bias, which the path tracer has none of at depth 8 beyond the depth cut-off both sides share.

#[allow(dead_code)] // the shared helpers this bench does not use (built-in scenes, the HDR-lit helmet)
mod common;

use mislab::render::settings::{Heuristic, Mode, Settings, Strategy};
use mislab::render::Renderer;
use mislab::render::{gpu_scene::GpuScene, scene_data::SceneData};
use mislab::scene::{self, LoadOptions};

const SCENES: [(&str, f64); 7] = [
    ("damagedhelmet_grey", 1.0),
    ("scaling_1k", 1.0),
    ("scaling_10k", 1.0),
    ("scaling_100k", 1.0),
    ("staircase2_grey", 1.0),
    ("livingroom_grey", 16.0 / 9.0),
    ("diningroom_grey", 16.0 / 9.0),
];

fn main() {
    let seconds: f64 = common::env_or("MISLAB_BENCH_SECONDS", 8.0);
    let height: u32 = common::env_or("MISLAB_BENCH_SIZE", 256);
    let target: f64 = common::env_or("MISLAB_BENCH_RELMSE", 1e-2);
    let only: String = common::env_or("MISLAB_BENCH_SCENES", String::new());
    let extra: String = common::env_or("MISLAB_BENCH_EXTRA", String::new());
    let ctx = common::gpu();
    println!("device: {} ({:?}); {seconds} s per scene, height {height}", ctx.info.name, ctx.info.device_type);
    let dir = concat!(env!("CARGO_MANIFEST_DIR"), "/../shared/bench-scenes");
    let mut cases: Vec<(String, String, f64)> = SCENES
        .iter()
        .filter(|(stem, _)| only.is_empty() || only.split(',').any(|s| s == *stem))
        .map(|(stem, aspect)| (stem.to_string(), format!("{dir}/{stem}/{stem}.toml"), *aspect))
        .collect();
    for p in extra.split(',').filter(|p| !p.is_empty()) {
        let stem = std::path::Path::new(p).file_stem().map_or(p.into(), |s| s.to_string_lossy().into_owned());
        cases.push((stem, p.to_string(), 1.0));
    }
    println!(
        "{:<20} {:>10} {:>9} {:>8} {:>6} {:>9} {:>9} {:>10} {:>12}",
        "scene", "tris", "size", "B/tri", "spp", "Msamp/s", "Mrays/s", "relMSE", "s to target"
    );
    for (stem, path, aspect) in cases {
        let s = scene::load(&path, &LoadOptions::default()).unwrap_or_else(|e| panic!("{path}: {e}"));
        let data = SceneData::build(&s);
        let bpt = data.bvh_bytes() as f64 / s.triangle_count().max(1) as f64;
        let gs = GpuScene::upload(&ctx, data).expect("upload");
        let width = (height as f64 * aspect).round() as u32;
        let settings = Settings {
            mode: Mode::Path,
            max_depth: 8,
            strategy: Strategy::Mis,
            heuristic: Heuristic::Power,
            width,
            height,
            ..Settings::default()
        };
        let mut r = Renderer::new(&ctx, &gs, s.camera.clone(), settings).expect("renderer");
        let stats = common::render_for(&ctx, &mut r, seconds);
        let film = r.film(&ctx).expect("film");
        // Needs ≥ 2 samples per pixel (a variance); NaN otherwise, printed as such.
        let mut rel = if stats.spp >= 2 { 0.0f64 } else { f64::NAN };
        for (i, m) in film.mean.iter().enumerate() {
            if let Some(v) = film.variance_of_mean(i) {
                rel += (0..3).map(|c| v[c] / ((m[c] as f64).powi(2) + 0.01)).sum::<f64>() / 3.0;
            }
        }
        rel /= film.mean.len() as f64;
        let samples = stats.spp as f64 * width as f64 * height as f64;
        println!(
            "{:<20} {:>10} {:>9} {:>8.0} {:>6} {:>9.3} {:>9.3} {:>10.2e} {:>12.2}",
            stem,
            s.triangle_count(),
            format!("{width}x{height}"),
            bpt,
            stats.spp,
            samples / stats.seconds / 1e6,
            stats.rays as f64 / stats.seconds / 1e6,
            rel,
            stats.seconds * rel / target
        );
    }
}
