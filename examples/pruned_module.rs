//! What the driver compiles for a render: the specialised, pruned render module (`render::shader_prune`) of a
//! scene and mode, its size against the module as written, and the functions it keeps — to find code that still
//! reaches the driver without a sample running it.
//!
//! `cargo run --release --example pruned_module -- SCENE [direct|path] [OUT.wgsl]`

use mislab::gpu::GpuContext;
use mislab::render::settings::{Mode, Settings};
use mislab::render::{gpu_scene::GpuScene, scene_data::SceneData, shader_prune, shaders, Renderer};
use mislab::scene::{self, LoadOptions};

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let name = args.get(1).map_or("cornell-box", String::as_str);
    let mode = if args.get(2).is_some_and(|m| m == "direct") { Mode::Direct } else { Mode::Path };
    let scene = scene::load(name, &LoadOptions::default()).unwrap_or_else(|e| panic!("{e}"));
    let ctx = GpuContext::new().unwrap_or_else(|e| panic!("no GPU adapter: {e}"));
    let gs = GpuScene::upload(&ctx, SceneData::build(&scene)).expect("upload");
    let settings = Settings { mode, width: 8, height: 8, ..Settings::default() };
    let r = Renderer::new_unprepared(&ctx, &gs, scene.camera.clone(), settings).expect("renderer");
    let key = r.key();
    let source = shaders::for_device(r.source_for(&key), ctx.device.features()).into_owned();
    let module = shaders::validate(&source).unwrap_or_else(|e| panic!("{e}"));
    let pruned = shader_prune::specialized_wgsl(&module, "render_main", &key.constants()).expect("prunes");
    let functions: Vec<&str> =
        pruned.lines().filter_map(|l| l.strip_prefix("fn ")).map(|l| l.split('(').next().unwrap_or(l)).collect();
    println!(
        "{name} {mode:?}: {} bytes as written, {} pruned; {} of {} functions kept:",
        source.len(),
        pruned.len(),
        functions.len(),
        module.functions.len() + 1
    );
    println!("{}", functions.join(" "));
    if let Some(out) = args.get(3) {
        std::fs::write(out, &pruned).expect("write");
    }
}
