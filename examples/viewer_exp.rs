// TEMPORARY experiment (not committed): where does pipeline compile time go on lavapipe?
use mislab::gpu::GpuContext;
use mislab::gpu_scene::{GpuScene, SceneData};
use mislab::render::Renderer;
use mislab::settings::*;
use std::time::Instant;

fn main() {
    let mode = std::env::args().nth(1).unwrap_or_default();
    let ctx = GpuContext::new().unwrap();
    let scene = mislab::scene::load("veach-mis", &Default::default()).unwrap();
    let gs = GpuScene::upload(&ctx, SceneData::build(&scene)).unwrap();
    let src = mislab::render::render_source();
    if mode == "spec" || mode == "generic" {
        let consts: Vec<(&str, f64)> = if mode == "spec" {
            mislab::features::PipelineKey::specialized(mislab::features::Features::of(&gs.data), &Settings::default()).constants()
        } else { vec![] };
        let t = Instant::now();
        let _p = mislab::shaders::compute_pipeline(&ctx.device, "x", &src, "render_main", &consts, None).unwrap();
        eprintln!("{mode}: create {:?}", t.elapsed());
        return;
    }
    if mode == "twodev" {
        // Device B compiles+warms the generic pipeline; device A renders specialised frames meanwhile.
        let ctx_b = GpuContext::from_adapter(ctx.instance.clone(), ctx.adapter.clone()).unwrap();
        let mut a = Renderer::new(&ctx, &gs, scene.camera.clone(), Settings::default()).unwrap();
        let scene2 = scene.clone();
        let t = Instant::now();
        let h = std::thread::spawn(move || {
            let gs_b = GpuScene::upload(&ctx_b, SceneData::build(&scene2)).unwrap();
            let mut b = Renderer::new(&ctx_b, &gs_b, scene2.camera.clone(), Settings { width: 8, height: 8, ..Default::default() }).unwrap();
            let t = Instant::now();
            b.set_specialize(false).unwrap();
            eprintln!("  B: generic create {:?}", t.elapsed());
            let t = Instant::now();
            b.warm_up(&ctx_b).unwrap();
            eprintln!("  B: generic warm-up {:?}", t.elapsed());
        });
        while !h.is_finished() {
            let t1 = Instant::now();
            a.render(&ctx, 1).unwrap();
            eprintln!("  A spec 1spp: {:?}", t1.elapsed());
        }
        h.join().unwrap();
        eprintln!("B done after {:?}", t.elapsed());
        std::thread::sleep(std::time::Duration::from_secs(2));
        let t = Instant::now();
        a.set_specialize(false).unwrap();
        eprintln!("A: generic create {:?}", t.elapsed());
        let t = Instant::now();
        a.warm_up(&ctx).unwrap();
        eprintln!("A: generic warm-up {:?}", t.elapsed());
        return;
    }
}
