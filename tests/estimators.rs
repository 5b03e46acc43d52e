mod common;
use common::*;
use mislab::gpu_scene::{GpuScene, SceneData};
use mislab::render::Renderer;
use mislab::settings::*;
use std::time::Instant;

#[test]
fn scratch_timing() {
    let ctx = gpu();
    for (name, mode) in [("veach-mis", Mode::Direct), ("cornell-box", Mode::Path), ("area-vs-cosine", Mode::Direct)] {
        let sc = scene(name);
        let gs = GpuScene::upload(&ctx, SceneData::build(&sc)).unwrap();
        let base = Settings { mode, max_depth: 4, ..small(32, 32) };
        let t = Instant::now();
        let mut r = Renderer::new(&ctx, &gs, sc.camera.clone(), base.clone()).unwrap();
        eprintln!("{name}: first renderer {:.2}s", t.elapsed().as_secs_f64());
        for s in [Strategy::Uniform, Strategy::Light, Strategy::Mis] {
            let t = Instant::now();
            r.set_settings(Settings { strategy: s, ..base.clone() }).unwrap();
            r.warm_up(&ctx).unwrap();
            let c = t.elapsed().as_secs_f64();
            let t = Instant::now();
            r.render(&ctx, 256).unwrap();
            let d = t.elapsed().as_secs_f64();
            eprintln!("  {s:?}: compile {c:.2}s, 256spp {d:.2}s = {:.2} Msamples/s", 256.0 * 1024.0 / d / 1e6);
        }
        let t = Instant::now();
        r.set_specialize(false).unwrap();
        r.warm_up(&ctx).unwrap();
        let c = t.elapsed().as_secs_f64();
        for s in [Strategy::Uniform, Strategy::Mis] {
            r.set_settings(Settings { strategy: s, ..base.clone() }).unwrap();
            let t = Instant::now();
            r.render(&ctx, 256).unwrap();
            let d = t.elapsed().as_secs_f64();
            eprintln!("  generic {s:?}: compile {c:.2}s, 256spp {d:.2}s = {:.2} Msamples/s", 256.0 * 1024.0 / d / 1e6);
        }
    }
}
