//! Throughput: samples/s and Mrays/s per scene at 512×512 (specialised pipelines), BVH build time and
//! bytes per triangle. `cargo bench --bench throughput` (set MISLAB_BENCH_SECONDS to change the time per
//! configuration; default 10 s). Speed is measured here, never in tests.

use mislab::gpu::GpuContext;
use mislab::gpu_scene::{GpuScene, SceneData};
use mislab::progressive::{self, Budget};
use mislab::render::Renderer;
use mislab::scene::{self, envmap, Environment, LoadOptions};
use mislab::settings::{Mode, Settings};
use std::sync::atomic::AtomicBool;
use std::sync::Arc;
use std::time::Duration;

fn main() {
    let seconds: f64 = std::env::var("MISLAB_BENCH_SECONDS").ok().and_then(|s| s.parse().ok()).unwrap_or(10.0);
    let ctx = GpuContext::new().expect("a Vulkan adapter (apt-get install mesa-vulkan-drivers)");
    println!("device: {} ({:?}); {seconds} s per configuration, 512x512", ctx.info.name, ctx.info.device_type);
    let shared = concat!(env!("CARGO_MANIFEST_DIR"), "/../shared/testdata");
    let helmet = format!("{shared}/gltf/khronos/DamagedHelmet/glTF-Binary/DamagedHelmet.glb");
    let sky = format!("{shared}/env/hdr/noon_grass_1k.hdr");
    let cases: Vec<(&str, String, Mode, bool)> = vec![
        ("veach-mis", "veach-mis".into(), Mode::Direct, false),
        ("veach-mis", "veach-mis".into(), Mode::Path, false),
        ("cornell-box", "cornell-box".into(), Mode::Direct, false),
        ("cornell-box", "cornell-box".into(), Mode::Path, false),
        ("furnace", "furnace".into(), Mode::Path, false),
        ("area-vs-cosine", "area-vs-cosine".into(), Mode::Direct, false),
        ("DamagedHelmet + noon_grass", helmet, Mode::Path, true),
    ];
    println!(
        "{:<28} {:>6} {:>10} {:>10} {:>8} {:>10} {:>9} {:>9}",
        "scene", "mode", "tris", "BVH ms", "B/tri", "spp", "Msamp/s", "Mrays/s"
    );
    for (label, name, mode, env) in cases {
        let mut s = scene::load(&name, &LoadOptions::default()).expect("scene");
        if env {
            let (map, _) = envmap::load_envmap(std::path::Path::new(&sky)).expect("env map");
            s.environment = Environment::Map { map: Arc::new(map), scale: 1.0, rotation: 0.0 };
        }
        let data = SceneData::build(&s);
        let (bvh_ms, bpt) = (data.bvh_seconds * 1e3, data.bvh_bytes() as f64 / s.triangle_count().max(1) as f64);
        let gs = GpuScene::upload(&ctx, data).expect("upload");
        let settings = Settings { mode, ..Settings::default() };
        let mut r = Renderer::new(&ctx, &gs, s.camera.clone(), settings).expect("renderer");
        let stats = progressive::run(
            &ctx,
            &mut r,
            Budget::Time(Duration::from_secs_f64(seconds)),
            &AtomicBool::new(false),
            |_, _| {},
        )
        .expect("render");
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
