//! `mislab bench`: time against error. Each configuration (settings from comma-list flags, a TOML file, or the
//! lecture suite) renders an spp ladder (or until a time budget) for several seeds; every point records GPU time
//! (timestamp queries), wall time, RMSE, relMSE, MAE and efficiency against a reference. Pipeline compilation and
//! warm-up are timed separately and left out. `--out DIR` receives results.csv, results.json, summary.md and plots
//! (error vs seconds, error vs spp, per-pixel relMSE heatmaps; PNG and SVG).
//!
//! lavapipe stops an invocation's loops after 65535 iterations in all (BVH traversal included) and the render
//! kernel loops over the samples of a dispatch, so a dispatch of many samples per pixel silently accumulates
//! fewer. Rendering here splits the samples into small dispatches and checks every pixel's count at every point.

mod args;
mod group;
mod output;
pub mod plot;
mod results;
mod runner;
mod suite;
mod ticks;

use crate::lab::LabError;
pub use args::BenchArgs;
pub use group::{BenchFile, BenchGroup};
use output::write_outputs;
use results::summarize;
pub use results::{to_csv, BenchRow, ConfigSummary, CSV_COLUMNS};
pub use runner::run_configurations;
use runner::{run_group, slug, GroupResult};
pub use suite::lecture_suite;

use crate::gpu::timer::GpuTimer;
use crate::gpu::GpuContext;
use crate::lab::reference;
use crate::lab::suite_inputs::{self, SuiteInputs};
use crate::render::samplers;
use crate::render::settings::*;
use crate::render::{gpu_scene::GpuScene, scene_data::SceneData};
use crate::render::{Renderer, Timing};
use crate::scene::SceneSpec;
use crate::testkit::metrics::{self, ErrorMetrics};
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
    /// samplers (on veach-mis, area-vs-cosine, a sphere and metal-rough spheres under noon_grass_1k.hdr, cornell-box).
    Lecture,
}

/// Runs `mislab bench`.
pub fn run(args: &BenchArgs) -> Result<(), LabError> {
    let groups = args.groups()?;
    let ctx = GpuContext::new().map_err(LabError::from)?;
    eprintln!(
        "adapter: {} ({:?}); GPU time from {}",
        ctx.info.name,
        ctx.info.device_type,
        if ctx.timestamps { "timestamp queries" } else { "wall clock (no TIMESTAMP_QUERY)" }
    );
    std::fs::create_dir_all(&args.out).map_err(|e| LabError::Input(format!("{}: {e}", args.out.display())))?;
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
