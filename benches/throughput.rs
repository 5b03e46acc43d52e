//! Throughput: samples/s and Mrays/s per scene at 512×512 (specialised pipelines), BVH build time and
//! bytes per triangle. `cargo bench --bench throughput` (set MISLAB_BENCH_SECONDS to change the time per
//! configuration; default 10 s). Speed is measured here, never in tests.

mod common;

use mislab::render::settings::{Mode, Settings};
use mislab::render::Renderer;
use mislab::render::{gpu_scene::GpuScene, scene_data::SceneData};

fn main() {
    let seconds: f64 = common::env_or("MISLAB_BENCH_SECONDS", 10.0);
    let ctx = common::gpu();
    println!("device: {} ({:?}); {seconds} s per configuration, 512x512", ctx.info.name, ctx.info.device_type);
    let cases = [
        ("veach-mis", Mode::Direct),
        ("veach-mis", Mode::Path),
        ("cornell-box", Mode::Direct),
        ("cornell-box", Mode::Path),
        ("furnace", Mode::Path),
        ("area-vs-cosine", Mode::Direct),
        (common::HELMET, Mode::Path),
    ];
    println!(
        "{:<28} {:>6} {:>10} {:>10} {:>8} {:>10} {:>9} {:>9}",
        "scene", "mode", "tris", "BVH ms", "B/tri", "spp", "Msamp/s", "Mrays/s"
    );
    for (label, mode) in cases {
        let s = common::load(label);
        let data = SceneData::build(&s);
        let (bvh_ms, bpt) = (data.bvh_seconds * 1e3, data.bvh_bytes() as f64 / s.triangle_count().max(1) as f64);
        let gs = GpuScene::upload(&ctx, data).expect("upload");
        let settings = Settings { mode, ..Settings::default() };
        let mut r = Renderer::new(&ctx, &gs, s.camera.clone(), settings).expect("renderer");
        let stats = common::render_for(&ctx, &mut r, seconds);
        let samples = stats.spp as f64 * 512.0 * 512.0;
        println!(
            "{:<28} {:>6} {:>10} {:>10.1} {:>8.0} {:>10} {:>9.3} {:>9.3}",
            label,
            format!("{mode:?}").to_lowercase(),
            s.triangle_count(),
            bvh_ms,
            bpt,
            stats.spp,
            samples / stats.seconds / 1e6,
            stats.rays as f64 / stats.seconds / 1e6
        );
    }
}
