//! Specialised against generic pipelines: samples/s of the same render with the pipeline compiled for the
//! scene's features and settings (WGSL override constants) and with the generic one that branches on
//! everything at run time. Rounds alternate between the two so that machine load hits both alike; the
//! ratio is of the summed samples over the summed seconds. `cargo bench --bench specialization`
//! (MISLAB_BENCH_SECONDS per round, default 4; MISLAB_BENCH_ROUNDS, default 3; MISLAB_BENCH_SIZE, default 512).

mod common;

use common::env_or;
use mislab::render::features::Features;
use mislab::render::settings::{Mode, Settings};
use mislab::render::Renderer;
use mislab::render::{gpu_scene::GpuScene, scene_data::SceneData};
use std::time::Instant;

fn main() {
    let seconds: f64 = env_or("MISLAB_BENCH_SECONDS", 4.0);
    let rounds: u32 = env_or("MISLAB_BENCH_ROUNDS", 3);
    let size: u32 = env_or("MISLAB_BENCH_SIZE", 512);
    let ctx = common::gpu();
    println!(
        "device: {} ({:?}); {size}x{size}, {rounds} rounds of {seconds} s per pipeline, alternating",
        ctx.info.name, ctx.info.device_type
    );
    let cases = [
        ("cornell-box", Mode::Path),
        ("furnace", Mode::Path),
        ("veach-mis", Mode::Direct),
        (common::HELMET, Mode::Path),
    ];
    println!(
        "{:<28} {:>6} {:>10} {:>12} {:>7} {:>14}  features",
        "scene", "mode", "spec Ms/s", "generic Ms/s", "ratio", "compile s s/g"
    );
    let mut generic: Option<wgpu::ComputePipeline> = None;
    for (label, mode) in cases {
        let s = common::load(label);
        let data = SceneData::build(&s);
        let features = Features::of(&data).describe();
        let gs = GpuScene::upload(&ctx, data).expect("upload");
        let settings = Settings { mode, width: size, height: size, ..Settings::default() };
        let t = Instant::now();
        let mut r = Renderer::new(&ctx, &gs, s.camera.clone(), settings).expect("renderer");
        let spec_compile = t.elapsed().as_secs_f64();
        let key = mislab::render::features::PipelineKey::generic();
        if let Some(p) = &generic {
            r.insert_pipeline(key, p.clone());
        }
        let t = Instant::now();
        r.set_specialize(false).expect("generic pipeline");
        r.warm_up(&ctx).expect("warm-up");
        let generic_compile = t.elapsed().as_secs_f64();
        generic = r.pipeline(&key).cloned();
        let mut totals = [(0.0f64, 0.0f64); 2]; // (samples, seconds) for specialised, generic
        for _ in 0..rounds {
            for (k, spec) in [true, false].into_iter().enumerate() {
                r.set_specialize(spec).expect("pipeline");
                r.reset();
                let stats = common::render_for(&ctx, &mut r, seconds);
                totals[k].0 += stats.spp as f64 * (size * size) as f64;
                totals[k].1 += stats.seconds;
            }
        }
        let rate = |k: usize| totals[k].0 / totals[k].1 / 1e6;
        println!(
            "{:<28} {:>6} {:>10.3} {:>12.3} {:>6.2}x {:>6.1}/{:<7.1}  {features}",
            label,
            format!("{mode:?}").to_lowercase(),
            rate(0),
            rate(1),
            rate(0) / rate(1),
            spec_compile,
            generic_compile
        );
    }
}
